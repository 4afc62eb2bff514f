//! A run writes summary.json and REPORT.md whose numbers agree with each other and with the
//! CSVs they were computed from.
mod common;

use crosscheck::case;
use crosscheck::comparison;
use crosscheck::comparison::summary::Summary;
use crosscheck::comparison::verdict::cost::Reached;
use crosscheck::report::data::read_history;
use crosscheck::report::format::sci;
use std::process::Command;

/// Every page of the report under `out`: (its directory, its text): the question pages and
/// each case's, then `REPORT.md` last.
fn pages(out: &std::path::Path) -> Vec<(std::path::PathBuf, String)> {
    let read = |p: std::path::PathBuf| std::fs::read_to_string(&p).unwrap();
    let mut cases: Vec<std::path::PathBuf> = std::fs::read_dir(out.join("cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    cases.sort();
    let mut all: Vec<(std::path::PathBuf, String)> = ["accuracy.md", "cost.md", "stability.md"]
        .iter()
        .map(|p| (out.to_path_buf(), read(out.join(p))))
        .collect();
    all.extend(cases.into_iter().map(|p| (out.join("cases"), read(p))));
    all.push((out.to_path_buf(), read(out.join("REPORT.md"))));
    all
}

/// Run every case, with the sweep, into a temporary directory (once per test binary): the
/// directory, its summary and its pages, one after the other (`REPORT.md` last).
fn run_into_temporary_directory() -> &'static (tempfile::TempDir, Summary, String) {
    static RUN: std::sync::OnceLock<(tempfile::TempDir, Summary, String)> =
        std::sync::OnceLock::new();
    RUN.get_or_init(|| {
        let out = tempfile::tempdir().unwrap();
        let status = Command::new(env!("CARGO_BIN_EXE_crosscheck"))
            .args([
                "run",
                "--quiet",
                "--sweep",
                "--stability",
                "--on-request",
                "--repeat",
                "1",
                "--out",
            ])
            .arg(out.path())
            .stdout(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(status.success());
        let summary: Summary = serde_json::from_str(
            &std::fs::read_to_string(out.path().join("summary.json")).unwrap(),
        )
        .unwrap();
        let report: String = pages(out.path()).into_iter().map(|p| p.1).collect();
        (out, summary, report)
    })
}

/// The sweep's orders and floors are on each run entry of summary.json and in REPORT.md's
/// overview, the same numbers; each swept case has its CSV and its work–precision figure.
#[test]
fn sweep_orders_and_floors_are_in_the_summary_and_the_report() {
    let (out, summary, report) = run_into_temporary_directory();
    let mut checked = 0;
    // The sweep covers the seed cases and the cases that ask for it (`sweep = true`).
    let swept = |id: &str| {
        let seed = !["stress_", "contact_", "friction_"]
            .iter()
            .any(|p| id.starts_with(p));
        seed || case::load(&case::resolve(id, &case::cases_dir()).unwrap())
            .unwrap()
            .sweep
    };
    let mut friction_swept = 0;
    for c in summary.cases.iter().filter(|c| swept(&c.id)) {
        friction_swept += usize::from(c.id.starts_with("friction_"));
        let sweep = std::fs::read_to_string(out.path().join("sweep.csv")).unwrap();
        assert!(
            sweep.lines().any(|l| l.starts_with(&format!("{},", c.id))),
            "{}: no sweep rows",
            c.id
        );
        assert!(
            out.path()
                .join("figures")
                .join(format!("{}.work-precision.svg", c.id))
                .is_file()
        );
        let start = report.find("## What accuracy costs").expect("the section");
        let end = start + report[start..].find("**CPU seconds per simulated").unwrap();
        let row = report[start..end]
            .lines()
            .find(|l| l.starts_with(&format!("| {} | ", c.id)))
            .unwrap_or_else(|| panic!("{}: no order row in REPORT.md", c.id));
        for engine in common::STEPPING {
            let r = c.runs.iter().find(|r| r.engine == engine).unwrap();
            if let Some(p) = r.observed_order {
                let fit = r.order_fit.as_ref().unwrap();
                assert_eq!(fit.value, p);
                assert!(fit.points >= 2 && fit.finest < fit.coarsest, "{fit:?}");
                assert!(
                    row.contains(&format!("{p:.2}")),
                    "{}: {engine} {p:.2} in {row}",
                    c.id
                );
                checked += 1;
            }
            if let Some(f) = &r.floor {
                assert!(f.value > 0.0 && !f.cause.is_empty());
                assert!(
                    row.contains(&sci(f.value)),
                    "{}: {engine} floor in {row}",
                    c.id
                );
            }
        }
    }
    // Every engine has an order but, on the four pinned cases, rapier's defaults (their errors
    // never leave the pre-asymptotic range within the budget) and rapier_f32 (f32 round-off
    // stalls it after two points): 13 × 6 − 12 (13 × 2 without rapier).
    assert_eq!(friction_swept, 2, "two friction cases are swept");
    let unordered = if cfg!(feature = "rapier") { 12 } else { 0 };
    assert!(
        checked >= 13 * common::STEPPING.len() - unordered,
        "{checked} orders"
    );
}

/// Every history and budget the whole suite writes: a CSV per case and engine, and a budget
/// CSV per case and studied stepping engine (all but the closed form and the reference, and
/// rapier's older releases). Of the 47 cases, 10 of the stress family (contact that opens and
/// closes from t = 0) have no closed form, so neither its CSV nor budgets (a budget splits the
/// error against the closed form), and on one of them (two balls, one free to turn)
/// `explicit_small` does not apply; rapier refuses the ramp case (μ_s > μ_k): each of its
/// engines writes no CSV there, and the stepping ones no budget; `explicit_small`
/// refuses the two roll cases (a body's ball on a face, whose contact point moves over the
/// body): it writes neither a CSV nor a budget there.
#[test]
fn every_history_and_budget_of_the_suite_is_written() {
    let (out, ..) = run_into_temporary_directory();
    let written = common::snapshot(&out.path().join("data"))
        .keys()
        .filter(|k| k.ends_with(".csv"))
        .count();
    let engines = crosscheck::run::registry::all();
    let stepping = engines.iter().filter(|e| e.stepping().is_some()).count();
    let is_rapier = |name: &str| name.starts_with("rapier");
    let rapier = engines.iter().filter(|e| is_rapier(e.name())).count();
    let rapier_stepping = engines
        .iter()
        .filter(|e| is_rapier(e.name()) && e.stepping().is_some())
        .count();
    let (without_closed_form, small_refused, rolling_refused) = (10, 1, 2);
    assert_eq!(
        written,
        47 * engines.len() - without_closed_form - small_refused - rapier - rolling_refused
            + (47 - without_closed_form) * stepping
            - rapier_stepping
            - rolling_refused
    );
}

#[test]
fn summary_and_report_agree() {
    let (out, summary, report) = run_into_temporary_directory();
    // The 13 seed cases, the 22 of the stress family (11 of them contact that opens and
    // closes) and the 12 of the friction family.
    assert_eq!(summary.cases.len(), 47);

    for c in &summary.cases {
        let scene = case::load(&case::resolve(&c.id, &case::cases_dir()).unwrap()).unwrap();
        let csv = |engine: &str| {
            read_history(
                &out.path()
                    .join("data")
                    .join(&c.id)
                    .join(format!("{}.csv", crosscheck::contract::file_stem(engine))),
            )
            .unwrap()
        };
        if c.runs
            .iter()
            .any(|r| r.engine == "analytic" && r.error.is_some())
        {
            // No closed form (contact that opens and closes): nothing is measured against it.
            assert!(
                c.runs.iter().all(|r| r.against_analytic.is_none()),
                "{}",
                c.id
            );
            continue;
        }
        let closed_form = csv("analytic");
        for r in &c.runs {
            let Some(a) = &r.against_analytic else {
                continue;
            };
            // The metrics recomputed from the CSVs on disk are the summary's, bit for bit
            // (the CSVs store shortest round-trip decimals): against the closed form, and
            // against the engine's own baseline, which is the one `comparison::baseline`
            // names (every engine's baseline ran here).
            let h = csv(&r.engine);
            assert_eq!(
                &comparison::compare(&scene, &closed_form, &h),
                a,
                "{} {}",
                c.id,
                r.engine
            );
            let baseline = r.baseline.as_deref().unwrap();
            assert_eq!(Some(baseline), comparison::baseline(&r.engine));
            let judged = r.against_baseline.as_ref().unwrap();
            assert_eq!(
                &comparison::compare(&scene, &csv(baseline), &h),
                judged,
                "{} {}",
                c.id,
                r.engine
            );
            // REPORT.md's accuracy row shows the same worst error, increment and steps.
            let Some(worst) = judged.worst_max else {
                continue;
            };
            // An exact solution's row shows the model-form gap as such.
            let model_form = if comparison::EXACT_SOLUTIONS.contains(&r.engine.as_str()) {
                "model form "
            } else {
                ""
            };
            let prefix = format!(
                "| {} | {} | {baseline} | {model_form}{} (",
                c.id,
                r.engine,
                sci(worst)
            );
            let row = report
                .lines()
                .find(|l| l.starts_with(&prefix))
                .unwrap_or_else(|| panic!("no report row starting {prefix}"));
            if let Some(total) = a.worst_max {
                assert!(row.contains(&format!("| {} |", sci(total))), "{row}");
            }
            if r.increment.unwrap() > 0.0 {
                assert!(row.contains(&sci(r.increment.unwrap())), "{row}");
                assert!(row.contains(&format!("| {} |", r.steps.unwrap())), "{row}");
            }
        }
        if let Some(m) = &c.contact {
            assert!(
                report.contains(&format!("starts at {}", sci(m.initial_force))),
                "{}",
                c.id
            );
        }
    }
    // Every judged cell has a tolerance: 47 cases × 6 judged engines (every engine but the two
    // exact solutions), less the 11 cells with nothing to compare: `explicit_small` does not
    // apply to contact_balls_oblique, has no closed form on the other 9 cases whose contact
    // strikes (5 drops, the tetrahedron, the wedge, the rattle, the ball slide) and is compared
    // over no rows on contact_reopen (its closed form is valid at no row); and the rapier
    // engines refuse friction_ramp_breakaway (μ_s > μ_k), `explicit_small` the two roll cases.
    let checks = summary.tolerance_checks();
    let rapier = common::STEPPING
        .iter()
        .filter(|e| e.starts_with("rapier"))
        .count();
    assert_eq!(checks.len(), 47 * common::STEPPING.len() - 11 - rapier - 2);
    assert!(checks.iter().all(|c| c.tolerance.is_some()));
    assert!(report.contains(&format!(
        "**{} of {} cells meet their tolerance.**",
        checks.iter().filter(|c| c.met()).count(),
        checks.len()
    )));
}

/// REPORT.md opens with the verdict matrix: every cell equals the summary's figure for that
/// case and engine (✓/✗ from `meets_tolerance`, the number from `against_baseline`); every
/// link of the report resolves to a file of the run, and every figure is an SVG document.
#[test]
fn verdict_matrix_equals_the_summary_and_every_link_resolves() {
    let (out, summary, report) = run_into_temporary_directory();
    let matrix = report
        .split("### Every cell")
        .nth(1)
        .expect("a verdict matrix")
        .split("\n### ")
        .next()
        .unwrap();
    let mut lines = matrix.lines().filter(|l| l.starts_with('|'));
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split('|')
        .map(|s| s.trim().trim_matches('`').to_string())
        .collect();
    let mut cells = 0;
    for line in lines.skip(1) {
        let row: Vec<&str> = line.split('|').map(str::trim).collect();
        let case = summary.cases.iter().find(|c| c.id == row[1]).unwrap();
        for (k, engine) in header.iter().enumerate().skip(2) {
            if engine.is_empty() {
                continue;
            }
            let run = case.runs.iter().find(|r| &r.engine == engine).unwrap();
            if let Some(error) = &run.error {
                // The closed form does not apply to contact that opens and closes.
                assert_eq!(
                    run.status,
                    crosscheck::run::Status::NotApplicable,
                    "{error}"
                );
                assert_eq!(row[k], "n/a", "{} / {engine}", case.id);
                cells += 1;
                continue;
            }
            let Some(judged) = &run.against_baseline else {
                // Judged against nothing: the reference where the closed form does not apply.
                assert_eq!(row[k], "–", "{} / {engine}", case.id);
                cells += 1;
                continue;
            };
            let Some(worst) = judged.worst_max else {
                assert_eq!(judged.rows, 0, "{} / {engine}", case.id);
                assert_eq!(row[k], "no rows compared", "{} / {engine}", case.id);
                cells += 1;
                continue;
            };
            let figure = sci(worst);
            let expected = match run.meets_tolerance {
                Some(true) => format!("✓ {figure}"),
                Some(false) => format!("✗ {figure}"),
                None => format!("{figure} (no tolerance)"),
            };
            assert_eq!(row[k], expected, "{} / {engine}", case.id);
            cells += 1;
        }
    }
    assert_eq!(
        cells,
        47 * common::STEPPING.len(),
        "every case × engine but the two exact solutions"
    );
    let mut links = 0;
    for (dir, page) in pages(out.path()) {
        for piece in page.split("](").skip(1) {
            let link = piece.split(')').next().unwrap();
            let (target, anchor) = link.split_once('#').unwrap_or((link, ""));
            if !anchor.is_empty() {
                // An anchor: a heading of the page it names (this one where none) whose slug
                // (GitHub's: lower case, spaces to hyphens) it is.
                let text = if target.is_empty() {
                    page.clone()
                } else {
                    std::fs::read_to_string(dir.join(target)).unwrap()
                };
                let slug = |h: &str| h.trim().to_lowercase().replace(' ', "-");
                assert!(
                    text.lines()
                        .filter_map(|l| l.strip_prefix('#'))
                        .any(|h| slug(h.trim_start_matches('#')) == anchor),
                    "anchor {link} in {dir:?}"
                );
                links += 1;
                if target.is_empty() {
                    continue;
                }
            }
            assert!(dir.join(target).is_file(), "link {target} from {dir:?}");
            links += 1;
            if target.ends_with(".svg") {
                let svg = std::fs::read_to_string(dir.join(target)).unwrap();
                assert!(
                    svg.contains("<svg") && svg.trim_end().ends_with("</svg>"),
                    "{target} is not an SVG document"
                );
            }
        }
    }
    assert!(links >= 13, "one figure per case at least, found {links}");
}

/// The equivalence checks find exactly the problems the spec builds twice (grounded A = B = C,
/// node-to-node B = C, each 3D rigid case = its 2D twin, pinned lumped = pinned surface), and on
/// each our engines and the references give one answer: within 1e-7 of the peak, which bounds
/// round-off (1e-16 per operation over 1e4 increments, amplified in the contact force by the
/// penalty stiffness: measured ≤ 8.7e-9). REPORT.md prints the summary's numbers.
#[test]
fn equivalent_cases_are_found_and_agree() {
    let (_out, summary, report) = run_into_temporary_directory();
    let mut found: Vec<(&str, &str)> = summary
        .equivalences
        .iter()
        .map(|e| (e.case.as_str(), e.same_as.as_str()))
        .collect();
    found.sort();
    let mut expected = vec![
        ("rigid2d_pin_surface", "rigid2d_pin_lumped"),
        ("rigid3d_pin_lumped", "rigid2d_pin_lumped"),
        ("rigid3d_pin_surface", "rigid2d_pin_lumped"),
        ("rigid3d_slide_lumped", "rigid2d_slide_lumped"),
        ("rigid3d_slide_surface", "rigid2d_slide_surface"),
        ("springs_grounded_b", "springs_grounded_a"),
        ("springs_grounded_c", "springs_grounded_a"),
        ("springs_n2n_c", "springs_n2n_b"),
        // The 3D slide-stop along x is the 2D one (a constant contact force, which every
        // friction case under its weight shares, makes no equivalence).
        ("friction_slide_stop_3d", "friction_slide_stop_2d"),
    ];
    expected.sort();
    assert_eq!(found, expected);
    for e in &summary.equivalences {
        for engine in ["analytic", "reference", "explicit", "explicit_small"] {
            let d = e.differences[engine];
            println!("{} = {} ({engine}): {d:.2e}", e.case, e.same_as);
            assert!(
                d <= 1e-7,
                "{} = {}: {engine} differs by {d:e}",
                e.case,
                e.same_as
            );
        }
        let row = report
            .lines()
            .find(|l| l.starts_with(&format!("| {} = {} |", e.case, e.same_as)))
            .unwrap_or_else(|| panic!("no equivalence row for {} = {}", e.case, e.same_as));
        for d in e.differences.values() {
            assert!(row.contains(&sci(*d)), "{row} lacks {}", sci(*d));
        }
    }
}

/// The stability map is in REPORT.md, one table row per engine whose counts are those of its
/// CSV, each engine is also run at its own step, and the explicit engine's edge is at the
/// stable increment on every case without contact that opens and closes: unstable at every
/// ratio above 1, never below. It maps the 44 cases with a stable increment (not the free
/// spins).
#[test]
fn the_stability_map_is_in_the_report_and_matches_its_csvs() {
    let (out, _, report) = run_into_temporary_directory();
    assert!(report.contains("# Where each engine stays stable"));
    // The stability page's own engine rows (other pages have rows that start with an engine).
    let report = std::fs::read_to_string(out.path().join("stability.md")).unwrap();
    let mut reader = csv::Reader::from_path(out.path().join("stability.csv")).unwrap();
    let records: Vec<Vec<String>> = reader
        .records()
        .map(|r| r.unwrap().iter().map(String::from).collect())
        .collect();
    for engine in common::STEPPING {
        // case, engine, search, ratio, increment_s, continued, outcome, …
        let of = |search: &str| -> Vec<&Vec<String>> {
            records
                .iter()
                .filter(|r| r[1] == engine && r[2] == search)
                .collect()
        };
        let (grid, own) = (of("grid"), of("own step"));
        assert_eq!(
            grid.len(),
            44 * crosscheck::comparison::stability::RATIOS.len()
        );
        // Its own step wherever its job ran (not where it does not apply).
        let mut applies: Vec<&str> = grid
            .iter()
            .filter(|r| r[6] != "not applicable")
            .map(|r| r[0].as_str())
            .collect();
        applies.dedup();
        assert_eq!(own.len(), applies.len(), "{engine}");
        let line = report
            .lines()
            .find(|l| l.starts_with(&format!("| `{engine}` |")))
            .unwrap_or_else(|| panic!("{engine}: no table row"));
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        assert_eq!(cells[2], applies.len().to_string(), "{line}");
        let accurate = own.iter().filter(|r| r[6] == "accurate").count();
        let judged = own
            .iter()
            .filter(|r| r[6] == "accurate" || r[6] == "inaccurate")
            .count();
        assert_eq!(cells[3], format!("{accurate} of {judged}"), "{line}");
        if engine.starts_with("explicit") {
            // Contact that opens and closes, and friction's pairs pressed by a weight, can stay
            // bounded past 1×: their penalty mode exists only while the pair is closed.
            let unilateral = |id: &str| id.starts_with("contact_") || id.starts_with("friction_");
            for r in grid.iter().filter(|r| !unilateral(&r[0])) {
                let ratio: f64 = r[3].parse().unwrap();
                assert_eq!(r[6] == "unstable", ratio > 1.0, "{engine}: {r:?}");
            }
        }
    }
}

/// Accuracy on request: the CSV has its header and a row per seed case, engine and tolerance;
/// every request lands in the band [ε/10, ε] against its own model's exact solution, and the
/// report's row for its case shows that error and its ratio to ε.
#[test]
fn accuracy_on_request_is_in_the_report_and_in_band() {
    use crosscheck::report::on_request::{COLUMNS, read};
    use crosscheck::run::on_request::TOLERANCES;
    let (out, _, report) = run_into_temporary_directory();
    assert!(report.contains("## Accuracy on request"));
    let text = std::fs::read_to_string(out.path().join("on_request.csv")).unwrap();
    assert_eq!(text.lines().next(), Some(COLUMNS.join(",").as_str()));
    let requests = read(out.path());
    assert_eq!(
        requests.len(),
        13 * common::ON_REQUEST.len() * TOLERANCES.len()
    );
    for r in &requests {
        let a = r.achieved.unwrap_or_else(|| {
            panic!(
                "{} / {} at {:e}: {:?}",
                r.case, r.engine, r.requested, r.message
            )
        });
        assert!(a <= r.requested && a >= r.requested / 10.0, "{r:?}");
        let cell = format!("{a:.2e} ({:.2})", a / r.requested);
        assert!(
            report
                .lines()
                .any(|l| l.starts_with(&format!("| {} |", r.case)) && l.contains(&cell)),
            "{r:?}: no row shows {cell}"
        );
    }
}

/// The contact section: its restitution table equals the summary's rebounds, the reference's
/// are e² to the table's four digits, and the explicit engine's within 0.02 of them.
#[test]
fn the_contact_section_shows_the_summarys_rebounds() {
    let (_, summary, report) = run_into_temporary_directory();
    assert!(report.contains("## Contact that opens and closes"));
    let mut rows = 0;
    for c in summary
        .cases
        .iter()
        .filter(|c| c.id.starts_with("contact_drop_"))
    {
        let line = report
            .lines()
            .skip_while(|l| !l.starts_with("| case | e | e² |"))
            .find(|l| l.starts_with(&format!("| {} | ", c.id)))
            .unwrap_or_else(|| panic!("{}: no restitution row", c.id));
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let e: f64 = cells[2].parse().unwrap();
        assert_eq!(cells[3], format!("{:.4}", e * e));
        let rebound = |engine: &str| {
            c.runs
                .iter()
                .find(|r| r.engine == engine)
                .and_then(|r| r.impacts.as_ref()?.rebound)
                .unwrap()
        };
        assert_eq!(cells[4], format!("{:.4}", rebound("reference")));
        assert!((rebound("reference") - e * e).abs() < 1e-4, "{}", c.id);
        assert!((rebound("explicit") - e * e).abs() < 0.02, "{}", c.id);
        rows += 1;
    }
    assert_eq!(rows, 5);
    // The impact table's deepest penetration on the elastic drop: the reference never goes in
    // (round-off); explicit's undamped penalty oscillation reaches A = mg/k_p +
    // √((mg/k_p)² + (v/ω_p)²), which rows Δ = 5e-4 s apart see to within cos(ω_p Δ/2) of it.
    let drop = summary
        .cases
        .iter()
        .find(|c| c.id == "contact_drop_e1")
        .unwrap();
    let deepest = |engine: &str| {
        drop.runs
            .iter()
            .find(|r| r.engine == engine)
            .and_then(|r| r.impacts.as_ref()?.penetration)
            .unwrap()
    };
    assert!(deepest("reference") < 1e-12);
    let (g, kp) = (9.81_f64, 1e7_f64);
    let (offset, wp) = (g / kp, kp.sqrt());
    let a = offset + (offset * offset + 2.0 * g / kp).sqrt();
    let explicit = deepest("explicit");
    assert!(
        explicit <= a * 1.001 && explicit >= a * (wp * 2.5e-4).cos(),
        "{explicit:e} vs {a:e}"
    );
    let line = report
        .lines()
        .skip_while(|l| !l.starts_with("| case | engine | impacts |"))
        .find(|l| l.starts_with("| contact_drop_e1 | explicit | "))
        .unwrap();
    assert!(line.ends_with(&format!("| {:.2e} |", explicit)), "{line}");
}

/// The first screen answers the user's three questions before its index, read at a glance: at
/// most 60 lines, no paragraph (nor list item) over 400 characters, with the summary's
/// numbers: tolerances met per engine, how each cost to 1e-4 was found, and each engine's
/// lowest critical ratio and its runs at its own step as `stability.csv` has them.
#[test]
fn the_first_screen_answers_the_three_questions_as_the_csvs_do() {
    use crosscheck::report::first_screen::{MAX_LINES, MAX_PARAGRAPH};
    let (out, summary, _) = run_into_temporary_directory();
    let text = std::fs::read_to_string(out.path().join("REPORT.md")).unwrap();
    let first: Vec<&str> = text.lines().take_while(|l| *l != "## In full").collect();
    assert!(first.len() <= MAX_LINES, "{} lines", first.len());
    for block in first.join("\n").split("\n\n") {
        let lines: Vec<&str> = block.lines().collect();
        let table_or_list = lines
            .iter()
            .all(|l| l.starts_with('|') || l.starts_with("- "));
        let longest = if table_or_list && !lines[0].starts_with('|') {
            lines.iter().map(|l| l.chars().count()).max().unwrap_or(0)
        } else if table_or_list {
            0
        } else {
            block.chars().count()
        };
        assert!(longest <= MAX_PARAGRAPH, "{longest} characters: {block}");
    }
    let cells =
        |line: &str| -> Vec<String> { line.split('|').map(|c| c.trim().to_string()).collect() };
    let row_of = |e: &str, after: &str| -> Vec<String> {
        let start = first.iter().position(|l| l.starts_with(after)).unwrap();
        cells(
            first[start..]
                .iter()
                .find(|l| l.starts_with(&format!("| `{e}` |")))
                .unwrap_or_else(|| panic!("{e}: no row after {after}")),
        )
    };
    // How close: tolerances met, as the summary counts them.
    let checks = summary.tolerance_checks();
    for e in common::STEPPING {
        let mine: Vec<_> = checks.iter().filter(|c| c.engine == e).collect();
        let met = mine.iter().filter(|c| c.met()).count();
        assert_eq!(
            row_of(e, "**How close?**")[2],
            format!("{met} of {}", mine.len())
        );
    }
    // What it costs: how each engine's cost to 1e-4 was found, over the problems swept (a
    // case equivalent to another left out).
    let problems: Vec<_> = summary
        .cases
        .iter()
        .filter(|c| c.runs.iter().any(|r| !r.cost_to_accuracy.is_empty()))
        .filter(|c| !summary.equivalences.iter().any(|q| q.case == c.id))
        .collect();
    let reached = |e: &str, how: Reached| {
        problems
            .iter()
            .filter(|c| {
                let cost = |name: &str| {
                    c.runs
                        .iter()
                        .find(|r| r.engine == name)?
                        .cost_to_accuracy
                        .iter()
                        .find(|k| k.target == 1e-4)
                };
                cost(e).is_some_and(|k| k.reached == how && k.cpu_s_per_simulated_s.is_some())
                    && cost("explicit").is_some_and(|k| k.cpu_s_per_simulated_s.is_some())
            })
            .count()
    };
    for e in common::STEPPING.iter().filter(|e| **e != "explicit") {
        let counted = format!(
            "{} / {} / {}",
            reached(e, Reached::Measured),
            reached(e, Reached::Extrapolated),
            reached(e, Reached::AtLeast)
        );
        assert_eq!(row_of(e, "**At what cost?**")[5], counted, "{e}");
    }
    // Stable: the lowest bisected critical ratio and the runs at the engine's own step, as
    // stability.csv has them.
    let mut reader = csv::Reader::from_path(out.path().join("stability.csv")).unwrap();
    let map: Vec<Vec<String>> = reader
        .records()
        .map(|r| r.unwrap().iter().map(String::from).collect())
        .collect();
    for e in common::STEPPING {
        let mine: Vec<&Vec<String>> = map.iter().filter(|r| r[1] == e).collect();
        let own: Vec<&&Vec<String>> = mine.iter().filter(|r| r[2] == "own step").collect();
        let bounded = own
            .iter()
            .filter(|r| ["accurate", "inaccurate", "bounded"].contains(&r[6].as_str()))
            .count();
        let row = row_of(e, "**Stable?**");
        assert_eq!(row[3], format!("{bounded} of {}", own.len()), "{e}");
        // A pair whose map runs stopped with an error has no critical increment: it is named
        // under the table with the lowest ratio at which one did.
        let mut failed: Vec<(&str, f64)> = mine
            .iter()
            .filter(|r| r[6] == "failed")
            .map(|r| (r[0].as_str(), r[3].parse::<f64>().unwrap()))
            .collect();
        failed.sort_by(|a, b| a.0.cmp(b.0).then(a.1.total_cmp(&b.1)));
        failed.dedup_by(|a, b| a.0 == b.0);
        for (case, ratio) in failed {
            let line =
                format!("- `{e}` on {case}: a map run stopped with an error from {ratio:.2}×");
            assert!(first.iter().any(|l| l.starts_with(&line)), "{line}");
        }
        let lowest = mine
            .iter()
            .filter(|r| r[14] == "bisected" || r[14] == "below")
            .map(|r| r[13].parse::<f64>().unwrap())
            .reduce(f64::min);
        let printed = lowest.map_or("–".to_string(), |x| format!("{x:.2}"));
        assert_eq!(row[4], printed, "{e}");
    }
    // results.csv: the worst relative error per case and engine is the summary's verdict.
    let mut reader = csv::Reader::from_path(out.path().join("results.csv")).unwrap();
    let rows: Vec<Vec<String>> = reader
        .records()
        .map(|r| r.unwrap().iter().map(String::from).collect())
        .collect();
    for check in checks.iter().filter(|c| c.measured.is_some()) {
        let worst = rows
            .iter()
            .filter(|r| r[0] == check.case && r[1] == check.engine && r[6] == "true")
            .map(|r| r[5].parse::<f64>().unwrap())
            .fold(0.0f64, f64::max);
        assert_eq!(
            Some(worst),
            check.measured,
            "{} / {}",
            check.case,
            check.engine
        );
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        v["schema_version"],
        crosscheck::comparison::summary::SCHEMA_VERSION
    );
}

/// The friction section's same-answer table: the 3D slide launched at 0°, 30° and 45° share
/// one exact stop, so they form one table whose every engine row gives that engine's end on
/// each case as the summary has it, and whose `reference` row spreads by its integrator's
/// tolerance only (1e-12 of the 0.41 m stop, with room: measured 1e-14).
#[test]
fn the_friction_sections_same_answer_table_reads_the_summary() {
    let (out, summary, _) = run_into_temporary_directory();
    let accuracy = std::fs::read_to_string(out.path().join("accuracy.md")).unwrap();
    let start = accuracy.find("The same exact answer, ").expect("the table");
    let ids = [
        "friction_isotropy_30",
        "friction_isotropy_45",
        "friction_slide_stop_3d",
    ];
    assert!(accuracy[start..].starts_with(&format!("The same exact answer, {}", ids.join(", "))));
    let rows: Vec<&str> = accuracy[start..]
        .lines()
        .skip_while(|l| !l.starts_with("| engine |"))
        .skip(2)
        .take_while(|l| l.starts_with("| `"))
        .collect();
    assert!(rows.len() >= 3, "{rows:?}");
    for row in rows {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let engine = cells[1].trim_matches('`');
        for (k, id) in ids.iter().enumerate() {
            let c = summary.cases.iter().find(|c| c.id == *id).unwrap();
            let r = c.runs.iter().find(|r| r.engine == engine).unwrap();
            let end = r.friction.as_ref().unwrap().engine.end;
            assert_eq!(cells[2 + k], format!("{end:.9}"), "{engine} on {id}");
        }
        if engine == "reference" {
            let spread: f64 = cells[5].parse().unwrap();
            assert!(spread < 1e-12 * 0.41, "reference spreads {spread:e}");
        }
    }
}
