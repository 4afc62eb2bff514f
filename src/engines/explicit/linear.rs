//! The scene linearised about a configuration, in its free generalised DOFs: mass, stiffness
//! and damping matrices, the modes they give, the [`StableIncrement`], and the static step.
//!
//! Stiffness and damping are central finite differences of the engine's own force routines,
//! so they include everything the simulation includes (geometric stiffness of preloaded
//! springs and of the load under finite rotation, the penalty of closed contacts).

use super::model::{Config, Constraints, ContactMode, Counters, Model, Target};
use super::space::{Lin, Space};
use crate::engines::EngineError;
use crate::scene::DampingTreatment;
use nalgebra::{DMatrix, DVector};

/// M, K, C in the free DOFs.
pub struct Linearised<S: Space> {
    /// The DOFs, in matrix order.
    pub dofs: Vec<Target<S>>,
    /// Mass matrix.
    pub mass: DMatrix<f64>,
    /// Tangent stiffness (symmetrised).
    pub stiffness: DMatrix<f64>,
    /// Damping matrix of the dashpots.
    pub damping: DMatrix<f64>,
}

/// One mode of the linearised system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    /// Circular frequency (rad/s).
    pub omega: f64,
    /// Modal damping ratio φᵀCφ / (2ω φᵀMφ).
    pub zeta: f64,
}

/// The stable time increment of a scene, and where it comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableIncrement {
    /// Highest frequency, penalty included.
    pub omega_max: f64,
    /// Damping ratio of that mode.
    pub zeta: f64,
    /// Undamped limit 2/ω_max.
    pub undamped: f64,
    /// Limit of the lagged treatment: min over modes of (2/ω)(√(1+ζ²) − ζ).
    pub lagged: f64,
    /// The limit of the treatment in use.
    pub increment: f64,
    /// Highest frequency of the structure without contact (the accuracy rule's reference).
    pub omega_structure: f64,
}

impl Mode {
    /// The largest increment at which this mode alone is stable under `treatment`.
    pub fn limit(&self, treatment: DampingTreatment) -> f64 {
        match treatment {
            DampingTreatment::Centred => 2.0 / self.omega,
            DampingTreatment::Lagged => {
                (2.0 / self.omega) * ((1.0 + self.zeta * self.zeta).sqrt() - self.zeta)
            }
        }
    }
}

const PERTURBATION: f64 = 1e-6;

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    fn generalised_forces(
        &self,
        cfg: &Config<S>,
        dofs: &[Target<S>],
        mode: ContactMode,
        counters: &mut Counters,
    ) -> DVector<f64> {
        let mut f = self.zero_forces();
        self.forces(cfg, mode, &mut f, counters);
        if matches!(mode, ContactMode::Bilateral) && self.has_friction() {
            self.stick_forces_about_start(cfg, &mut f);
        }
        DVector::from_iterator(dofs.len(), dofs.iter().map(|d| self.project(&f, d)))
    }

    /// Tangent stiffness −∂Q/∂q by central differences, symmetrised.
    fn stiffness(
        &self,
        cfg: &Config<S>,
        dofs: &[Target<S>],
        mode: ContactMode,
        counters: &mut Counters,
    ) -> DMatrix<f64> {
        let n = dofs.len();
        let mut k = DMatrix::zeros(n, n);
        for (j, d) in dofs.iter().enumerate() {
            let mut plus = cfg.clone();
            self.perturb(&mut plus, d, PERTURBATION);
            let mut minus = cfg.clone();
            self.perturb(&mut minus, d, -PERTURBATION);
            let qp = self.generalised_forces(&plus, dofs, mode, counters);
            let qm = self.generalised_forces(&minus, dofs, mode, counters);
            k.set_column(j, &((qm - qp) / (2.0 * PERTURBATION)));
        }
        (&k + k.transpose()) * 0.5
    }

    /// Linearise about `cfg` under `held`, with contacts closed (`ContactMode::Bilateral`) or
    /// off (`ContactMode::Off`).
    pub fn linearise(
        &self,
        cfg: &Config<S>,
        held: &Constraints<S>,
        mode: ContactMode,
        counters: &mut Counters,
    ) -> Linearised<S> {
        let dofs = self.free_dofs(held);
        let n = dofs.len();
        let mass = DMatrix::from_fn(n, n, |i, j| self.mass_entry(cfg, &dofs[i], &dofs[j]));
        let stiffness = self.stiffness(cfg, &dofs, mode, counters);
        let mut damping = DMatrix::zeros(n, n);
        if self.has_dashpots() {
            for (j, d) in dofs.iter().enumerate() {
                let unit = self.unit_rate(d);
                let mut f = self.zero_forces();
                self.damping(cfg, &unit, &mut f, counters);
                for (i, e) in dofs.iter().enumerate() {
                    damping[(i, j)] = -self.project(&f, e);
                }
            }
        }
        Linearised {
            dofs,
            mass,
            stiffness,
            damping,
        }
    }
}

impl<S: Space> Linearised<S> {
    /// Modes: frequencies and damping ratios, highest first.
    pub fn modes(&self) -> Vec<Mode> {
        self.shapes().into_iter().map(|(m, _)| m).collect()
    }

    /// Modes with their shapes (mass-normalised, φᵀMφ = 1, in the order of [`Self::dofs`]),
    /// highest first.
    pub fn shapes(&self) -> Vec<(Mode, DVector<f64>)> {
        let n = self.dofs.len();
        if n == 0 {
            return Vec::new();
        }
        let l = self
            .mass
            .clone()
            .cholesky()
            .expect("mass matrix positive definite on free DOFs (validated)")
            .l();
        let linv = l
            .clone()
            .try_inverse()
            .expect("triangular factor invertible");
        let a = &linv * &self.stiffness * linv.transpose();
        let a = (&a + a.transpose()) * 0.5;
        let eig = a.symmetric_eigen();
        let mut modes: Vec<(Mode, DVector<f64>)> = (0..n)
            .map(|i| {
                let omega = eig.eigenvalues[i].max(0.0).sqrt();
                let phi = linv.transpose() * eig.eigenvectors.column(i);
                let zeta = if omega > 0.0 {
                    (phi.transpose() * &self.damping * &phi)[0]
                        / (2.0 * omega * (phi.transpose() * &self.mass * &phi)[0])
                } else {
                    0.0
                };
                (Mode { omega, zeta }, phi)
            })
            .collect();
        modes.sort_by(|a, b| b.0.omega.total_cmp(&a.0.omega));
        modes
    }
}

impl StableIncrement {
    /// From bounds instead of modes: λ ≥ every eigenvalue of M⁻¹K and γ ≥ 2ζω of every mode
    /// (the row-sum bound on M⁻¹C), so the limits are safe: `2/√λ` undamped and
    /// `2/(√(λ + γ²/4) + γ/2)` lagged, which is below (2/ω)(√(1+ζ²) − ζ) for every mode.
    pub fn from_bound(lambda: f64, gamma: f64, treatment: DampingTreatment) -> Option<Self> {
        if lambda.is_nan() || lambda <= 0.0 {
            return None;
        }
        let omega = lambda.sqrt();
        let lagged = 2.0 / ((lambda + 0.25 * gamma * gamma).sqrt() + 0.5 * gamma);
        Some(Self::of(
            (omega, 0.5 * gamma / omega),
            lagged,
            omega,
            treatment,
        ))
    }

    /// The limits of the highest mode `(ω, ζ)`, with the lagged limit `lagged` and the
    /// structure's highest frequency `omega_structure`.
    fn of(
        (omega, zeta): (f64, f64),
        lagged: f64,
        omega_structure: f64,
        treatment: DampingTreatment,
    ) -> Self {
        let undamped = 2.0 / omega;
        StableIncrement {
            omega_max: omega,
            zeta,
            undamped,
            lagged,
            increment: match treatment {
                DampingTreatment::Centred => undamped,
                DampingTreatment::Lagged => lagged,
            },
            omega_structure,
        }
    }

    /// From the modes with contact closed and the modes of the structure alone.
    pub fn from_modes(
        modes: &[Mode],
        structure: &[Mode],
        treatment: DampingTreatment,
    ) -> Option<Self> {
        let top = modes.iter().find(|m| m.omega > 0.0)?;
        let lagged = modes
            .iter()
            .filter(|m| m.omega > 0.0)
            .map(|m| m.limit(DampingTreatment::Lagged))
            .fold(f64::INFINITY, f64::min);
        let omega_structure = structure.first().map_or(top.omega, |m| m.omega);
        Some(Self::of(
            (top.omega, top.zeta),
            lagged,
            omega_structure,
            treatment,
        ))
    }
}

/// Solve a static step: apply its prescribed values, then Newton on the free DOFs.
pub fn static_step<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &mut Config<S>,
    held: &Constraints<S>,
    counters: &mut Counters,
) -> Result<(), EngineError> {
    for (target, value) in &held.prescribed {
        let current = match target {
            Target::Particle(i, d) => d.dot(&cfg.u.get(*i)),
            Target::Translation(b, d) => d.dot(&cfg.bu[*b]),
            Target::Rotation(b, g) => model.rotation_about(cfg, *b, g),
        };
        model.perturb(cfg, target, value - current);
    }
    let dofs = model.free_dofs(held);
    if dofs.is_empty() {
        return Ok(());
    }
    let mut scale = 1.0f64;
    for iteration in 0..50 {
        let q = model.generalised_forces(cfg, &dofs, ContactMode::Unilateral, counters);
        let norm = q.amax();
        if iteration == 0 {
            scale = scale.max(norm);
        }
        if norm <= 1e-10 * scale {
            return Ok(());
        }
        let k = model.stiffness(cfg, &dofs, ContactMode::Unilateral, counters);
        let Some(delta) = k.lu().solve(&q) else {
            return Err(EngineError::Failed(
                "static step: the free DOFs are not restrained (singular stiffness); hold them or add springs".into(),
            ));
        };
        for (d, x) in dofs.iter().zip(delta.iter()) {
            model.perturb(cfg, d, *x);
        }
    }
    Err(EngineError::Failed(
        "static step: Newton did not converge in 50 iterations".into(),
    ))
}
