//! rapier's control experiments (`Engine::controls`): the same run with one suspected cause of
//! a discrepancy varied, each something the exact solution does not depend on: f64 for f32, a
//! stiffer contact softness (and a softer one on rapier 0.34, whose restitution depends on
//! it), restitution 0 on pairs that start closed and never strike, the contact impulse read as
//! n/(n + 1) of what rapier 0.34 reports, gyroscopic forces on rapier 0.34 (off by default
//! there).

use super::{Configuration, MatchedSettings, Precision, RapierEngine};
use crate::engines::{Control, ControlKind};
use crate::scene::{ContactPair, ContactState, Dimension, Scene};

/// The control experiments of `engine` on `scene`.
pub fn of(engine: &RapierEngine, scene: &Scene) -> Vec<Control> {
    let mut out = Vec::new();
    if engine.precision == Precision::F32 {
        out.push(Control {
            kind: ControlKind::Precision,
            change: "rapier in f64 with the same settings".into(),
            engine: Some(Box::new(RapierEngine {
                name: format!("{}_in_f64", engine.name),
                precision: Precision::F64,
                ..engine.clone()
            })),
            scene: None,
        });
    }
    if engine.release.gyroscopic_off_by_default() && scene.dimension == Dimension::Three {
        out.push(Control {
            kind: ControlKind::Gyroscopic,
            change: "gyroscopic forces on (`gyroscopic_forces_enabled`; off by default on 0.34)"
                .into(),
            engine: Some(Box::new(engine.clone().with_gyroscopic(true))),
            scene: None,
        });
    }
    if scene.contacts.is_empty() {
        return out;
    }
    if let Configuration::Matched(m) = engine.configuration {
        // The contact softness times `factor`, named with `suffix`.
        let softness = |factor: f64, suffix: &str| {
            let varied = MatchedSettings {
                contact_frequency: factor * m.contact_frequency,
                ..m
            };
            Control {
                kind: ControlKind::ContactSoftness,
                change: format!(
                    "`contact_softness` {:.0e} Hz instead of {:.0e} Hz",
                    varied.contact_frequency, m.contact_frequency
                ),
                engine: Some(Box::new(RapierEngine {
                    name: format!("{}_{suffix}", engine.name),
                    configuration: Configuration::Matched(varied),
                    ..engine.clone()
                })),
                scene: None,
            }
        };
        out.push(softness(10.0, "stiffer_contact"));
        if engine.release.restitution_in_substeps() {
            out.push(softness(0.1, "softer_contact"));
        }
    }
    if engine.configuration == Configuration::Default {
        let hz = MatchedSettings::chosen(engine.precision).contact_frequency;
        out.push(Control {
            kind: ControlKind::ContactSoftness,
            change: format!(
                "`contact_softness` {hz:.0e} Hz, damping ratio 1 (the matched configuration's) \
                 instead of rapier's {}",
                engine.release.default_contact_softness()
            ),
            engine: Some(Box::new(RapierEngine {
                name: format!("{}_matched_softness", engine.name),
                default_softness: Some(hz),
                ..engine.clone()
            })),
            scene: None,
        });
    }
    if engine.release.reports_extra_substep_impulse() {
        let n = match engine.configuration {
            Configuration::Matched(m) => m.solver_iterations,
            Configuration::Default => super::backend::DEFAULT_SOLVER_ITERATIONS,
        };
        out.push(Control {
            kind: ControlKind::ImpulseReading,
            change: format!(
                "the contact impulse read as {n}/{} of what rapier reports (the motion unchanged)",
                n + 1
            ),
            engine: Some(Box::new(RapierEngine {
                name: format!("{}_impulse_per_step", engine.name),
                impulse_scale: n as f64 / (n + 1) as f64,
                ..engine.clone()
            })),
            scene: None,
        });
    }
    if let Some(varied) = closed_pairs_inelastic(scene) {
        out.push(Control {
            kind: ControlKind::Restitution,
            change: "restitution 0 on the pairs that start closed".into(),
            engine: None,
            scene: Some(varied),
        });
    }
    out
}

/// The scene with restitution 0 on every contact pair that starts closed, where one has a
/// restitution above 0 (`None` otherwise): a control for how rapier treats the restitution of a
/// resting contact. It changes nothing the exact solution sees as long as that pair never
/// strikes (the comparison checks that its exact solution has no impact).
pub fn closed_pairs_inelastic(scene: &Scene) -> Option<Scene> {
    let closed = |c: &ContactPair| c.initially == ContactState::Closed && c.restitution > 0.0;
    if !scene.contacts.iter().any(closed) {
        return None;
    }
    let mut varied = scene.clone();
    for c in varied.contacts.iter_mut().filter(|c| closed(c)) {
        c.restitution = 0.0;
    }
    Some(varied)
}
