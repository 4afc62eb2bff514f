//! Records what the binary is, for the report's "what was run" line, when it is built (an
//! installed binary reports itself, wherever it runs): the compiler's version and the git
//! commit of the source, with "+ uncommitted changes" where tracked files outside `report/`
//! differ from it.
use std::process::Command;

fn output(program: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(program).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// `commit 1234abcd5678`, with "+ uncommitted changes"; or that it is unknown (no git, or not
/// a checkout).
fn commit() -> String {
    let Some(hash) = output("git", &["rev-parse", "--short=12", "HEAD"]) else {
        return "git commit unknown".into();
    };
    let status = output(
        "git",
        &[
            "status",
            "--porcelain",
            "--untracked-files=no",
            "--",
            ".",
            ":!report",
        ],
    );
    if status.is_some_and(|s| !s.is_empty()) {
        format!("commit {hash} + uncommitted changes")
    } else {
        format!("commit {hash}")
    }
}

/// `$OUT_DIR/embedded_cases.rs`: the shipped case files (`cases/*.toml` and those of its
/// families, `cases/stress/*.toml` and `cases/friction/*.toml`)
/// as `(path under cases/, text)`, sorted, for the binary to use where no case directory is
/// given or found.
fn embed_cases() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let mut files = Vec::new();
    let folders = [
        ("", root.clone()),
        ("stress/", root.join("stress")),
        ("friction/", root.join("friction")),
    ];
    for (sub, dir) in folders {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.extension().is_some_and(|x| x == "toml") && path.is_file() {
                let name = path.file_name().unwrap().to_string_lossy().into_owned();
                files.push((format!("{sub}{name}"), path));
            }
        }
    }
    files.sort();
    let mut code = String::from("/// The shipped case files: (path under `cases/`, text).\n");
    code.push_str("pub const FILES: &[(&str, &str)] = &[\n");
    for (name, path) in &files {
        code.push_str(&format!(
            "    ({name:?}, include_str!({:?})),\n",
            path.display().to_string()
        ));
    }
    code.push_str("];\n");
    let out = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("embedded_cases.rs");
    std::fs::write(out, code).expect("write embedded_cases.rs");
    println!("cargo:rerun-if-changed=cases");
    println!("cargo:rerun-if-changed=cases/stress");
    println!("cargo:rerun-if-changed=cases/friction");
}

fn main() {
    embed_cases();
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = output(&rustc, &["--version"]).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=CROSSCHECK_RUSTC={version}");
    println!("cargo:rustc-env=CROSSCHECK_COMMIT={}", commit());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=RUSTC");
    // A new commit moves HEAD or the branch it names; staging changes the index; the tracked
    // sources change the answer to "uncommitted changes".
    for path in ["HEAD", "index", "packed-refs"] {
        if let Some(p) = output("git", &["rev-parse", "--git-path", path]) {
            println!("cargo:rerun-if-changed={p}");
        }
    }
    if let Some(branch) = output("git", &["symbolic-ref", "-q", "HEAD"])
        && let Some(p) = output("git", &["rev-parse", "--git-path", &branch])
    {
        println!("cargo:rerun-if-changed={p}");
    }
    for tracked in [
        "src",
        "cases",
        "tests",
        "benches",
        "examples",
        "Cargo.toml",
        "Cargo.lock",
    ] {
        println!("cargo:rerun-if-changed={tracked}");
    }
}
