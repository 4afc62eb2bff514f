//! What was run, for the top of REPORT.md: crosscheck's version and git commit, the compiler,
//! the rapier crates' versions, the machine, the date and the run's settings. Only REPORT.md
//! shows it (like the wall times), so `summary.json` stays byte-identical across machines.

use crate::engines::RunSettings;

/// How rapier is built, to be said wherever its time is compared: with its
/// `enhanced-determinism` feature (Cargo.toml), and what that was measured to cost.
pub const RAPIER_BUILD: &str = "rapier is built with its `enhanced-determinism` feature \
     (software libm through simba's `libm_force`, which reaches crosscheck's own nalgebra too; \
     an insertion-ordered map; a fixed wake-up order), which byte-identical reports need and \
     most users do not turn on. Measured once on the seed cases against a build without it \
     (criterion, `BENCHMARKS.md`), it moves `rapier_f64`'s time by −3 % to +3 % and `explicit`'s \
     by −3 % to +1 %, within the benchmark's noise: the time ratios read the same either way.";

/// The lock file the binary was built from (for the rapier crates' versions).
const CARGO_LOCK: &str = include_str!("../../Cargo.lock");

/// What was run, each as one line of text.
#[derive(Debug, Clone, PartialEq)]
pub struct Provenance {
    /// `crosscheck 0.1.0 (commit 1234abcd…)`, with "+ uncommitted changes" outside `report/`.
    pub version: String,
    /// `rustc 1.x.y (…)`.
    pub rustc: String,
    /// `rapier2d 0.36.1, rapier2d-f64 0.36.1, …`.
    pub rapier: String,
    /// CPU model, logical cores, memory, operating system.
    pub machine: String,
    /// UTC date of the run, `YYYY-MM-DD`.
    pub date: String,
    /// The run's setting overrides, or that each case's own settings applied.
    pub settings: String,
}

impl Provenance {
    /// Gather it now, for a run with `settings`.
    pub fn gather(settings: &RunSettings) -> Provenance {
        Provenance {
            version: format!(
                "crosscheck {} ({})",
                env!("CARGO_PKG_VERSION"),
                env!("CROSSCHECK_COMMIT")
            ),
            rustc: env!("CROSSCHECK_RUSTC").to_string(),
            rapier: if cfg!(feature = "rapier") {
                rapier_versions()
            } else {
                "rapier not built (cargo feature `rapier` off)".into()
            },
            machine: machine(),
            date: utc_date(),
            settings: if *settings == RunSettings::default() {
                "each case's own settings (no overrides)".into()
            } else {
                format!("overrides {settings:?}")
            },
        }
    }
}

/// Whether this build has the rapier release `version` (Cargo.lock lists the older ones
/// whether or not the `rapier-versions` feature is on).
#[cfg(feature = "rapier")]
fn built(version: &str) -> bool {
    crate::engines::rapier::Release::all()
        .iter()
        .any(|r| r.version() == version)
}

#[cfg(not(feature = "rapier"))]
fn built(_: &str) -> bool {
    false
}

fn rapier_versions() -> String {
    let mut found = Vec::new();
    let mut lines = CARGO_LOCK.lines();
    while let Some(line) = lines.next() {
        if let Some(name) = line
            .strip_prefix("name = \"")
            .and_then(|s| s.strip_suffix('"'))
            && name.starts_with("rapier")
            && let Some(v) = lines.next().and_then(|l| {
                l.strip_prefix("version = \"")
                    .and_then(|s| s.strip_suffix('"'))
            })
            && built(v)
        {
            found.push(format!("{name} {v}"));
        }
    }
    found.join(", ")
}

fn machine() -> String {
    let read = |p| std::fs::read_to_string(p).unwrap_or_default();
    let cpu = read("/proc/cpuinfo")
        .lines()
        .find_map(|l| {
            l.strip_prefix("model name")
                .map(|s| s.trim_start_matches([' ', '\t', ':']).to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let memory = read("/proc/meminfo")
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:").map(|s| s.trim().to_string()))
        .and_then(|s| s.trim_end_matches(" kB").parse::<f64>().ok())
        .map_or("unknown memory".into(), |kb| {
            format!("{:.0} GiB", kb / (1024.0 * 1024.0))
        });
    let os = read("/etc/os-release")
        .lines()
        .find_map(|l| {
            l.strip_prefix("PRETTY_NAME=")
                .map(|s| s.trim_matches('"').to_string())
        })
        .unwrap_or_else(|| std::env::consts::OS.into());
    format!("{cpu}, {cores} logical cores, {memory}, {os}")
}

/// Today's UTC date from the system clock (days since 1970 to the civil calendar).
fn utc_date() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}
