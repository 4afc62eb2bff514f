//! What one element costs per increment, on scenes nobody tuned for: the generated family
//! ([`crate::case::family`]: 1 to 16 bodies, 0 to 16 contacts, 1 to 64 particles, springs and
//! dashpots of every kind, 2D and 3D) and the seed cases, measured the same way, in the same
//! run, with one cost model fitted to the family alone.
//!
//! Per scene, `explicit` runs S and 2S increments at half its own stable increment (a seed
//! case at its own increment), each run repeated and the fastest repeat taken; the marginal
//! time (t₂ − t₁)/S is the cost of one increment with the setup and the output rows taken
//! out. The scene's elements are what an increment visits: free particles, bodies, springs,
//! dashpots, contact pairs and loads.
//!
//! The model, one per dimension, fitted by least squares to the family's points only: a fixed
//! cost per increment, a cost per element of each kind, and a cost per further acceleration
//! pass (where the centred velocity is found by iteration: bodies whose reference is off
//! their centre of mass, dashpots that are not all between particles; the passes are read
//! from the engine's counters) over what each pass visits again. The seed cases are then
//! predicted by the model, not fitted: their measured cost over the prediction says whether
//! a case of one's own costs what the family says.

use crate::case::family::Size;
use crate::engines::explicit::ExplicitEngine;
use crate::engines::{Engine, RunSettings};
use crate::scene::{Attachment, Dimension, IncrementRule, Scene, StepKind};
use std::time::Instant;

/// Increments of the shorter timed run of a scene with one element; a scene of E elements
/// takes `ELEMENT_INCREMENTS / E` (at least [`MIN_STEPS`]), so every run does about the same
/// work.
const ELEMENT_INCREMENTS: f64 = 2.0e6;

/// Fewest increments of the shorter timed run.
const MIN_STEPS: u64 = 2_000;

/// Times each timed run is repeated (the fastest counts: on a shared machine interference
/// only ever adds time).
pub const REPEATS: usize = 5;

/// The generated scenes run at this fraction of the engine's stable increment.
pub const STABLE_FRACTION: f64 = 0.5;

/// Where a measured scene comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// A seed case (predicted by the model, not fitted).
    Seed,
    /// A scene of the generated family (fitted).
    Generated,
}

/// What an increment visits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Elements {
    /// Free nodes with a mass.
    pub particles: usize,
    /// Rigid bodies.
    pub bodies: usize,
    /// Springs.
    pub springs: usize,
    /// Dashpots.
    pub dashpots: usize,
    /// Contact pairs.
    pub contacts: usize,
    /// Point loads.
    pub loads: usize,
}

impl Elements {
    /// The scene's elements.
    pub fn of(scene: &Scene) -> Self {
        Elements {
            particles: scene
                .nodes
                .iter()
                .filter(|n| n.mass > 0.0 && n.attachment == Attachment::Free)
                .count(),
            bodies: scene.bodies.len(),
            springs: scene.springs.len(),
            dashpots: scene.dashpots.len(),
            contacts: scene.contacts.len(),
            loads: scene.loads.len(),
        }
    }

    /// All of them.
    pub fn total(&self) -> usize {
        self.particles + self.bodies + self.springs + self.dashpots + self.contacts + self.loads
    }

    /// What each acceleration pass visits: particles and bodies.
    pub fn moving(&self) -> usize {
        self.particles + self.bodies
    }
}

/// One measured scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Case id.
    pub case: String,
    /// Seed case or generated.
    pub origin: Origin,
    /// 2D or 3D.
    pub dimension: Dimension,
    /// What an increment visits.
    pub elements: Elements,
    /// The increment the runs took, s.
    pub increment: f64,
    /// Increments of the shorter run.
    pub steps: u64,
    /// Acceleration passes per increment (body or particle acceleration sweeps, from the
    /// engine's counters).
    pub passes: f64,
    /// Marginal wall time per increment, ns.
    pub ns_per_increment: f64,
}

impl Point {
    /// ns per element and increment.
    pub fn ns_per_element(&self) -> f64 {
        self.ns_per_increment / self.elements.total() as f64
    }
}

/// The terms of the cost model, in order: a fixed cost per increment, one per body and one per
/// force element (springs, dashpots, contact pairs and loads alike: each is one entry of a
/// force pass; a particle's own update is carried by the elements it brings, since every
/// particle of the family brings two springs, so no separate particle term can be told from
/// theirs), and for each further acceleration pass a fixed cost and one per particle, body
/// and dashpot it visits again.
pub const TERMS: [&str; 5] = [
    "increment",
    "body",
    "spring, dashpot, contact or load",
    "further pass",
    "further pass, per particle, body or dashpot",
];

/// The cost model of one dimension: ns per increment = Σ coefficient × count over [`TERMS`].
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// 2D or 3D.
    pub dimension: Dimension,
    /// ns per unit of each term of [`TERMS`].
    pub coefficients: [f64; 5],
}

impl Model {
    /// The counts a point has of each term.
    pub fn counts(p: &Point) -> [f64; 5] {
        let e = &p.elements;
        [
            1.0,
            e.bodies as f64,
            (e.springs + e.dashpots + e.contacts + e.loads) as f64,
            p.passes - 1.0,
            (p.passes - 1.0) * (e.moving() + e.dashpots) as f64,
        ]
    }

    /// The predicted ns per increment of a point.
    pub fn predict(&self, p: &Point) -> f64 {
        Self::counts(p)
            .iter()
            .zip(&self.coefficients)
            .map(|(n, c)| n * c)
            .sum()
    }

    /// Least squares over the points of `dimension`, each row divided by its measured time
    /// (the fit minimises relative error: a 50 ns scene counts as much as a 5 µs one). None
    /// with fewer points than terms or a rank-deficient system.
    pub fn fit(points: &[&Point], dimension: Dimension) -> Option<Model> {
        let rows: Vec<&&Point> = points.iter().filter(|p| p.dimension == dimension).collect();
        if rows.len() < TERMS.len() {
            return None;
        }
        let design = nalgebra::DMatrix::from_fn(rows.len(), TERMS.len(), |i, j| {
            Self::counts(rows[i])[j] / rows[i].ns_per_increment
        });
        let ones = nalgebra::DVector::from_element(rows.len(), 1.0);
        let solution = design.svd(true, true).solve(&ones, 1e-12).ok()?;
        let mut coefficients = [0.0; 5];
        coefficients.copy_from_slice(solution.as_slice());
        Some(Model {
            dimension,
            coefficients,
        })
    }
}

/// The study's outcome.
#[derive(Debug, Clone)]
pub struct Study {
    /// Every measured scene, the family first.
    pub points: Vec<Point>,
    /// The models fitted to the family, 2D and 3D.
    pub models: Vec<Model>,
}

impl Study {
    /// The model of a dimension.
    pub fn model(&self, dimension: Dimension) -> Option<&Model> {
        self.models.iter().find(|m| m.dimension == dimension)
    }

    /// Measured over predicted, per point.
    pub fn ratios(&self) -> impl Iterator<Item = (&Point, f64)> {
        self.points.iter().filter_map(|p| {
            let model = self.model(p.dimension)?;
            Some((p, p.ns_per_increment / model.predict(p)))
        })
    }

    /// The largest factor by which a point of `origin` is off the model, either way.
    pub fn worst_factor(&self, origin: Origin) -> f64 {
        self.ratios()
            .filter(|(p, _)| p.origin == origin)
            .map(|(_, r)| r.max(1.0 / r))
            .fold(1.0, f64::max)
    }
}

/// The family's sizes: bodies 1, 4, 16 × contacts 0, 4, 16 × particles 1, 16, 64 (contacts
/// at most the particles), with and without forces that read the bodies' velocity, in 2D and
/// 3D.
pub fn family() -> Vec<Size> {
    let mut sizes = Vec::new();
    for dimension in [Dimension::Two, Dimension::Three] {
        for bodies in [1, 4, 16] {
            for particles in [1, 16, 64] {
                for contacts in [0, 4, 16] {
                    for body_velocity in [false, true] {
                        if contacts <= particles {
                            sizes.push(Size {
                                dimension,
                                bodies,
                                contacts,
                                particles,
                                body_velocity,
                            });
                        }
                    }
                }
            }
        }
    }
    sizes
}

/// Run the study on the family and on `seeds`; `progress` is told each scene's id as it
/// starts.
pub fn study(seeds: &[Scene], mut progress: impl FnMut(&str)) -> Result<Study, String> {
    let engine = ExplicitEngine::finite();
    let mut points = Vec::new();
    for size in family() {
        let scene = size.scene()?;
        progress(&scene.id);
        let stable = engine
            .stable_increment(&scene, &RunSettings::default())
            .ok_or_else(|| format!("{}: no stable increment", scene.id))?;
        let h = STABLE_FRACTION * stable.increment;
        points.push(measure(&engine, &scene, h, Origin::Generated)?);
    }
    for scene in seeds {
        crate::interrupt::checkpoint("cost").map_err(|_| "interrupted".to_string())?;
        progress(&scene.id);
        let IncrementRule::Given(h) = scene.settings.increment else {
            continue;
        };
        points.push(measure(&engine, scene, h, Origin::Seed)?);
    }
    let fitted: Vec<&Point> = points
        .iter()
        .filter(|p| p.origin == Origin::Generated)
        .collect();
    let models = [Dimension::Two, Dimension::Three]
        .into_iter()
        .map(|d| Model::fit(&fitted, d).ok_or("the cost model cannot be fitted"))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Study { points, models })
}

/// `scene` with its last dynamic step lasting `steps` increments of `h`.
fn lasting(scene: &Scene, h: f64, steps: u64) -> Scene {
    let mut scene = scene.clone();
    if let Some(step) = scene
        .steps
        .iter_mut()
        .rev()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
    {
        step.kind = StepKind::Dynamic {
            duration: h * steps as f64,
        };
    }
    scene
}

/// Measure `engine` on `scene` at increment `h`.
pub fn measure(
    engine: &dyn Engine,
    scene: &Scene,
    h: f64,
    origin: Origin,
) -> Result<Point, String> {
    crate::interrupt::checkpoint("cost").map_err(|_| "interrupted".to_string())?;
    let elements = Elements::of(scene);
    let steps = ((ELEMENT_INCREMENTS / elements.total() as f64) as u64).max(MIN_STEPS);
    let settings = RunSettings {
        increment: Some(IncrementRule::Exact(h)),
        ..RunSettings::default()
    };
    let timed = |steps: u64| -> Result<(f64, crate::engines::RunOutput), String> {
        let scene = lasting(scene, h, steps);
        let mut best = f64::INFINITY;
        let mut output = None;
        for _ in 0..REPEATS {
            let start = Instant::now();
            let run = engine
                .run(&scene, &settings)
                .map_err(|e| format!("{} on {}: {e}", engine.name(), scene.id))?;
            best = best.min(start.elapsed().as_secs_f64());
            output = Some(run);
        }
        Ok((best, output.expect("at least one repeat")))
    };
    let (short, _) = timed(steps)?;
    let (long, output) = timed(2 * steps)?;
    let solves = output
        .info
        .counters
        .get("body_solves")
        .copied()
        .unwrap_or(0) as f64;
    let increments = output.info.steps.max(1) as f64;
    // Body solves per increment and body: the acceleration passes (one where no velocity is
    // iterated; particles are swept in the same passes).
    let passes = if elements.bodies > 0 {
        (solves / increments / elements.bodies as f64).max(1.0)
    } else {
        1.0
    };
    Ok(Point {
        case: scene.id.clone(),
        origin,
        dimension: scene.dimension,
        elements,
        increment: h,
        steps,
        passes,
        ns_per_increment: (long - short).max(0.0) * 1e9 / steps as f64,
    })
}
