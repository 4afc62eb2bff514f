//! A generated case family for the scaling study: a chain of N equal masses joined by equal
//! springs, fixed at both ends, started at rest in its j-th discrete mode.
//!
//! Node i (1…N) sits at x = i·L and moves along x only; nodes 0 and N+1 are fixed. The exact
//! solution is `x_i(t) = A sin(jπi/(N+1)) cos(ω_j t)` with `ω_j = 2√(k/m) sin(jπ/(2(N+1)))`.
//! Central differences started from rest (`v(½) = (h/2)·a(0)`) reproduce the mode shape
//! exactly and only shift its frequency, to `ω̃ = (2/h) asin(ω_j h/2)`: the computed history
//! is `A sin(jπi/(N+1)) cos(ω̃ t_n)` to round-off, so the error against the exact solution is
//! known in advance ([`Chain::predicted_error`]).
//!
//! The scene is built directly (a million-node TOML file would be 100 MB); it is the same kind
//! of scene a case file gives: particles, fixed-direction springs, a static step that sets the
//! mode shape and a dynamic step that releases it.

use crate::scene::{
    Attachment, BoundaryCondition, Column, Connection, ContactStart, DampingTreatment, Dimension,
    Dof, Element, Family, IncrementRule, Node, PenaltyRule, Probe, Scene, SceneSettings, Step,
    StepKind,
};
use nalgebra::{Matrix3, Vector3};
use std::f64::consts::PI;

/// One member of the chain family.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chain {
    /// Number of moving masses.
    pub n: usize,
    /// Mode number (1…N).
    pub mode: usize,
    /// Mass of each node, kg.
    pub mass: f64,
    /// Stiffness of each spring, N/m.
    pub stiffness: f64,
    /// Amplitude of the mode, m.
    pub amplitude: f64,
    /// Time increment, s.
    pub increment: f64,
    /// Increments over the run (a multiple of `rows − 1`).
    pub steps: u64,
    /// Output rows.
    pub rows: usize,
}

/// Spacing of the nodes, m.
const SPACING: f64 = 1.0;

impl Chain {
    /// The study's chain of `n` masses: m = 1 kg, k = 10⁴ N/m, A = 10⁻³ m, the mode
    /// j = round((N+1)/4) (ω_j ≈ 0.77·√(k/m) whatever N is, so every N runs the same physics),
    /// h = 0.1·√(m/k) (a twentieth of the stable limit), and `steps` increments (rounded up to
    /// a multiple of the 100 output intervals).
    pub fn new(n: usize, steps: u64) -> Self {
        let rows = 101;
        let interval = (rows - 1) as u64;
        let (mass, stiffness) = (1.0, 1.0e4);
        Chain {
            n,
            mode: ((n + 1) as f64 / 4.0).round().max(1.0) as usize,
            mass,
            stiffness,
            amplitude: 1.0e-3,
            increment: 0.1 * (mass / stiffness).sqrt(),
            steps: steps.div_ceil(interval).max(1) * interval,
            rows,
        }
    }

    /// Circular frequency of the mode, rad/s.
    pub fn omega(&self) -> f64 {
        2.0 * (self.stiffness / self.mass).sqrt()
            * (self.mode as f64 * PI / (2.0 * (self.n + 1) as f64)).sin()
    }

    /// The frequency central differences give the mode at increment h: (2/h) asin(ω h/2).
    pub fn discrete_omega(&self, h: f64) -> f64 {
        2.0 / h * (0.5 * self.omega() * h).asin()
    }

    /// Mode shape at node i (1…N): sin(jπi/(N+1)).
    pub fn shape(&self, i: usize) -> f64 {
        (self.mode as f64 * PI * i as f64 / (self.n + 1) as f64).sin()
    }

    /// Exact displacement of node i at time t.
    pub fn displacement(&self, i: usize, t: f64) -> f64 {
        self.amplitude * self.shape(i) * (self.omega() * t).cos()
    }

    /// Exact velocity of node i at time t.
    pub fn velocity(&self, i: usize, t: f64) -> f64 {
        -self.amplitude * self.shape(i) * self.omega() * (self.omega() * t).sin()
    }

    /// Duration of the run, s.
    pub fn duration(&self) -> f64 {
        self.steps as f64 * self.increment
    }

    /// The probed nodes: the end node N and the middle node, as (column name, node index 1…N).
    pub fn probes(&self) -> [(&'static str, usize); 2] {
        [("end", self.n), ("mid", self.n.div_ceil(2))]
    }

    /// What central differences at increment `h` must give as the error of the probed
    /// displacements against the exact solution, over the output rows: the largest of
    /// `|sin(jπi/(N+1))| · |cos(ω̃ t) − cos(ω t)|`, as a fraction of the amplitude.
    pub fn predicted_error(&self, h: f64) -> f64 {
        let (w, wd) = (self.omega(), self.discrete_omega(h));
        let shape = self
            .probes()
            .iter()
            .map(|(_, i)| self.shape(*i).abs())
            .fold(0.0, f64::max);
        (0..self.rows)
            .map(|r| {
                let t = self.duration() * r as f64 / (self.rows - 1) as f64;
                ((wd * t).cos() - (w * t).cos()).abs()
            })
            .fold(0.0, f64::max)
            * shape
    }

    /// The scene: nodes `0`…`N+1` (the ends fixed), springs between neighbours along x, a
    /// static step that prescribes the mode shape, a dynamic step that releases it; the output
    /// columns `u_end, u_mid, v_end, v_mid` along x (the springs family's contract).
    pub fn scene(&self) -> Scene {
        let n = self.n;
        let x = Vector3::x();
        let node = |i: usize, mass: f64| Node {
            name: i.to_string(),
            position: Vector3::new(i as f64 * SPACING, 0.0, 0.0),
            attachment: Attachment::Free,
            frame: Matrix3::identity(),
            mass,
        };
        let nodes: Vec<Node> = (0..=n + 1)
            .map(|i| node(i, if i == 0 || i == n + 1 { 0.0 } else { self.mass }))
            .collect();
        let springs = (0..=n)
            .map(|i| Element {
                name: format!("spring-{i}"),
                connection: Connection::FixedDirection {
                    nodes: [i, i + 1],
                    direction: x,
                },
                coefficient: self.stiffness,
            })
            .collect();
        let held = |node: usize, dof: usize, value: Option<f64>| BoundaryCondition {
            node,
            dof: Dof::Translation(dof),
            value,
        };
        let ends = [0, n + 1]
            .into_iter()
            .flat_map(|i| [held(i, 0, None), held(i, 1, None)]);
        let mut shaped: Vec<BoundaryCondition> = Vec::with_capacity(2 * n + 4);
        let mut released: Vec<BoundaryCondition> = Vec::with_capacity(n + 4);
        shaped.extend(ends.clone());
        released.extend(ends);
        for i in 1..=n {
            shaped.push(held(i, 0, Some(self.amplitude * self.shape(i))));
            shaped.push(held(i, 1, None));
            released.push(held(i, 1, None));
        }
        let mut columns = Vec::new();
        for (quantity, velocity) in [("u", false), ("v", true)] {
            for (name, i) in self.probes() {
                columns.push(Column {
                    name: format!("{quantity}_{name}"),
                    probe: if velocity {
                        Probe::Velocity {
                            node: i,
                            direction: x,
                        }
                    } else {
                        Probe::Displacement {
                            node: i,
                            direction: x,
                        }
                    },
                });
            }
        }
        Scene {
            id: format!("chain_{n}"),
            title: format!(
                "Chain of {n} masses and springs, fixed at both ends, in mode {}",
                self.mode
            ),
            family: Family::Springs,
            dimension: Dimension::Two,
            nodes,
            bodies: Vec::new(),
            springs,
            dashpots: Vec::new(),
            contacts: Vec::new(),
            loads: Vec::new(),
            initial_velocities: Vec::new(),
            steps: vec![
                Step {
                    kind: StepKind::Static,
                    conditions: shaped,
                },
                Step {
                    kind: StepKind::Dynamic {
                        duration: self.duration(),
                    },
                    conditions: released,
                },
            ],
            output_rows: self.rows,
            columns,
            settings: SceneSettings {
                increment: IncrementRule::Given(self.increment),
                damping: DampingTreatment::Centred,
                penalty: PenaltyRule::Ratio(1.0e4),
                contact_start: ContactStart::Consistent,
            },
            tolerances: Default::default(),
            sweep: false,
        }
    }
}
