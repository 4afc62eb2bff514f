//! The module layout shows the data flow, and the imports follow it: engines never know each
//! other, the scene knows no file format, the run writes nothing and knows no comparison, the
//! comparison reaches engines only through the run (the `Engine` trait it re-exports). The README's architecture diagram names files that exist and every module there is.
use std::fs;
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// Every line of every file under `dir` that contains `needle`, as `path:line: text`; a file's
/// unit tests (from a top-level `#[cfg(test)]` to its end) are not part of the library the flow
/// describes, and may build their fixture from a case file.
fn mentions(dir: &str, needle: &str) -> Vec<String> {
    rust_files(Path::new(dir))
        .iter()
        .flat_map(|p| {
            fs::read_to_string(p)
                .unwrap()
                .lines()
                .take_while(|l| *l != "#[cfg(test)]")
                .enumerate()
                .filter(|(_, l)| l.contains(needle))
                .map(|(i, l)| format!("{}:{}: {}", p.display(), i + 1, l.trim()))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn imports_follow_the_data_flow() {
    let forbidden = [
        ("src/engines/rapier", "explicit"),
        ("src/engines/analytic", "explicit"),
        ("src/engines/explicit", "rapier"),
        ("src/engines/analytic", "rapier"),
        ("src/engines/explicit", "analytic"),
        ("src/engines/rapier", "analytic"),
        ("src/engines", "crate::run"),
        ("src/engines", "crate::report"),
        ("src/engines", "crate::comparison"),
        ("src/engines", "crate::case"),
        ("src/scene", "crate::case"),
        ("src/scene", "toml"),
        ("src/scene", "crate::engines"),
        ("src/contract.rs", "crate::engines"),
        ("src/contract.rs", "crate::case"),
        ("src/run", "crate::report"),
        ("src/run", "crate::comparison"),
        ("src/comparison", "crate::engines"),
        // The comparison may read what the run returns (it is to its left); only the budget's
        // ladders, which rerun a job, go through it. It never names an engine type.
        ("src/comparison", "crate::report"),
        ("src/case", "crate::engines"),
        ("src/case", "crate::run"),
        // The pipeline runs the whole flow, so it comes last: nothing in the flow uses it.
        ("src/scene", "crate::pipeline"),
        ("src/contract.rs", "crate::pipeline"),
        ("src/case", "crate::pipeline"),
        ("src/engines", "crate::pipeline"),
        ("src/run", "crate::pipeline"),
        ("src/comparison", "crate::pipeline"),
        ("src/report", "crate::pipeline"),
        // The command line parses options and calls the pipeline: nothing else uses it.
        ("src/scene", "crate::cli"),
        ("src/contract.rs", "crate::cli"),
        ("src/case", "crate::cli"),
        ("src/engines", "crate::cli"),
        ("src/run", "crate::cli"),
        ("src/comparison", "crate::cli"),
        ("src/report", "crate::cli"),
        ("src/pipeline.rs", "crate::cli"),
    ];
    let mut found = Vec::new();
    for (dir, needle) in forbidden {
        let hits = if dir.ends_with(".rs") {
            fs::read_to_string(dir)
                .unwrap()
                .lines()
                .enumerate()
                .filter(|(_, l)| l.contains(needle))
                .map(|(i, l)| format!("{dir}:{}: {}", i + 1, l.trim()))
                .collect()
        } else {
            mentions(dir, needle)
        };
        found.extend(hits.into_iter().map(|h| format!("`{needle}` in {h}")));
    }
    assert!(
        found.is_empty(),
        "imports against the flow:\n{}",
        found.join("\n")
    );
}

#[test]
fn readme_diagram_matches_the_modules() {
    let readme = fs::read_to_string("README.md").unwrap();
    let start = readme
        .find("## Architecture")
        .expect("an architecture section");
    let section = &readme[start..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |i| i + 3)];
    // Every path the diagram names exists (`src/case/{file,build}.rs` expands).
    let mut named = Vec::new();
    for word in section.split_whitespace() {
        let word = word.trim_matches(|c: char| c == ',' || c == '`' || c == '(' || c == ')');
        if !word.starts_with("src/") {
            continue;
        }
        if let (Some(open), Some(close)) = (word.find('{'), word.find('}')) {
            for part in word[open + 1..close].split(',') {
                named.push(format!("{}{part}{}", &word[..open], &word[close + 1..]));
            }
        } else {
            named.push(word.to_string());
        }
    }
    for p in &named {
        assert!(
            Path::new(p).exists(),
            "the README names {p}, which does not exist"
        );
    }
    // Every module file and engine directory is named.
    for f in rust_files(Path::new("src")) {
        let f = f.to_string_lossy().into_owned();
        let covered = named.iter().any(|n| {
            *n == f || (n.ends_with('/') && f.starts_with(n.as_str()) && f.contains("/engines/"))
        });
        let is_support = f.ends_with("src/lib.rs");
        assert!(
            covered || is_support,
            "{f} is not in the README's architecture diagram"
        );
    }
}
