//! The spring/dashpot/mass systems, by hand.
//!
//! The scene is read only for its parameters: the end and middle masses (the nodes of the
//! `u_end`/`u_mid` columns), the springs and dashpots between ground, middle and end along the
//! line of action, the static step's initial stretch and which masses the dynamic step holds.
//!
//! - Middle mass held (grounded test): m ü + c u̇ + k u = 0, u(0) = u0, u̇(0) = 0, with
//!   ωn = √(k/m), ζ = c/(2 m ωn): under-, critically and over-damped ([`single_dof`]).
//! - Both masses free (node-to-node test): M ü + C u̇ + K u = 0 with
//!   M = diag(m1, m2), K = [[k1+k2, −k2], [−k2, k2]], C = [[c1+c2, −c2], [−c2, c2]]
//!   (the dashpot between the masses only: non-proportional), exact as
//!   z(t) = exp(A t) z0, A = [[0, I], [−M⁻¹K, −M⁻¹C]].

use super::{exponential_states, history, unsupported};
use crate::engines::{EngineError, History};
use crate::scene::{
    Attachment, Connection, Dof, Element, NodeId, Probe, Scene, StepKind, parallel,
};
use nalgebra::{DMatrix, DVector, Vector3};

/// Where an element end sits in the system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Ground,
    Middle,
    End,
}

struct System {
    end: NodeId,
    middle: Option<NodeId>,
    line: Vector3<f64>,
}

impl System {
    fn role(&self, scene: &Scene, node: NodeId) -> Result<Role, EngineError> {
        if node == self.end {
            Ok(Role::End)
        } else if Some(node) == self.middle {
            Ok(Role::Middle)
        } else if scene.nodes[node].mass == 0.0 && scene.nodes[node].attachment == Attachment::Free
        {
            Ok(Role::Ground)
        } else {
            unsupported(format!(
                "node `{}` is neither ground, middle nor end",
                scene.nodes[node].name
            ))
        }
    }

    /// The pair of roles an element joins (ground first), checking it acts along the line.
    fn ends(&self, scene: &Scene, e: &Element) -> Result<(Role, Role), EngineError> {
        let along = |d: Vector3<f64>| parallel(&d.normalize(), &self.line);
        let (a, b) = match &e.connection {
            Connection::Grounded { node, dof } => {
                let Dof::Translation(axis) = dof else {
                    return unsupported("rotational element in a spring system");
                };
                if !along(scene.nodes[*node].frame.column(*axis).into_owned()) {
                    return unsupported(format!(
                        "{} does not act along the line of action",
                        e.name
                    ));
                }
                (Role::Ground, self.role(scene, *node)?)
            }
            Connection::FixedDirection { nodes, direction } => {
                if !along(*direction) {
                    return unsupported(format!(
                        "{} does not act along the line of action",
                        e.name
                    ));
                }
                (self.role(scene, nodes[0])?, self.role(scene, nodes[1])?)
            }
            Connection::Axial { nodes } => {
                if !along(scene.nodes[nodes[1]].position - scene.nodes[nodes[0]].position) {
                    return unsupported(format!(
                        "{} does not lie along the line of action",
                        e.name
                    ));
                }
                (self.role(scene, nodes[0])?, self.role(scene, nodes[1])?)
            }
        };
        Ok(if a as u8 <= b as u8 { (a, b) } else { (b, a) })
    }
}

/// Whether a node's motion along `line` is held in a step.
fn held_along(scene: &Scene, step: usize, node: NodeId, line: &Vector3<f64>) -> bool {
    scene.steps[step].conditions.iter().any(|c| {
        c.node == node
            && matches!(c.dof, Dof::Translation(_))
            && parallel(
                &scene.nodes[node].frame.column(c.dof.axis()).into_owned(),
                line,
            )
    })
}

/// Displacement along `line` that the static steps leave on a node.
fn initial_stretch(scene: &Scene, node: NodeId, line: &Vector3<f64>) -> f64 {
    let mut u = 0.0;
    for step in scene.steps.iter().filter(|s| s.kind == StepKind::Static) {
        for c in &step.conditions {
            if c.node == node
                && let (Some(v), Dof::Translation(axis)) = (c.value, c.dof)
            {
                u += v * scene.nodes[node].frame.column(axis).dot(line);
            }
        }
    }
    u
}

/// Solve a spring-family scene by its hand-derived closed form.
pub fn solve(scene: &Scene) -> Result<History, EngineError> {
    let (end, line) = match scene.columns.first().map(|c| &c.probe) {
        Some(Probe::Displacement { node, direction }) => (*node, *direction),
        _ => return unsupported("`u_end` must be a displacement column"),
    };
    let middle = match scene.columns.get(1).map(|c| &c.probe) {
        Some(Probe::Displacement { node, .. }) => Some(*node),
        Some(Probe::Zero { .. }) => None,
        _ => return unsupported("`u_mid` must be a displacement or zero column"),
    };
    let dynamic: Vec<usize> = (0..scene.steps.len())
        .filter(|&i| matches!(scene.steps[i].kind, StepKind::Dynamic { .. }))
        .collect();
    if dynamic.len() != 1 || dynamic[0] + 1 != scene.steps.len() {
        return unsupported("one dynamic step, after the static ones");
    }
    if scene
        .initial_velocities
        .iter()
        .any(|iv| iv.velocity != Vector3::zeros() || iv.angular != Vector3::zeros())
    {
        // The hand-derived forms release from rest; a start with velocity goes to the general
        // linear solver.
        return unsupported("released from rest (no initial velocity)");
    }
    let step = dynamic[0];
    let system = System { end, middle, line };
    let middle_free = middle.is_some_and(|m| !held_along(scene, step, m, &line));
    if held_along(scene, step, end, &line) {
        return unsupported("the end mass is held in the dynamic step");
    }
    // Stiffness and damping between each pair of roles.
    let mut k = [[0.0; 3]; 3];
    let mut c = [[0.0; 3]; 3];
    for (list, table) in [(&scene.springs, &mut k), (&scene.dashpots, &mut c)] {
        for e in list {
            let (a, b) = system.ends(scene, e)?;
            table[a as usize][b as usize] += e.coefficient;
        }
    }
    let (g, mid, en) = (
        Role::Ground as usize,
        Role::Middle as usize,
        Role::End as usize,
    );
    let m_end = scene.nodes[end].mass;
    let u0 = initial_stretch(scene, end, &line);
    let times = scene.output_times();

    let rows: Vec<Vec<f64>> = if !middle_free {
        // The end mass against ground (a held middle mass is ground for it).
        let kk = k[g][en] + k[mid][en];
        let cc = c[g][en] + c[mid][en];
        let wn = (kk / m_end).sqrt();
        let zeta = cc / (2.0 * m_end * wn);
        if !(wn > 0.0 && wn.is_finite() && zeta.is_finite()) {
            return unsupported("no stiffness on the end mass");
        }
        let u_mid = middle.map_or(0.0, |m| initial_stretch(scene, m, &line));
        times
            .iter()
            .map(|&t| {
                let (u, v) = single_dof(u0, wn, zeta, t);
                vec![u, u_mid, v, 0.0, 1.0]
            })
            .collect()
    } else {
        let m_mid = scene.nodes[middle.unwrap()].mass;
        let kmat = DMatrix::from_row_slice(
            2,
            2,
            &[
                k[g][mid] + k[mid][en],
                -k[mid][en],
                -k[mid][en],
                k[mid][en] + k[g][en],
            ],
        );
        let cmat = DMatrix::from_row_slice(
            2,
            2,
            &[
                c[g][mid] + c[mid][en],
                -c[mid][en],
                -c[mid][en],
                c[mid][en] + c[g][en],
            ],
        );
        let minv = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0 / m_mid, 1.0 / m_end]));
        let mut a = DMatrix::zeros(4, 4);
        a.view_mut((0, 2), (2, 2)).fill_with_identity();
        a.view_mut((2, 0), (2, 2)).copy_from(&(-&minv * kmat));
        a.view_mut((2, 2), (2, 2)).copy_from(&(-&minv * cmat));
        let u_mid0 = initial_stretch(scene, middle.unwrap(), &line);
        let z0 = DVector::from_vec(vec![u_mid0, u0, 0.0, 0.0]);
        exponential_states(&a, &z0, &times)?
            .into_iter()
            .map(|z| vec![z[1], z[0], z[3], z[2], 1.0])
            .collect()
    };
    Ok(history(scene, &times, rows))
}

/// Displacement and velocity of m ü + c u̇ + k u = 0 released from `u0` at rest, for any
/// damping ratio `zeta` ≥ 0 (ωn = √(k/m) = `wn`).
///
/// - ζ < 1: u = u0 e^(−ζωn t) (cos ωd t + ζωn/ωd sin ωd t), u̇ = −u0 (ωn²/ωd) e^(−ζωn t) sin ωd t.
/// - ζ ≥ 1: the roots r₁ = −ωn²/(ζωn + s) (the slow one, written without cancellation) and
///   r₂ = −ζωn − s, s = ωn √(ζ² − 1), give u = u0 (r₁ e^(r₂t) − r₂ e^(r₁t))/(r₁ − r₂) and
///   u̇ = u0 ωn² (e^(r₂t) − e^(r₁t))/(r₁ − r₂). With g = (e^(−2st) − 1)/(2s) (= −t at s = 0,
///   and through `exp_m1` accurate as s → 0) they read u = u0 e^(r₁t) (1 + r₁ g) and
///   u̇ = u0 ωn² e^(r₁t) g: one expression for critical (ζ = 1: u0 e^(−ωn t)(1 + ωn t)) and
///   overdamped motion, with no 0/0 near ζ = 1.
pub fn single_dof(u0: f64, wn: f64, zeta: f64, t: f64) -> (f64, f64) {
    if zeta < 1.0 {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let decay = (-zeta * wn * t).exp();
        let (s, co) = (wd * t).sin_cos();
        (
            u0 * decay * (co + zeta * wn / wd * s),
            -u0 * wn * wn / wd * decay * s,
        )
    } else {
        let s = wn * ((zeta - 1.0) * (zeta + 1.0)).sqrt();
        let r1 = -wn * wn / (zeta * wn + s);
        let g = if s > 0.0 {
            (-2.0 * s * t).exp_m1() / (2.0 * s)
        } else {
            -t
        };
        let slow = (r1 * t).exp();
        (u0 * slow * (1.0 + r1 * g), u0 * wn * wn * slow * g)
    }
}
