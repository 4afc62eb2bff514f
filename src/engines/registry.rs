//! The list of engines crosscheck has, in report order, and finding one by name.

use super::{Engine, analytic, explicit, rapier, reference};

/// Every engine crosscheck has, in report order.
pub fn all() -> Vec<Box<dyn Engine>> {
    vec![
        Box::new(analytic::AnalyticEngine),
        Box::new(reference::ReferenceEngine),
        Box::new(explicit::ExplicitEngine::finite()),
        Box::new(explicit::ExplicitEngine::small()),
        Box::new(rapier::RapierEngine::matched(rapier::Precision::F64)),
        Box::new(rapier::RapierEngine::matched(rapier::Precision::F32)),
        Box::new(rapier::RapierEngine::default_configuration(
            rapier::Precision::F64,
        )),
        Box::new(rapier::RapierEngine::default_configuration(
            rapier::Precision::F32,
        )),
    ]
}

/// Engine by name.
pub fn named(name: &str) -> Option<Box<dyn Engine>> {
    all().into_iter().find(|e| e.name() == name)
}
