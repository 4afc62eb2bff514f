//! The list of engines crosscheck has, in report order, and finding one by name. It lives in
//! the run layer, not beside the engines, so that no engine can reach another through it.

#[cfg(feature = "rapier")]
use crate::engines::rapier;
use crate::engines::{Engine, analytic, explicit, reference};

/// Every engine crosscheck has, in report order (the rapier engines with the `rapier`
/// feature, on by default).
pub fn all() -> Vec<Box<dyn Engine>> {
    let own: Vec<Box<dyn Engine>> = vec![
        Box::new(analytic::AnalyticEngine),
        Box::new(reference::ReferenceEngine),
        Box::new(explicit::ExplicitEngine::finite()),
        Box::new(explicit::ExplicitEngine::small()),
    ];
    own.into_iter().chain(rapier_engines()).collect()
}

/// None without the `rapier` feature.
#[cfg(not(feature = "rapier"))]
fn rapier_engines() -> Vec<Box<dyn Engine>> {
    Vec::new()
}

/// The rapier engines: matched and default configurations, f64 and f32; then, with the
/// `rapier-versions` feature, the f64 ones on older releases (`rapier_f64@0.34`, ...).
#[cfg(feature = "rapier")]
fn rapier_engines() -> Vec<Box<dyn Engine>> {
    rapier::engines()
        .into_iter()
        .chain(rapier::older_releases())
        .map(|e| Box::new(e) as Box<dyn Engine>)
        .collect()
}

/// Engine by name.
pub fn named(name: &str) -> Option<Box<dyn Engine>> {
    all().into_iter().find(|e| e.name() == name)
}

/// The rapier engines' names: a case file may declare their tolerances whether or not the
/// build has them (without the `rapier` feature those lines are kept, unused).
pub const RAPIER_NAMES: [&str; 4] = [
    "rapier_f64",
    "rapier_f32",
    "rapier_f64_default",
    "rapier_f32_default",
];

/// The names a case file may declare a tolerance for: every engine of [`all`], then the rapier
/// engines' where this build has not got them.
pub fn known_names() -> Vec<String> {
    let mut names: Vec<String> = all().iter().map(|e| e.name().to_string()).collect();
    for n in RAPIER_NAMES {
        if !names.iter().any(|m| m == n) {
            names.push(n.to_string());
        }
    }
    names
}
