//! The increment of a large scene of particles, springs along fixed lines and loads, block by
//! block of springs ([`Model::step_by_blocks`]), and the one-dimensional store it runs on when
//! every particle of such a scene moves along one coordinate axis ([`AxialStore`]).

#[cfg(doc)]
use super::model::Model;
use super::model::{Constraints, Motion};
use super::space::{Lin, Space, compensated_add};

/// A spring of fixed direction between particles or ground (the bulk of large scenes), in
/// the compact form the force pass streams through.
#[derive(Debug, Clone, Copy)]
pub(super) struct LineSpring<V: Lin> {
    /// Particle at end a, or [`GROUND`] (32 bits: the pass streams 32 bytes per 2D spring).
    pub a: u32,
    /// Particle at end b, or [`GROUND`].
    pub b: u32,
    /// Unit direction (in an [`Axial`] scene, ±1).
    pub direction: V,
    /// Stiffness.
    pub c: f64,
}

/// A [`LineSpring`] end that does not move.
pub(super) const GROUND: u32 = u32::MAX;

/// Particles from which the time loop steps a scene by blocks ([`Model::step_by_blocks`])
/// where it can: about 45 MB of a 2D chain's data, past a 32 MB third-level
/// cache. Measured on the chain of the scaling study in one build, by blocks against the
/// force pass and update: 8 % slower from 10^3 to 10^5 particles, where the data stay in
/// cache and the blocks only add bookkeeping; 22 % faster at 10^6, where the second pass
/// over memory is what they save. A scene on one axis takes its blocks on the one-dimensional
/// store ([`AxialStore`]) at every size: there the blocks were faster than the two passes from
/// 10 particles up (1.7–1.9 ns per particle against 3.1 from 10^3 to 10^5, one session).
pub const BLOCKS_FROM: usize = 1 << 18;

/// Line springs per block of [`Model::step_by_blocks`]: in a chain, a block's springs and the
/// data of the particles it finishes (about 30 kB in 2D) stay in the first-level cache
/// between its forces and its update.
const SPRING_BLOCK: usize = 256;

/// The order in which [`Model::step_by_blocks`] finishes particles, for a scene of particles
/// with springs of fixed direction and loads (nothing else): a particle's force is complete
/// after the last element that loads it, and no later element reads its position, so it can
/// be advanced there, while its data are still in cache. The line springs are taken in
/// blocks of [`SPRING_BLOCK`]; after each block's forces, the particles whose last spring
/// was in it are advanced, as runs of consecutive particles (one run per block in a chain).
#[derive(Debug, Clone)]
pub(super) struct BlockSchedule {
    /// Per block: the end of its springs in the line springs, and of its runs in `runs`.
    blocks: Vec<(u32, u32)>,
    /// Runs of consecutive particles, `start..end`, by block. The last block has no springs:
    /// its runs are the particles finished after the loads, those a load acts on and those
    /// no line spring touches.
    runs: Vec<(u32, u32)>,
}

impl BlockSchedule {
    /// The order for these line springs and the particles that loads act on; every particle
    /// is finished exactly once.
    pub(super) fn of<V: Lin>(
        particles: usize,
        line_springs: &[LineSpring<V>],
        loaded: &[usize],
    ) -> Self {
        // The block of the last line spring to touch each particle (blocks past the last:
        // after the loads).
        let after_loads = line_springs.len().div_ceil(SPRING_BLOCK);
        let mut last = vec![after_loads; particles];
        for (k, s) in line_springs.iter().enumerate() {
            for end in [s.a, s.b] {
                if end != GROUND {
                    last[end as usize] = k / SPRING_BLOCK;
                }
            }
        }
        for i in loaded {
            last[*i] = after_loads;
        }
        let mut by_block: Vec<Vec<u32>> = vec![Vec::new(); after_loads + 1];
        for (i, block) in last.iter().enumerate() {
            by_block[*block].push(i as u32);
        }
        let mut blocks = Vec::with_capacity(after_loads + 1);
        let mut runs: Vec<(u32, u32)> = Vec::new();
        for (b, finished) in by_block.iter().enumerate() {
            let first = runs.len();
            for i in finished {
                match runs[first..].last_mut() {
                    Some((_, end)) if *end == *i => *end += 1,
                    _ => runs.push((*i, *i + 1)),
                }
            }
            let springs = ((b + 1) * SPRING_BLOCK).min(line_springs.len());
            blocks.push((
                u32::try_from(springs).expect("fewer than 2^32 line springs"),
                u32::try_from(runs.len()).expect("fewer than 2^32 runs"),
            ));
        }
        BlockSchedule { blocks, runs }
    }
}

/// Add the forces of line springs at particle displacements `u` to the particle forces `p`;
/// `elastic` with their elastic energy added term by term (unchanged unless `ENERGY`).
#[inline(always)]
pub(super) fn line_spring_forces<V: Lin, const ENERGY: bool>(
    springs: &[LineSpring<V>],
    u: &[V],
    p: &mut [V],
    mut elastic: f64,
) -> f64 {
    for s in springs {
        let at = |i: u32| {
            if i == GROUND {
                V::zero()
            } else {
                u[i as usize]
            }
        };
        let e = s.direction.dot(&(at(s.b) - at(s.a)));
        if ENERGY {
            elastic += 0.5 * s.c * e * e;
        }
        let f = s.direction * (s.c * e);
        if s.a != GROUND {
            p[s.a as usize] += f;
        }
        if s.b != GROUND {
            p[s.b as usize] -= f;
        }
    }
    elastic
}

/// The particles' data [`Model::step_by_blocks`] advances, and how: the arithmetic of
/// [`Model::step`], over runs of particles that share a projection.
pub(super) struct Advance<'a, V: Lin> {
    /// Displacements.
    pub u: &'a mut [V],
    /// Their rounding carries.
    pub carry: &'a mut [V],
    /// Velocities (at half increments).
    pub v: &'a mut [V],
    /// Forces being summed; a particle's is reset to zero once it is advanced.
    pub f: &'a mut [V],
    /// 1 / mass.
    pub inverse: &'a [f64],
    /// The step's runs of particles that share a projection ([`Constraints::motion_runs`]).
    pub motion_runs: &'a [(u32, u32)],
    /// The projections the runs index.
    pub motions: &'a [Motion<V>],
    /// The increment.
    pub h: f64,
}

impl<V: Lin> Advance<'_, V> {
    /// Advance the particles `start..end`, whose forces are complete: one loop per run of
    /// a shared projection, with the projection's kind chosen once per run.
    #[inline(always)]
    fn particles(&mut self, start: usize, end: usize) {
        let mut from = start;
        let first = self
            .motion_runs
            .partition_point(|(e, _)| *e as usize <= start);
        for (run_end, motion) in &self.motion_runs[first..] {
            let to = (*run_end as usize).min(end);
            match self.motions[*motion as usize] {
                Motion::Free => self.run(from, to, |a| a),
                Motion::Held => self.run(from, to, |_| V::zero()),
                Motion::Across(d) => self.run(from, to, |a| a - d * d.dot(&a)),
                motion @ Motion::AcrossTwo(..) => self.run(from, to, |a| motion.project(a)),
            }
            if to == end {
                break;
            }
            from = to;
        }
    }

    /// Advance the particles `start..end`, projected by `project` (the arithmetic of
    /// [`Motion::project`] for their shared motion).
    #[inline(always)]
    fn run(&mut self, start: usize, end: usize, project: impl Fn(V) -> V) {
        let (u, carry, v, f) = (
            &mut self.u[start..end],
            &mut self.carry[start..end],
            &mut self.v[start..end],
            &mut self.f[start..end],
        );
        let inverse = &self.inverse[start..end];
        for i in 0..u.len() {
            let a = project(f[i] * inverse[i]);
            f[i] = V::zero();
            v[i] += a * self.h;
            compensated_add(&mut u[i], &mut carry[i], v[i] * self.h);
        }
    }
}

/// One increment by blocks: a block's line springs add their forces into `advance.f`, then
/// the particles the block finishes are advanced; `loads` adds the loads into the forces
/// before the last block's particles (those a load acts on) are advanced.
#[inline(always)]
pub(super) fn step_blocks<V: Lin>(
    schedule: &BlockSchedule,
    springs: &[LineSpring<V>],
    loads: impl Fn(&mut [V]),
    advance: &mut Advance<V>,
) {
    let mut from_spring = 0;
    let mut from_run = 0;
    for (block, (springs_end, runs_end)) in schedule.blocks.iter().enumerate() {
        let (springs_end, runs_end) = (*springs_end as usize, *runs_end as usize);
        line_spring_forces::<V, false>(
            &springs[from_spring..springs_end],
            advance.u,
            advance.f,
            0.0,
        );
        if block + 1 == schedule.blocks.len() {
            loads(advance.f);
        }
        for (start, end) in &schedule.runs[from_run..runs_end] {
            advance.particles(*start as usize, *end as usize);
        }
        (from_spring, from_run) = (springs_end, runs_end);
    }
}

/// The coordinate axis a direction lies along, if it is a unit coordinate vector exactly (±1
/// on the axis, 0 off it): along it, a 2D or 3D product with the direction is the 1D product
/// with ±1, to the bit.
pub(super) fn axis_of<S: Space>(d: &S::V) -> Option<usize> {
    let d = S::v3(d);
    let on: Vec<usize> = (0..3).filter(|k| d[*k] != 0.0).collect();
    match on[..] {
        [k] if d[k].abs() == 1.0 => Some(k),
        _ => None,
    }
}

/// A scene that steps by blocks whose line springs and grounded springs all lie along one
/// coordinate axis, compiled to that axis: a chain along x, whose particles move along x only,
/// needs one number per particle and quantity, not a 2D or 3D vector with a held component
/// that is always zero.
#[derive(Debug, Clone)]
pub(super) struct Axial {
    /// The coordinate axis (0 = x).
    pub axis: usize,
    /// The line springs, with direction ±1.
    pub springs: Vec<LineSpring<f64>>,
    /// Grounded springs on particles: particle, direction (±1), stiffness.
    pub grounded: Vec<(usize, f64, f64)>,
    /// Loads on particles: particle, component along the axis.
    pub loads: Vec<(usize, f64)>,
    /// Whether every load lies on the axis. Then no force acts off the axis, and a particle
    /// that is free off it but does not move off it at the start never does.
    pub loads_on_axis: bool,
}

/// The particles' displacements, rounding carries, velocities and pending forces of one step
/// along an `Axial` scene's axis, for the increments [`Model::step_axial`] takes.
///
/// The store is loaded from the configuration at the first such increment (and again after
/// each write-back) and written back ([`AxialStore::write_back`]) before anything else reads
/// the configuration. Only the axis's components are kept and written, since nothing changes
/// the others: every spring force lies on the axis; a load off it acts only where the
/// particle's projection removes what lies off the axis (`AxialStore::of`); and the store
/// loads only where no velocity or carry lies off the axis.
#[derive(Debug, Clone)]
pub struct AxialStore {
    axis: usize,
    /// The step's projections along the axis, index for index those of
    /// [`Constraints::motions`]: free along it, or held.
    motions: Vec<Motion<f64>>,
    u: Vec<f64>,
    carry: Vec<f64>,
    v: Vec<f64>,
    /// Zero between increments.
    f: Vec<f64>,
    /// Whether the store holds the current state (loaded and not yet written back).
    loaded: bool,
}

impl AxialStore {
    /// The store for one step of an [`Axial`] scene under `held`, if every particle's
    /// projection keeps its axis component as it is and removes the others (or may keep them
    /// too, where every load lies on the axis), or holds it entirely.
    pub(super) fn of<S: Space>(
        axial: &Axial,
        held: &Constraints<S>,
        particles: usize,
    ) -> Option<Self> {
        let across = |d: &S::V| axis_of::<S>(d).filter(|k| *k != axial.axis).is_some();
        let motions = held
            .motions
            .iter()
            .map(|m| match m {
                Motion::Held => Some(Motion::Held),
                Motion::Free => axial.loads_on_axis.then_some(Motion::Free),
                Motion::Across(d) => {
                    (across(d) && (S::DIM == 2 || axial.loads_on_axis)).then_some(Motion::Free)
                }
                // Held directions are orthonormal: two off the axis are its two others.
                Motion::AcrossTwo(d, e) => (across(d) && across(e)).then_some(Motion::Free),
            })
            .collect::<Option<Vec<_>>>()?;
        Some(AxialStore {
            axis: axial.axis,
            motions,
            u: vec![0.0; particles],
            carry: vec![0.0; particles],
            v: vec![0.0; particles],
            f: vec![0.0; particles],
            loaded: false,
        })
    }

    /// Load the store from the particles' displacements, carries and velocities, unless it
    /// holds the current state already. False (and the store not loaded) where a velocity or
    /// carry has a component off the axis: the particle would move off it.
    pub(super) fn load<S: Space>(&mut self, u: &[S::V], carry: &[S::V], v: &[S::V]) -> bool {
        if self.loaded {
            return true;
        }
        let loaded = match self.axis {
            0 => self.load_axis::<S, 0>(u, carry, v),
            1 => self.load_axis::<S, 1>(u, carry, v),
            _ => self.load_axis::<S, 2>(u, carry, v),
        };
        self.loaded = loaded;
        loaded
    }

    /// Write the axis components back into the particles' displacements, carries and
    /// velocities, if the store holds the current state; it then no longer does.
    pub fn write_back<S: Space>(&mut self, u: &mut [S::V], carry: &mut [S::V], v: &mut [S::V]) {
        if !self.loaded {
            return;
        }
        match self.axis {
            0 => self.write_back_axis::<S, 0>(u, carry, v),
            1 => self.write_back_axis::<S, 1>(u, carry, v),
            _ => self.write_back_axis::<S, 2>(u, carry, v),
        }
        self.loaded = false;
    }

    /// [`AxialStore::load`] along axis `K` (a constant, so that taking the component is a
    /// register move: with the axis a variable it went through memory, and writing the store
    /// back took three times as long as an increment); whether no velocity or carry lies off
    /// the axis (checked in the same pass).
    fn load_axis<S: Space, const K: usize>(
        &mut self,
        u: &[S::V],
        carry: &[S::V],
        v: &[S::V],
    ) -> bool {
        let mut off_axis = false;
        for i in 0..self.u.len() {
            let (x, c, w) = (S::v3(&u[i]), S::v3(&carry[i]), S::v3(&v[i]));
            off_axis |= (0..3).any(|j| j != K && (c[j] != 0.0 || w[j] != 0.0));
            (self.u[i], self.carry[i], self.v[i]) = (x[K], c[K], w[K]);
        }
        !off_axis
    }

    /// [`AxialStore::write_back`] along axis `K`.
    fn write_back_axis<S: Space, const K: usize>(
        &self,
        u: &mut [S::V],
        carry: &mut [S::V],
        v: &mut [S::V],
    ) {
        let set = |x: &mut S::V, y: f64| {
            let mut x3 = S::v3(x);
            x3[K] = y;
            *x = S::v(&x3);
        };
        for i in 0..self.u.len() {
            set(&mut u[i], self.u[i]);
            set(&mut carry[i], self.carry[i]);
            set(&mut v[i], self.v[i]);
        }
    }

    /// One increment by blocks on the store (loaded): the grounded springs, then
    /// [`step_blocks`] with `axial`'s springs and loads.
    pub(super) fn step(
        &mut self,
        axial: &Axial,
        schedule: &BlockSchedule,
        inverse: &[f64],
        motion_runs: &[(u32, u32)],
        h: f64,
    ) {
        for (i, d, c) in &axial.grounded {
            self.f[*i] += d * (-c * (d * self.u[*i]));
        }
        let mut advance = Advance {
            u: &mut self.u,
            carry: &mut self.carry,
            v: &mut self.v,
            f: &mut self.f,
            inverse,
            motion_runs,
            motions: &self.motions,
            h,
        };
        step_blocks(
            schedule,
            &axial.springs,
            |f| {
                for (i, force) in &axial.loads {
                    f[*i] += force;
                }
            },
            &mut advance,
        );
    }
}
