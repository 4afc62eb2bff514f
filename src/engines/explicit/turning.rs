//! One rigid body turning about one axis under finite rotation (`explicit`), stepped with its
//! state in locals between output rows.
//!
//! Under finite rotation a body's arms and contact normals turn with it, so its forces are not
//! affine in the motion and [`AffineStep`](super::affine::AffineStep) declines the step. What
//! the general path spends on such a small scene is mostly not arithmetic: it reads the state
//! from the configuration's vectors and writes it back at every increment, clears and sums the
//! force vectors element by element through the points' indices, and walks the time loop's
//! tests. Here a step with one body that turns about one free axis, at most one particle,
//! springs along fixed lines, plane contacts and loads keeps the body's translation,
//! orientation, the particle's displacement and both velocities in locals (registers where
//! the compiler can), and runs the increment one of two ways:
//! - **About the axis** ([`about_axis`]): the body's turn since the batch's start is carried
//!   as a heading about its free axis, each point's lever and turn formed from parts fixed for
//!   the batch, and the body solve on that axis in closed form. The same to round-off: the
//!   body turns by other arithmetic than the general path's. Taken wherever every term turns
//!   with the body: no spring about an axis, at most [`about_axis::MAX_POINTS`] body points.
//! - **As the general path** (otherwise: a spring about an axis reads the body's twist): the
//!   force terms of [`Model::forces_with`] in its order, written out as it writes them (the
//!   plane contacts through the same functions of the model's `Contact`); the same body
//!   solve, with the centred angular rate in closed form where the body's centripetal terms
//!   act ([`Model::centred_single_axis`]); the same projection, compensated sums and
//!   orientation update (with its rounding carry and mass properties), by the same functions.
//!   The general path's bit for bit.
//!
//! Either way the work counters are the general path's (with a counter of their own,
//! `turning_increments`, and `about_axis_increments` for those about the axis), and so are the
//! impacts. `tests/turning.rs` checks every output value of scenes that use every force term,
//! bit for bit, or to round-off up to the first impact after t = 0 (a penalty contact that
//! closes again amplifies a difference in the last bit to the whole contact force), so a change
//! to one path's arithmetic that the other does not follow fails there.
//!
//! A batch runs the increments the affine step's batches run: up to the next output row, the
//! step's last two increments (the last one's acceleration starts the next step) or the next
//! look at the interruption flag (every 4096 increments), whichever comes first. An increment
//! whose centred angular rate has no real value, or (about the axis) whose operator on the axis
//! is not positive and finite, is left to the general path, which reports it.

use super::integrate::note_impacts;
use super::model::{Config, Constraints, Contact, Counters, Model, Point, Rates, centred_rate};
use super::space::{Lin, Space, compensated_add, compensated_add_fused};
use crate::scene::DampingTreatment;

mod about_axis;

/// At most this many contact pairs (their normal forces are kept for the impacts).
pub const MAX_CONTACTS: usize = 4;

/// Where a force term acts, for the one body and the one particle.
#[derive(Debug, Clone, Copy)]
enum End<S: Space> {
    /// A fixed point: it neither moves nor takes force.
    Ground,
    /// The particle.
    Particle,
    /// A material point of the body, by its offset from the reference node at t = 0 and its
    /// index among the step's body points.
    Body {
        /// Offset from the reference node at t = 0 (the body's axes).
        rho: S::V,
        /// Index in [`TurningStep`]'s body points.
        point: usize,
    },
}

/// A grounded spring's term, as [`Model::forces_with`] sums it.
#[derive(Debug, Clone, Copy)]
enum GroundedTerm<S: Space> {
    /// Along a fixed direction, at a moving point (one on the ground takes no force).
    Along {
        /// The particle or the body's point.
        end: End<S>,
        /// Unit direction.
        direction: S::V,
        /// Stiffness.
        c: f64,
    },
    /// About a fixed axis, on the body's rotation.
    About {
        /// Unit axis.
        axis: S::W,
        /// Stiffness.
        c: f64,
    },
}

/// A spring of fixed direction between two ends, the particle's joined to the ground
/// (`LineSpring`) or any two ends (the model's other springs, not axial).
#[derive(Debug, Clone, Copy)]
struct LineTerm<S: Space> {
    a: End<S>,
    b: End<S>,
    direction: S::V,
    c: f64,
}

/// What the time loop hands [`TurningStep::advance`] for one batch: the model and its
/// constraints; the configuration `cfg` (with the orientation's rounding carry), the
/// displacements' rounding carries `carry` and the half-step velocities `v_half`, which the
/// batch advances; the time increment `h`, the index `n` of the batch's first increment and the
/// most increments it may take, `count`; and the contact pairs' states `pressed` and the
/// `impacts`, which it notes.
pub struct Batch<'a, S: Space, const FINITE: bool> {
    /// The model.
    pub model: &'a Model<S, FINITE>,
    /// The step's constraints.
    pub held: &'a Constraints<S>,
    /// The configuration.
    pub cfg: &'a mut Config<S>,
    /// The displacements' rounding carries.
    pub carry: &'a mut Rates<S>,
    /// The half-step velocities.
    pub v_half: &'a mut Rates<S>,
    /// The time increment.
    pub h: f64,
    /// The index of the batch's first increment (at time n·h).
    pub n: u64,
    /// The most increments the batch may take.
    pub count: u64,
    /// Whether each contact pair pressed at the last increment (None before the first).
    pub pressed: &'a mut [Option<bool>],
    /// The impacts' times.
    pub impacts: &'a mut Vec<f64>,
}

/// The increments of a dynamic step with one body turning about one axis, state in locals.
#[derive(Debug, Clone)]
pub struct TurningStep<S: Space> {
    /// Whether the increments carry the turn about the axis since the batch's start
    /// ([`about_axis`]) instead of the general path's orientation (bit for bit).
    about_axis: bool,
    /// The body points the terms act on (offsets from the reference node at t = 0, the body's
    /// axes), indexed by [`End::Body`]'s `point`.
    points: Vec<S::V>,
    /// The body's mass centre relative to its reference node at t = 0 (the body's axes).
    centre: S::V,
    /// The grounded springs' terms, in the model's order.
    grounded: Vec<GroundedTerm<S>>,
    /// Springs of fixed direction whose ends are the particle or the ground (the model's line
    /// springs; the general path sums them before the others).
    line: Vec<LineTerm<S>>,
    /// The model's other springs, all of fixed direction (for the general path; the increments
    /// about the axis take them as `body_springs` and `coupled`).
    other: Vec<LineTerm<S>>,
    /// Plane contact pairs (between the particle and the body's faces).
    planes: Vec<Contact<S>>,
    /// Loads.
    loads: Vec<(End<S>, S::V)>,
    /// The springs of fixed direction between the particle and the ground (direction,
    /// stiffness): the grounded springs along a fixed direction on the particle, then the line
    /// springs with one end on each, in the model's order (for the increments about the axis).
    particle_springs: Vec<(S::V, f64)>,
    /// The springs of fixed direction between a body point and the ground (the point's index,
    /// direction, stiffness): the grounded springs along a fixed direction on a body point,
    /// then the model's other springs with one end on each, in the model's order (for the
    /// increments about the axis).
    body_springs: Vec<(usize, S::V, f64)>,
    /// The springs the increments about the axis sum end by end: the model's other springs
    /// that are not in `body_springs` (the line springs are all in `particle_springs`, or take
    /// no force: both ends on the particle, or on the ground).
    coupled: Vec<LineTerm<S>>,
    /// The particle's 1 / mass, if there is one.
    inverse_mass: f64,
    /// Whether the body's centripetal terms act (its angular rate is then centred in closed
    /// form).
    centred: bool,
    /// Penalty stiffness.
    penalty: f64,
}

/// The translations a batch carries in locals, either way it turns the body: the particle's
/// displacement (with its rounding carry) and half-step velocity, and the body's reference
/// node's.
#[derive(Debug, Clone, Copy)]
struct Translations<S: Space> {
    u: S::V,
    u_carry: S::V,
    v: S::V,
    bu: S::V,
    bu_carry: S::V,
    vb: S::V,
}

impl<S: Space> Translations<S> {
    /// From the configuration, its rounding carries and half-step velocities (the particle's
    /// parts zero where there is none).
    #[inline(always)]
    fn read(particle: bool, cfg: &Config<S>, carry: &Rates<S>, v_half: &Rates<S>) -> Self {
        let at = |x: &[S::V]| if particle { x[0] } else { S::V::zero() };
        Translations {
            u: at(&cfg.u),
            u_carry: at(&carry.p),
            v: at(&v_half.p),
            bu: cfg.bu[0],
            bu_carry: carry.b[0],
            vb: v_half.b[0],
        }
    }

    /// One increment of `h` at the particle's acceleration `a` and the body's `ab`: the
    /// half-step velocities, then the displacements by compensated sums.
    #[inline(always)]
    fn advance(&mut self, a: S::V, ab: S::V, h: f64) {
        self.vb += ab * h;
        self.v += a * h;
        compensated_add(&mut self.u, &mut self.u_carry, self.v * h);
        compensated_add(&mut self.bu, &mut self.bu_carry, self.vb * h);
    }

    /// [`Translations::advance`] with each product fused into the sum it feeds (the
    /// velocities' h·a, the displacements' h·v into Kahan's difference): to round-off the
    /// same, and from the acceleration to the displacements three dependent operations
    /// instead of five.
    #[inline(always)]
    fn advance_fused(&mut self, a: S::V, ab: S::V, h: f64) {
        self.vb = ab.fused(h, self.vb);
        self.v = a.fused(h, self.v);
        compensated_add_fused(&mut self.u, &mut self.u_carry, self.v, h);
        compensated_add_fused(&mut self.bu, &mut self.bu_carry, self.vb, h);
    }

    /// Back into the configuration, its carries and its half-step velocities.
    #[inline(always)]
    fn write(
        &self,
        particle: bool,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        v_half: &mut Rates<S>,
    ) {
        if particle {
            cfg.u[0] = self.u;
            carry.p[0] = self.u_carry;
            v_half.p[0] = self.v;
        }
        cfg.bu[0] = self.bu;
        carry.b[0] = self.bu_carry;
        v_half.b[0] = self.vb;
    }
}

/// The state a batch carries in locals.
struct State<S: Space> {
    t: Translations<S>,
    w: S::W,
    br: S::R,
    br_carry: S::Carry,
}

impl<S: Space> State<S> {
    #[inline(always)]
    fn displacement(&self, end: &End<S>) -> S::V {
        match end {
            End::Ground => S::V::zero(),
            End::Particle => self.t.u,
            End::Body { rho, .. } => self.t.bu + S::turned(&self.br, rho),
        }
    }
}

/// The forces of one increment.
struct Sums<S: Space> {
    p: S::V,
    b: S::V,
    m: S::W,
    contact: [f64; MAX_CONTACTS],
}

impl<S: Space> Sums<S> {
    #[inline(always)]
    fn apply(&mut self, state: &State<S>, end: &End<S>, f: S::V) {
        match end {
            End::Ground => {}
            End::Particle => self.p += f,
            End::Body { rho, .. } => {
                self.b += f;
                self.m += S::moment(&S::rotate(&state.br, rho), &f);
            }
        }
    }
}

impl<S: Space> TurningStep<S> {
    /// The step under `held`, where it qualifies: finite rotation; one body, which turns about
    /// one free axis; at most one particle; springs of fixed direction (grounded, or between
    /// two ends, none axial) and loads; at most [`MAX_CONTACTS`] plane contact pairs without
    /// dashpots; no dashpot and no solid; the centred treatment where the body's centripetal
    /// terms act (either treatment where they do not: without a dashpot or a centripetal term
    /// both take the same increment). None otherwise.
    pub fn of<const FINITE: bool>(
        model: &Model<S, FINITE>,
        held: &Constraints<S>,
        damping: DampingTreatment,
    ) -> Option<Self> {
        if !FINITE
            || model.bodies.len() != 1
            || model.particles.len() > 1
            || !held.rotating[0]
            || held.body_free_r[0].len() != 1
            || model.has_dashpots()
            || model.has_solids()
            || model.contact_count() > MAX_CONTACTS
            || (held.velocity_terms[0] && damping != DampingTreatment::Centred)
        {
            return None;
        }
        let mut points = Vec::new();
        let mut end = |p: &Point<S>| match p {
            Point::Ground(_) => End::Ground,
            Point::Particle(_) => End::Particle,
            Point::Body { rho, .. } => {
                points.push(*rho);
                End::Body {
                    rho: *rho,
                    point: points.len() - 1,
                }
            }
        };
        let mut grounded = Vec::new();
        for s in &model.grounded_springs {
            if let Some(direction) = s.direction
                && !matches!(s.point, Point::Ground(_))
            {
                grounded.push(GroundedTerm::Along {
                    end: end(&s.point),
                    direction,
                    c: s.c,
                });
            }
            if let Some((_, axis)) = s.rotation {
                grounded.push(GroundedTerm::About { axis, c: s.c });
            }
        }
        let ground_or_particle = |i: u32| {
            if i == super::blocks::GROUND {
                End::Ground
            } else {
                End::Particle
            }
        };
        let line: Vec<_> = model
            .line_springs
            .iter()
            .map(|s| LineTerm {
                a: ground_or_particle(s.a),
                b: ground_or_particle(s.b),
                direction: s.direction,
                c: s.c,
            })
            .collect();
        let mut other = Vec::new();
        for s in model.other_springs.iter().map(|k| &model.springs[*k]) {
            if s.axial {
                return None;
            }
            other.push(LineTerm {
                a: end(&s.a),
                b: end(&s.b),
                direction: s.direction,
                c: s.c,
            });
        }
        let planes = model.contacts.clone();
        let loads = model
            .loads
            .iter()
            .map(|l| (end(&l.point), l.force))
            .collect();
        // About the axis where every term turns with the body (a spring about an axis reads
        // the body's twist, which the general path's orientation gives).
        let about_axis = points.len() <= about_axis::MAX_POINTS
            && grounded
                .iter()
                .all(|t| matches!(t, GroundedTerm::Along { .. }));
        // A line spring's force on the particle, d·(c·d·(u_b − u_a)) with the other end on
        // the ground, is the grounded spring's d·(−c·d·u) bit for bit (negation is exact), up
        // to the sign of a zero force.
        let particle_springs = grounded
            .iter()
            .filter_map(|t| match t {
                GroundedTerm::Along {
                    end: End::Particle,
                    direction,
                    c,
                } => Some((*direction, *c)),
                _ => None,
            })
            .chain(line.iter().filter_map(|t: &LineTerm<S>| {
                matches!(
                    (t.a, t.b),
                    (End::Particle, End::Ground) | (End::Ground, End::Particle)
                )
                .then_some((t.direction, t.c))
            }))
            .collect();
        // Likewise a spring between a body point and the ground is a grounded spring on the
        // point (to round-off: the increments about the axis sum a grounded spring's stretch
        // and moment from scalars, [`about_axis`]).
        let on_body_point = |t: &LineTerm<S>| match (t.a, t.b) {
            (End::Body { point, .. }, End::Ground) | (End::Ground, End::Body { point, .. }) => {
                Some(point)
            }
            _ => None,
        };
        let body_springs = grounded
            .iter()
            .filter_map(|t| match t {
                GroundedTerm::Along {
                    end: End::Body { point, .. },
                    direction,
                    c,
                } => Some((*point, *direction, *c)),
                _ => None,
            })
            .chain(
                other
                    .iter()
                    .filter_map(|t| on_body_point(t).map(|point| (point, t.direction, t.c))),
            )
            .collect();
        let coupled = other
            .iter()
            .filter(|t| on_body_point(t).is_none())
            .copied()
            .collect();
        Some(TurningStep {
            about_axis,
            particle_springs,
            body_springs,
            coupled,
            points,
            centre: model.bodies[0].inertia.centre,
            grounded,
            line,
            other,
            planes,
            loads,
            inverse_mass: model.particles.first().map_or(0.0, |p| p.inverse_mass),
            centred: held.velocity_terms[0],
            penalty: model.penalty,
        })
    }

    /// Take up to the [`Batch`]'s `count` increments of `h` from the configuration `cfg`, the
    /// rounding carries `carry` and the half-step velocities `v_half`, and write the state
    /// back; the work counters and the impacts (`pressed`, `impacts`, from increment `n`) as
    /// the general path notes them: about the axis ([`about_axis`]; the same to round-off) or
    /// as the general path takes them (bit for bit), as the module's documentation says.
    /// Returns the increments taken: fewer than `count` only where an increment's centred
    /// angular rate has no real value or its operator on the axis is not positive and finite,
    /// which the general path then reports.
    #[inline]
    pub fn advance<const FINITE: bool>(
        &self,
        batch: Batch<'_, S, FINITE>,
        counters: &mut Counters,
    ) -> u64 {
        let taken = if self.about_axis {
            self.advance_about_axis(batch)
        } else {
            self.advance_as_general(batch)
        };
        counters.force_evaluations += taken;
        counters.contact_evaluations += taken * self.planes.len() as u64;
        counters.body_solves += taken * if self.centred { 2 } else { 1 };
        counters.rotation_updates += taken;
        counters.turning_increments += taken;
        if self.about_axis {
            counters.about_axis_increments += taken;
        }
        taken
    }

    /// [`TurningStep::advance`] by the general path's arithmetic, in its order.
    /// Never inlined: called once per batch, it keeps its own code layout whatever the time
    /// loop around it becomes.
    #[inline(never)]
    fn advance_as_general<const FINITE: bool>(&self, batch: Batch<'_, S, FINITE>) -> u64 {
        let Batch {
            model,
            held,
            h,
            n,
            count,
            ..
        } = batch;
        let particle = !model.particles.is_empty();
        let mut s = State::<S> {
            t: Translations::read(particle, batch.cfg, batch.carry, batch.v_half),
            w: batch.v_half.w[0],
            br: batch.cfg.br[0],
            br_carry: batch.cfg.br_carry[0],
        };
        let mut inertia = batch.cfg.inertia[0];
        let motion = if particle {
            held.motions[held.particle_motion[0] as usize]
        } else {
            super::model::Motion::Held
        };
        let g = held.body_free_r[0][0];
        let contacts = self.planes.len();
        let mut taken = 0;
        while taken < count {
            let mut f = Sums::<S> {
                p: S::V::zero(),
                b: S::V::zero(),
                m: S::W::zero(),
                contact: [0.0; MAX_CONTACTS],
            };
            for term in &self.grounded {
                match term {
                    GroundedTerm::Along { end, direction, c } => {
                        let u = direction.dot(&s.displacement(end));
                        f.apply(&s, end, *direction * (-c * u));
                    }
                    GroundedTerm::About { axis, c } => {
                        let angle = S::twist(&s.br, axis);
                        f.m -= *axis * (c * angle);
                    }
                }
            }
            for term in self.line.iter().chain(&self.other) {
                let stretch = s.displacement(&term.b) - s.displacement(&term.a);
                let e = term.direction.dot(&stretch);
                let force = term.direction * (term.c * e);
                f.apply(&s, &term.a, force);
                f.apply(&s, &term.b, -force);
            }
            for (k, c) in self.planes.iter().enumerate() {
                let relative = s.t.u - s.t.bu;
                let (gap, normal) = c.plane_gap(&s.br, relative);
                let force = self.penalty * (-gap).max(0.0);
                f.contact[k] = force;
                f.p += normal * force;
                f.b -= normal * force;
                f.m -= S::moment(&c.arm(relative), &normal) * force;
            }
            for (end, force) in &self.loads {
                f.apply(&s, end, *force);
            }
            let solve = held.body_solve(&inertia, 0);
            let (ab, aw) = if self.centred {
                let (a0, p) = solve.solve_on_axis(&f.b, &f.m);
                let unit_force = S::cross(&g, &S::cross(&g, &inertia.centre)) * (-inertia.mass);
                let (a1, q) = solve.solve_on_axis(&unit_force, &S::W::zero());
                let beta = 0.5 * h * q;
                let gamma = g.dot(&s.w) + 0.5 * h * p;
                let Some(rate) = centred_rate(beta, gamma) else {
                    break;
                };
                let squared = rate * rate;
                (a0 + a1 * squared, g * (p + q * squared))
            } else {
                solve.solve(&f.b, &f.m)
            };
            note_impacts(
                batch.pressed,
                &f.contact[..contacts],
                (n + taken, h),
                batch.impacts,
            );
            let a = motion.project(f.p * self.inverse_mass);
            s.t.advance(a, ab, h);
            s.w += aw * h;
            let r = S::advance_compensated(&s.br, &mut s.br_carry, &(s.w * h));
            inertia = model.oriented(0, &r);
            s.br = r;
            taken += 1;
        }
        s.t.write(particle, batch.cfg, batch.carry, batch.v_half);
        batch.v_half.w[0] = s.w;
        batch.cfg.br[0] = s.br;
        batch.cfg.br_carry[0] = s.br_carry;
        batch.cfg.inertia[0] = inertia;
        taken
    }
}
