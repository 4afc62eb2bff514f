//! Why a run went unstable: the mode of the linearised scene that carries the motion when the
//! energy guard trips, named by its frequency and the DOFs it moves.
//!
//! The central-difference scheme amplifies a mode whose ω·h exceeds 2 by |λ| > 1 per increment
//! (|λ| ≈ 1.49 at ω·h = 2.04, undamped), so by the time the energy is twice what the run may hold,
//! that mode carries practically all of the motion: the velocities' projection on the modes
//! (mass-weighted, φᵀM q̇) names it.

use super::model::{Config, Constraints, ContactMode, Counters, Model, Rates, Target};
use super::space::Space;
use crate::scene::{DampingTreatment, Scene};
use nalgebra::DVector;

/// The mode an unstable run's motion is in.
#[derive(Debug, Clone, PartialEq)]
pub struct GrowingMode {
    /// Circular frequency (rad/s).
    pub omega: f64,
    /// The largest increment at which this mode alone is stable (2/ω undamped or centred).
    pub limit: f64,
    /// Its share of the kinetic energy of the velocities it was found from (0–1).
    pub share: f64,
    /// The DOFs it moves most, as (label, component scaled so the largest is ±1), largest first.
    pub dofs: Vec<(String, f64)>,
}

impl GrowingMode {
    /// One line: frequency, ω·h, DOFs and energy share.
    pub fn describe(&self, h: f64) -> String {
        let dofs: Vec<String> = self
            .dofs
            .iter()
            .map(|(l, c)| format!("{l} ({c:+.2})"))
            .collect();
        format!(
            "the growing mode is ω = {:.4e} rad/s ({:.4e} Hz; ω·h = {:.3}, h = {:.3} × its own limit {:.4e}) in {}, carrying {:.1} % of the kinetic energy",
            self.omega,
            self.omega / std::f64::consts::TAU,
            self.omega * h,
            h / self.limit,
            self.limit,
            dofs.join(", "),
            100.0 * self.share
        )
    }

    /// One line for a run stopped below this mode's limit after a penalty impact at `at`: no
    /// mode grows there; the energy came in at the impact. A contact mode of ω·h resolves an
    /// impact in about π/(ω·h) increments; a node inside for one increment at depth d ≤ h·v
    /// leaves at ω²h·d − v, up to ((ω·h)² − 1)·v, so above ω·h = √2 an impact can return more
    /// energy than it received (up to ((ω·h)² − 1)² times).
    pub fn describe_impact(&self, h: f64, at: f64) -> String {
        let wh = self.omega * h;
        format!(
            "no mode is past its limit (the one carrying the motion, ω = {:.4e} rad/s in {}, has ω·h = {wh:.3}, h = {:.3} × its limit): the energy came in at the penalty impact at t = {at:e}, which this mode resolves in about π/(ω·h) = {:.1} increments; a node inside for one increment rebounds at up to (ω·h)² − 1 = {:.2} × its striking speed, so above ω·h = √2 an impact can return more energy than it received",
            self.omega,
            self.dofs
                .first()
                .map_or("no DOF".to_string(), |(l, _)| l.clone()),
            h / self.limit,
            std::f64::consts::PI / wh,
            wh * wh - 1.0
        )
    }
}

/// The mode responsible for an unstable run at increment `h`: of the modes of the scene
/// linearised at `cfg` (contacts closed) that increment `h` puts past their stability limit
/// under `treatment`, the one that carries the largest share of the kinetic energy of `rates`
/// (when none is past it, the growth is nonlinear, and the mode with the largest share is
/// named). `None` without free DOFs or motion.
///
/// Past the limit is not always where the energy ends up: a penalty mode that grows opens the
/// contact, and the chatter pumps energy into the slow rigid-body modes, which then carry most
/// of it (73–94 % measured on the pinned seed cases at 1.02×).
pub fn growing_mode<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    scene: &Scene,
    cfg: &Config<S>,
    held: &Constraints<S>,
    rates: &Rates<S>,
    h: f64,
    treatment: DampingTreatment,
) -> Option<GrowingMode> {
    // The diagnosis's own force evaluations are not the run's work: counted apart.
    let lin = model.linearise(cfg, held, ContactMode::Bilateral, &mut Counters::default());
    let qdot = DVector::from_iterator(
        lin.dofs.len(),
        lin.dofs.iter().map(|d| model.rate_along(rates, d)),
    );
    let momentum = &lin.mass * &qdot;
    let shapes = lin.shapes();
    let energies: Vec<f64> = shapes
        .iter()
        .map(|(_, phi)| phi.dot(&momentum).powi(2))
        .collect();
    let total: f64 = energies.iter().sum();
    if !(total.is_finite() && total > 0.0) {
        return None;
    }
    let past = |i: &usize| shapes[*i].0.omega > 0.0 && h > shapes[*i].0.limit(treatment);
    let candidates: Vec<usize> = if (0..shapes.len()).any(|i| past(&i)) {
        (0..shapes.len()).filter(past).collect()
    } else {
        (0..shapes.len()).collect()
    };
    let best = candidates
        .into_iter()
        .max_by(|a, b| energies[*a].total_cmp(&energies[*b]))?;
    let energy = energies[best];
    let (mode, phi) = &shapes[best];
    let largest = phi.amax();
    let mut dofs: Vec<(String, f64)> = lin
        .dofs
        .iter()
        .zip(phi.iter())
        .map(|(d, c)| (label(model, scene, d), c / largest))
        .filter(|(_, c)| c.abs() >= 0.05)
        .collect();
    dofs.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    dofs.truncate(4);
    Some(GrowingMode {
        omega: mode.omega,
        limit: mode.limit(treatment),
        share: energy / total,
        dofs,
    })
}

/// `node.ux` for a DOF along a global axis, `node.u(0.71,0.71,0)` otherwise.
fn label<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    scene: &Scene,
    target: &Target<S>,
) -> String {
    let (node, prefix, direction) = match target {
        Target::Particle(i, d) => (model.particles[*i].node, "u", S::v3(d)),
        Target::Translation(b, d) => (model.bodies[*b].node, "u", S::v3(d)),
        Target::Rotation(b, g) => (model.bodies[*b].node, "r", S::w3(g)),
    };
    let axis = (0..3).find(|&k| (direction[k].abs() - 1.0).abs() < 1e-12);
    let name = &scene.nodes[node].name;
    match axis {
        Some(k) => format!(
            "{name}.{}{}{}",
            if direction[k] < 0.0 { "-" } else { "" },
            prefix,
            ["x", "y", "z"][k]
        ),
        None => {
            let (x, y, z) = (direction.x, direction.y, direction.z);
            format!("{name}.{prefix}({x:.2},{y:.2},{z:.2})")
        }
    }
}

/// The modes an increment puts past their stability limit, watched while a run goes on: by
/// linear theory their energy can only grow, so a 100-fold growth is instability even where a
/// nonlinearity keeps the total energy bounded (a light body under finite rotation detunes its
/// own mode as its swing grows, and its energy saturates below the guard).
pub struct PastLimit<S: Space> {
    dofs: Vec<Target<S>>,
    /// M·φ per mode past the limit (φ mass-normalised): the modal velocity is (Mφ)ᵀ q̇.
    weights: Vec<DVector<f64>>,
    /// Their kinetic energy in the first look.
    initial: Option<f64>,
}

/// How much the watched modes' energy may grow before the run is stopped.
pub const PAST_LIMIT_GROWTH: f64 = 100.0;

impl<S: Space> PastLimit<S> {
    /// The modes of the scene linearised at `cfg` that increment `h` puts past their limit
    /// under `treatment`; `None` when there are none (every run at or below its stable
    /// increment).
    pub fn new<const FINITE: bool>(
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        held: &Constraints<S>,
        h: f64,
        treatment: DampingTreatment,
    ) -> Option<Self> {
        let lin = model.linearise(cfg, held, ContactMode::Bilateral, &mut Counters::default());
        let weights: Vec<DVector<f64>> = lin
            .shapes()
            .into_iter()
            .filter(|(m, _)| m.omega > 0.0 && h > m.limit(treatment) * (1.0 + 1e-12))
            .map(|(_, phi)| &lin.mass * phi)
            .collect();
        (!weights.is_empty()).then_some(PastLimit {
            dofs: lin.dofs,
            weights,
            initial: None,
        })
    }

    /// Whether the watched modes' kinetic energy in `rates` has grown past
    /// [`PAST_LIMIT_GROWTH`] × its first value (or × `floor`, a round-off level of the run's
    /// energy, when that was smaller): `Some(growth)` when it has.
    pub fn grown<const FINITE: bool>(
        &mut self,
        model: &Model<S, FINITE>,
        rates: &Rates<S>,
        floor: f64,
    ) -> Option<f64> {
        let qdot = DVector::from_iterator(
            self.dofs.len(),
            self.dofs.iter().map(|d| model.rate_along(rates, d)),
        );
        let energy: f64 = self
            .weights
            .iter()
            .map(|w| 0.5 * w.dot(&qdot).powi(2))
            .sum();
        let base = self.initial.get_or_insert(energy).max(floor);
        (energy > PAST_LIMIT_GROWTH * base).then_some(energy / base)
    }
}
