//! The turning step's increments about the body's one free axis g: its turn since the batch's
//! start carried as a heading about g, the orientation written back once per batch.
//!
//! A body turning about a fixed axis g is at R(θ) = Rot(g, θ)·R₀ after turning θ from its
//! orientation R₀ at the batch's start, so each of its vectors ρ is at
//! R(θ)ρ = a + (cos θ − 1)·a⊥ + sin θ·(g × a), with a = R₀ρ and a⊥ = −g × (g × a) its part
//! across g ([`Arm`]). With a, a⊥ and g × a formed once per batch, turning a 3D point takes 6
//! products instead of the general path's 9 (R − 1 applied to ρ), and the moment about g of a
//! force f at the point is f·(g × Rρ) = f·((1 + v)·(g × a) − s·a⊥) instead of a cross product
//! and a projection. The general path's quaternion update (about 60 flops), its R − 1 (about
//! 20) and its mass centre's turn give way to the planar heading's update about g (the
//! versine v and sine s, with their carries, as a 2D body's) and three products per
//! coordinate. On the one free axis the body solve is closed: g·I g does not change as the
//! body turns about g, and the drag w = P(g × Rρ_c) of the mass centre Rρ_c (P the projection
//! onto the free translations) is (1 + v)·P(g × a_c) − s·P(a_c⊥), so the operator
//! g·I g − m·w·w costs a few products and a division. In 2D (g = z, a⊥ = a) the turn costs
//! what the general path's does; what the step saves there is the body solve's and the mass
//! properties' bookkeeping.
//!
//! More is formed once per batch so that an increment does scalar arithmetic where the general
//! path does vector arithmetic, and loops over its terms without a match on their kind:
//! - the fixed direction d of a spring to the ground or of a load, on its body point
//!   ([`Along`]): the stretch d·(R − 1)ρ and the moment arm d·(g × Rρ) are affine in (v, s),
//!   from three scalars, and so is the arm less d·w, the force's part of the solve's
//!   numerator (moment − force·w, w the drag below, [`Along::less_drag`]);
//! - the mass centre's drag: |w|² and the centripetal unit force's dot with w are quadratic
//!   forms in (cos θ, sin θ) with three coefficients (P is symmetric and idempotent), and the
//!   unit force's free part is linear in them; the operator g·I g − m|w|² is a polynomial in
//!   (cos θ − 1, sin θ) with six;
//! - the loads summed into one force on each end and one moment arm (their forces are fixed);
//!   the springs to the ground (grounded, line and two-point) are sorted by what they act on
//!   (a body point or the particle) once per step, in [`TurningStep::of`].
//!
//! And per increment, h·(g·I g − m w·w)⁻¹, h²·(…)⁻¹ and (h/2)·(…)⁻¹ are formed from the
//! heading while the forces are summed, so that the solve's numerator reaches the rate and the
//! turn h·rate (advanced side by side, the heading from the latter) in two operations each.
//! Each force of a fixed direction on the body enters the numerator as one product and one sum
//! (a contact pair's last, its normal force being the increment's latest value), not through
//! the body's summed force and its dot with w (the springs with other ends are summed first);
//! the operator's test (positive and finite) is a branch, not a select, so the inverse does not
//! wait for it.
//!
//! Where the centripetal terms act, the centred rate enters only squared, and
//! [`centred_square_factor`] forms the factor C(z)² that turns γ² into its square, from the
//! series of C(z)².
//!
//! Where a product feeds a sum whose other term is ready first, the two are one fused
//! multiply-add (`mul_add`, rounded once): the moments into the solve's numerator, the
//! centred rate, the rate and the turn, the forces along the contact's normal, the
//! projections onto the free translations, the operator on the axis (as
//! (c₀ + s·(o_s + o_ss·s)) + v·((o_v + o_vs·s) + o_vv·v)), the velocities' and the
//! displacements' increments ([`Translations::advance_fused`]) and the heading's series
//! ([`Heading::advanced_fused`]). On this path's chain of dependent operations a fused step
//! takes the latency of a product alone (4 cycles on current x86 cores) where a product and
//! a sum take 6 to 8. A sum of two products that arrive together stays unfused: fusing it
//! would put the products one after the other.
//!
//! The arithmetic is the general path's to round-off, not bit for bit: `tests/turning.rs`
//! holds the two paths together within bounds that follow from the round-off and the
//! penalty's leverage. At the batch's end the heading's angle θ turns R₀ by the general path's
//! own compensated update, so the quaternion keeps its rounding carry.

use super::super::integrate::note_impacts;
use super::super::model::{Motion, centred_square_factor};
use super::super::space::{Heading, Lin, Space, pivot_reciprocal, project};
use super::{Batch, End, MAX_CONTACTS, Translations, TurningStep};

/// At most this many body points in the step's terms (their [`Arm`]s are formed per batch, in
/// a fixed array).
pub const MAX_POINTS: usize = 8;

/// A body vector ρ (the body's axes) at the batch's start orientation R₀, split about the
/// axis g: turned a further θ about g it is R(θ)ρ = `at` + v·`across` + s·`around`, with
/// v = cos θ − 1 and s = sin θ.
#[derive(Debug, Clone, Copy)]
struct Arm<S: Space> {
    /// R₀ρ − ρ, the start's turn, from R₀ − 1 (small parts where R₀ is near 1).
    turned: S::V,
    /// a = R₀ρ.
    at: S::V,
    /// a⊥ = −g × (g × a), the part of a across g.
    across: S::V,
    /// g × a.
    around: S::V,
}

impl<S: Space> Arm<S> {
    fn zero() -> Self {
        Arm {
            turned: S::V::zero(),
            at: S::V::zero(),
            across: S::V::zero(),
            around: S::V::zero(),
        }
    }

    /// ρ at `r0`, about the unit axis `g`.
    fn new(r0: &S::R, g: &S::W, rho: &S::V) -> Self {
        let at = S::rotate(r0, rho);
        let around = S::cross(g, &at);
        Arm {
            turned: S::turned(r0, rho),
            at,
            across: -S::cross(g, &around),
            around,
        }
    }

    /// (R − 1)ρ at the heading (v, s) since the batch's start.
    #[inline(always)]
    fn turned(&self, v: f64, s: f64) -> S::V {
        self.turned + (self.across * v + self.around * s)
    }

    /// Rρ at the heading (v, s).
    #[inline(always)]
    fn rotated(&self, v: f64, s: f64) -> S::V {
        self.at + (self.across * v + self.around * s)
    }

    /// g × Rρ at the heading (c = 1 + v, s): the moment about g of a unit force f at the point
    /// is f·(g × Rρ).
    #[inline(always)]
    fn lever(&self, c: f64, s: f64) -> S::V {
        self.around * c - self.across * s
    }
}

/// A fixed direction d (a spring's to the ground, or a load's force) on a body point's [`Arm`], as
/// scalars: d·(R − 1)ρ = `turned` + v·`across` + s·`around` and d·(g × Rρ) =
/// c·`around` − s·`across` (c = 1 + v), so the term's stretch and moment cost a few scalar
/// products instead of turning the point and two dot products.
#[derive(Debug, Clone, Copy, Default)]
struct Along {
    /// d·(R₀ − 1)ρ.
    turned: f64,
    /// d·a⊥.
    across: f64,
    /// d·(g × a).
    around: f64,
}

impl Along {
    fn new<S: Space>(arm: &Arm<S>, d: &S::V) -> Self {
        Along {
            turned: d.dot(&arm.turned),
            across: d.dot(&arm.across),
            around: d.dot(&arm.around),
        }
    }

    /// d·(R − 1)ρ at the heading (v, s).
    #[inline(always)]
    fn turned(&self, v: f64, s: f64) -> f64 {
        self.turned + (self.across * v + self.around * s)
    }

    /// This direction's scalars with the part d·drag = c·`around_drag` − s·`across_drag` taken
    /// from the arm, `around_drag` = d·d_r and `across_drag` = d·d_x: [`Along::lever`] then
    /// gives the force d's part of the solve's numerator, moment − force·drag.
    fn less_drag(self, around_drag: f64, across_drag: f64) -> Self {
        Along {
            turned: self.turned,
            across: self.across - across_drag,
            around: self.around - around_drag,
        }
    }

    /// d·(g × Rρ) at the heading (c = 1 + v, s): the moment about g of the force d at the
    /// point.
    #[inline(always)]
    fn lever(&self, c: f64, s: f64) -> f64 {
        self.around * c - self.across * s
    }
}

/// A plane contact pair's face at the batch's start: its normal's and its face point's
/// [`Arm`]s, and the node's offset from the face point and from the reference node at t = 0
/// (the model's `Contact`, as an increment reads it).
#[derive(Debug, Clone, Copy)]
struct Face<S: Space> {
    /// The outward normal's arm.
    normal: Arm<S>,
    /// The face point's arm.
    point: Arm<S>,
    /// From the face point to the node at t = 0.
    offset: S::V,
    /// From the reference node to the node at t = 0.
    arm0: S::V,
}

impl<S: Space> Face<S> {
    fn zero() -> Self {
        Face {
            normal: Arm::zero(),
            point: Arm::zero(),
            offset: S::V::zero(),
            arm0: S::V::zero(),
        }
    }
}

/// The state a batch carries in locals: the particle's displacement and velocity, the body's
/// translation and velocity, its angular rate about g and its heading since the batch's start.
struct State<S: Space> {
    t: Translations<S>,
    rate: f64,
    heading: Heading,
    heading_carry: [f64; 2],
}

/// The forces of one increment: on the particle and on the body (for the translations; the
/// body's moment about g goes into the solve's numerator directly).
struct Sums<S: Space> {
    p: S::V,
    b: S::V,
}

impl<S: Space> TurningStep<S> {
    /// [`TurningStep::advance`] with the turn about the axis since the batch's start (see the
    /// module's documentation). On an x86-64 processor with AVX and FMA the same increments
    /// are compiled a second time with AVX's three-operand instructions, which drop the
    /// register copies that SSE2's two-operand forms need, and FMA's fused multiply-adds, and
    /// with AVX-512 (foundation and 128-bit forms) a third time, for its 32 vector registers
    /// where AVX has 16: the increment's parts fixed for the batch (arms, faces, the
    /// operator's coefficients) then stay in registers instead of being reloaded from the
    /// stack. The arithmetic, and so every result, is the same bit for bit: Rust neither fuses
    /// nor reorders floating-point operations, and the multiply-adds fused here (`mul_add`)
    /// are rounded once on every path (without FMA, by the C library's `fma`, which is slower
    /// but exact in the same way).
    #[inline(never)]
    pub(super) fn advance_about_axis<const FINITE: bool>(
        &self,
        batch: Batch<'_, S, FINITE>,
    ) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("f16c")
        {
            // SAFETY: the processor has AVX-512's foundation and its 128-bit forms, and the
            // operating system saves their registers, as `is_x86_feature_detected!` checked just
            // above, with AVX2, FMA and F16C, which enabling `avx512f` also enables in the
            // callee; it needs nothing else.
            return unsafe { self.about_axis_with_avx512(batch) };
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the processor has AVX and FMA and the operating system saves their
            // registers, as `is_x86_feature_detected!` checked just above; the callee needs
            // nothing else.
            return unsafe { self.about_axis_with_avx(batch) };
        }
        self.step_about_axis_shaped(batch)
    }

    /// [`TurningStep::step_about_axis`] compiled for AVX, with FMA's fused multiply-adds.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,fma")]
    fn about_axis_with_avx<const FINITE: bool>(&self, batch: Batch<'_, S, FINITE>) -> u64 {
        self.step_about_axis_shaped(batch)
    }

    /// [`TurningStep::step_about_axis`] compiled for AVX-512 (32 vector registers).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl")]
    fn about_axis_with_avx512<const FINITE: bool>(&self, batch: Batch<'_, S, FINITE>) -> u64 {
        self.step_about_axis_shaped(batch)
    }

    /// [`TurningStep::step_about_axis`] compiled for the batch's shape: whether the body's
    /// translations are all held (`PINNED`), whether its mass centre is off its reference node
    /// with a translation free (`OFF_CENTRE`: the solve on the axis then drags the
    /// translations), and whether its centripetal terms act (`CENTRED`). Fixed for a batch, these
    /// choose among the increment's branches; as constants they leave none of those tests in
    /// the increment.
    #[inline(always)]
    fn step_about_axis_shaped<const FINITE: bool>(&self, batch: Batch<'_, S, FINITE>) -> u64 {
        let pinned = batch.held.body_held_t[0].len() == S::DIM;
        let off_centre = !pinned && self.centre != S::V::zero();
        match (pinned, off_centre, self.centred) {
            (true, _, false) => self.step_about_axis::<FINITE, true, false, false>(batch),
            (true, _, true) => self.step_about_axis::<FINITE, true, false, true>(batch),
            (false, false, false) => self.step_about_axis::<FINITE, false, false, false>(batch),
            (false, false, true) => self.step_about_axis::<FINITE, false, false, true>(batch),
            (false, true, false) => self.step_about_axis::<FINITE, false, true, false>(batch),
            (false, true, true) => self.step_about_axis::<FINITE, false, true, true>(batch),
        }
    }

    /// The increments of [`TurningStep::advance_about_axis`], for a batch of the shape
    /// [`TurningStep::step_about_axis_shaped`] names.
    #[inline(always)]
    fn step_about_axis<
        const FINITE: bool,
        const PINNED: bool,
        const OFF_CENTRE: bool,
        const CENTRED: bool,
    >(
        &self,
        batch: Batch<'_, S, FINITE>,
    ) -> u64 {
        let Batch {
            model,
            held,
            cfg,
            carry,
            v_half,
            h,
            n,
            count,
            pressed,
            impacts,
        } = batch;
        let g = held.body_free_r[0][0];
        let r0 = cfg.br[0];
        let start = cfg.inertia[0];
        let mut arms = [Arm::<S>::zero(); MAX_POINTS];
        for (arm, rho) in arms.iter_mut().zip(&self.points) {
            *arm = Arm::new(&r0, &g, rho);
        }
        let mut faces = [Face::<S>::zero(); MAX_CONTACTS];
        for (face, c) in faces.iter_mut().zip(&self.planes) {
            *face = Face {
                normal: Arm::new(&r0, &g, &c.normal),
                point: Arm::new(&r0, &g, &c.face),
                offset: c.arm0 - c.face,
                arm0: c.arm0,
            };
        }
        let faces = &faces[..self.planes.len()];
        // The body solve on the one free axis (`BodySolve::solve_on_axis`, closed): g·I g as
        // the body turns about g, the mass centre's drag through the free translations.
        let held_t = &held.body_held_t[0][..];
        let pinned = PINNED;
        debug_assert_eq!(pinned, held_t.len() == S::DIM);
        let mass = start.mass;
        let axial = start.axial(&g);
        let centre = Arm::<S>::new(&r0, &g, &self.centre);
        let off_centre = OFF_CENTRE;
        debug_assert_eq!(off_centre, !pinned && self.centre != S::V::zero());
        let (drag_around, drag_across) = (
            project(held_t, centre.around),
            project(held_t, centre.across),
        );
        // With P the projection onto the free translations, d_r = P(g × a_c) and
        // d_x = P(a_c⊥): the drag is c·d_r − s·d_x, so |drag|² and the centripetal unit
        // force's m(c·a_c⊥ + s·(g × a_c))·drag are quadratic forms in (c, s) (P symmetric and
        // idempotent), and the unit force's P/m is c·d_x + s·d_r.
        let (rr, xx, rx) = (
            drag_around.dot(&drag_around),
            drag_across.dot(&drag_across),
            drag_around.dot(&drag_across),
        );
        // The springs to the ground sorted by what they act on ([`TurningStep::of`]) and the
        // loads summed, so that an increment loops over each kind without a match: a spring on
        // a body point with its direction d as scalars ([`Along`]; each body point is one
        // term's end), a spring on the particle, and the loads summed once (their forces are
        // fixed, and the moment of a load on a body point is linear in (c, s): the loads'
        // [`Along`]s add their `across` and `around` into one; a load has no stretch, so
        // `turned` stays 0).
        //
        // A force f on the body enters the solve's numerator, moment − force·drag, as
        // f·(g × Rρ) − f·drag. The drag c·d_r − s·d_x is linear in (c, s) as the moment arm
        // is, so for a fixed direction d its part d·drag folds into the arm's coefficients once
        // per batch ([`Along::less_drag`]), and a body term enters the numerator as one product
        // and one sum: the body's force, summed for the translations, is not on the way from
        // the heading to the next one.
        let less_drag = |along: Along, d: &S::V| {
            if OFF_CENTRE {
                along.less_drag(d.dot(&drag_around), d.dot(&drag_across))
            } else {
                along
            }
        };
        let mut body_springs =
            [(Along::default(), Along::default(), S::V::zero(), 0.0); MAX_POINTS];
        for (spring, (point, direction, c)) in body_springs.iter_mut().zip(&self.body_springs) {
            let along = Along::new(&arms[*point], direction);
            *spring = (along, less_drag(along, direction), *direction, *c);
        }
        let body_springs = &body_springs[..self.body_springs.len()];
        let (mut load_on_particle, mut load_on_body) = (S::V::zero(), S::V::zero());
        let mut load_lever = Along::default();
        for (end, force) in &self.loads {
            match end {
                End::Ground => {}
                End::Particle => load_on_particle += *force,
                End::Body { point, .. } => {
                    load_on_body += *force;
                    let along = Along::new(&arms[*point], force);
                    load_lever.across += along.across;
                    load_lever.around += along.around;
                }
            }
        }
        let load_lever = less_drag(load_lever, &load_on_body);
        // The operator g·I g − m|drag|² as a polynomial in (v, s), c = 1 + v: its constant
        // g·I g − m·rr, its linear part −2m(rr·v − rx·s), its quadratic part
        // −m(rr·v² − 2rx·vs + xx·s²); from the heading it takes three dependent fused steps
        // (in the loop) where forming c and its square first takes seven.
        let operator_at_start = axial - mass * rr;
        let (operator_v, operator_s) = (-2.0 * mass * rr, 2.0 * mass * rx);
        let (operator_vv, operator_vs, operator_ss) = (-mass * rr, 2.0 * mass * rx, -mass * xx);
        let fixed_inverse = pivot_reciprocal(axial);
        if !off_centre && fixed_inverse.is_nan() {
            // The operator on the axis is not positive and finite (fixed for the batch): the
            // first increment is left to the general path, which reports it.
            return 0;
        }
        let particle = !model.particles.is_empty();
        let w0 = v_half.w[0];
        let rate0 = g.dot(&w0);
        let mut s = State::<S> {
            t: Translations::read(particle, cfg, carry, v_half),
            rate: rate0,
            heading: Heading::IDENTITY,
            heading_carry: [0.0; 2],
        };
        let motion = if particle {
            held.motions[held.particle_motion[0] as usize]
        } else {
            Motion::Held
        };
        let contacts = self.planes.len();
        let mut taken = 0;
        while taken < count {
            let (v, sine) = (s.heading.versine(), s.heading.sin());
            let cosine = 1.0 + v;
            let displacement = |end: &End<S>, s: &State<S>| match end {
                End::Ground => S::V::zero(),
                End::Particle => s.t.u,
                End::Body { point, .. } => s.t.bu + arms[*point].turned(v, sine),
            };
            let mut f = Sums::<S> {
                p: load_on_particle,
                b: load_on_body,
            };
            let drag = if off_centre {
                drag_around * cosine - drag_across * sine
            } else {
                S::V::zero()
            };
            // The solve's numerator, moment − force·drag (above), from the loads on.
            let mut num = load_lever.lever(cosine, sine);
            let lever = |end: &End<S>| match end {
                End::Body { point, .. } => arms[*point].lever(cosine, sine),
                _ => S::V::zero(),
            };
            for (d, numerator, direction, c) in body_springs {
                let u = direction.dot(&s.t.bu) + d.turned(v, sine);
                let tension = -c * u;
                f.b += *direction * tension;
                num = tension.mul_add(numerator.lever(cosine, sine), num);
            }
            for (direction, c) in &self.particle_springs {
                f.p += *direction * (-c * direction.dot(&s.t.u));
            }
            if !self.coupled.is_empty() {
                // Springs of other ends: each end's force added to the particle's or the body's
                // and its moment to the numerator as it comes (the general path's order); on an
                // off-centre body their force's dot with the drag once, from its sum.
                let mut on_body = S::V::zero();
                for term in &self.coupled {
                    let stretch = displacement(&term.b, &s) - displacement(&term.a, &s);
                    let force = term.direction * (term.c * term.direction.dot(&stretch));
                    for (end, force) in [(&term.a, force), (&term.b, -force)] {
                        match end {
                            End::Ground => {}
                            End::Particle => f.p += force,
                            End::Body { .. } => {
                                f.b += force;
                                num += force.dot(&lever(end));
                                on_body += force;
                            }
                        }
                    }
                }
                if off_centre {
                    num -= on_body.dot(&drag);
                }
            }
            // The contact pairs' normal forces (for the impacts).
            let mut normal_forces = [0.0; MAX_CONTACTS];
            for (k, face) in faces.iter().enumerate() {
                // `Contact::plane_gap` and `Contact::arm`, with the normal and the face point
                // turned by the heading.
                let relative = s.t.u - s.t.bu;
                let turned_normal = face.normal.rotated(v, sine);
                let gap =
                    turned_normal.dot(&((face.offset + relative) - face.point.turned(v, sine)));
                // The general path's moment −g·(arm × n) of the unit normal force, as
                // arm·(g × n); with the push −n on the body, the pair's part of the numerator
                // per unit force is that moment plus n·drag.
                let moment = (face.arm0 + relative).dot(&face.normal.lever(cosine, sine));
                let leverage = if off_centre {
                    moment + turned_normal.dot(&drag)
                } else {
                    moment
                };
                let force = self.penalty * (-gap).max(0.0);
                normal_forces[k] = force;
                f.p = turned_normal.fused(force, f.p);
                f.b = turned_normal.fused(-force, f.b);
                num = leverage.mul_add(force, num);
            }
            let (cc, cs, ss) = (cosine * cosine, cosine * sine, sine * sine);
            let inverse = if off_centre {
                // In fused steps: (c₀ + s·(o_s + o_ss·s)) + v·((o_v + o_vs·s) + o_vv·v).
                let on_sine = operator_ss
                    .mul_add(sine, operator_s)
                    .mul_add(sine, operator_at_start);
                let on_versine = operator_vv.mul_add(v, operator_vs.mul_add(sine, operator_v));
                let operator = on_versine.mul_add(v, on_sine);
                let inverse = 1.0 / operator;
                // `pivot_reciprocal`'s test (positive and finite) as a branch, not a select:
                // the inverse then does not wait for the test on its way to the next heading.
                // An increment whose operator fails it is left to the general path, which
                // reports it.
                if !((operator > 0.0) & (inverse > 0.0)) {
                    break;
                }
                inverse
            } else {
                fixed_inverse
            };
            // The solve on g: α = (moment − force·drag)·inverse, the drag 0 where the mass
            // centre is on the reference node or the body is pinned; the translations'
            // acceleration from α.
            let translation = |force: &S::V, alpha: f64| {
                if pinned {
                    S::V::zero()
                } else {
                    drag.fused(-alpha, project_fused(held_t, *force) * (1.0 / mass))
                }
            };
            // h·inverse and h²·inverse depend only on the heading: formed while the forces
            // are summed, they take a product each off the chain from the moment to the next
            // heading. The rate and its increment h·rate are advanced side by side (the
            // heading from the latter), each to round-off.
            let (h_inverse, hh_inverse) = (h * inverse, (h * h) * inverse);
            // (h/2)·inverse, exactly 0.5·h_inverse, one product from the inverse.
            let half_h_inverse = (0.5 * h) * inverse;
            let (ab, rate, turn) = if CENTRED {
                let p = num * inverse;
                // The centripetal force at unit rate, −m g × (g × ρ_c) = m(c·a_c⊥ + s·(g × a_c))
                // (the centre's part across g, turned), as its solve on g reads it: its
                // moment about g is 0, its dot with the drag m(rx(c² − s²) + (rr − xx)cs),
                // its P/m c·d_x + s·d_r.
                let centripetal = rx * (cc - ss) + (rr - xx) * cs;
                let q = if off_centre {
                    -(mass * centripetal) * inverse
                } else {
                    0.0
                };
                let unit_translation = if pinned {
                    S::V::zero()
                } else {
                    (drag_across * cosine + drag_around * sine) - drag * q
                };
                // 0.5·h·q, with the factors that do not wait for the inverse taken first.
                let beta = if off_centre {
                    (-(0.5 * h * mass) * centripetal) * inverse
                } else {
                    0.0
                };
                let gamma = num.mul_add(half_h_inverse, s.rate);
                let Some(factor) = centred_square_factor(beta, gamma) else {
                    break;
                };
                // s² = γ²·factor: γ² takes its products while the factor is formed.
                let gamma2 = gamma * gamma;
                let ab = unit_translation.fused(gamma2 * factor, translation(&f.b, p));
                // rate + h·(p + q·s²), and h times it.
                let rate = ((h * q) * gamma2).mul_add(factor, num.mul_add(h_inverse, s.rate));
                let turn =
                    (((h * h) * q) * gamma2).mul_add(factor, num.mul_add(hh_inverse, s.rate * h));
                (ab, rate, turn)
            } else {
                let ab = translation(&f.b, num * inverse);
                (
                    ab,
                    num.mul_add(h_inverse, s.rate),
                    num.mul_add(hh_inverse, s.rate * h),
                )
            };
            note_impacts(pressed, &normal_forces[..contacts], (n + taken, h), impacts);
            let a = motion_fused(motion, f.p * self.inverse_mass);
            s.t.advance_fused(a, ab, h);
            s.rate = rate;
            s.heading = s.heading.advanced_fused(&mut s.heading_carry, turn);
            taken += 1;
        }
        if taken == 0 {
            // The first increment's centred rate has no real value, or its operator is not
            // positive and finite: the state is as it was, for the general path to report.
            return 0;
        }
        s.t.write(particle, cfg, carry, v_half);
        // The part of w off g (round-off, after the step's start enforced the held axes) kept;
        // exact in 2D, where it is 0.
        v_half.w[0] = (w0 - g * rate0) + g * s.rate;
        // The heading's angle (its carry is what the stored value holds beyond the exact one)
        // turns R₀ about g by the general path's compensated update. Read in (−π, π], it drops
        // whole turns: after more than half a turn in one batch the quaternion comes back with
        // the general path's opposite sign, the same rotation. Only a twist would see the sign:
        // the rows' twist is unwrapped, and a spring about an axis takes the general path's
        // arithmetic instead of this.
        let angle = (s.heading.sin() - s.heading_carry[1])
            .atan2(1.0 + (s.heading.versine() - s.heading_carry[0]));
        let r = S::advance_compensated(&r0, &mut cfg.br_carry[0], &(g * angle));
        cfg.br[0] = r;
        cfg.inertia[0] = model.oriented(0, &r);
        taken
    }
}

/// [`project`] with each step's product fused into its difference.
#[inline(always)]
fn project_fused<V: Lin>(held: &[V], v: V) -> V {
    let mut v = v;
    for d in held {
        v = d.fused(-d.dot(&v), v);
    }
    v
}

/// [`Motion::project`] with each step's product fused into its difference.
#[inline(always)]
fn motion_fused<V: Lin>(motion: Motion<V>, a: V) -> V {
    match motion {
        Motion::Free => a,
        Motion::Held => V::zero(),
        Motion::Across(d) => d.fused(-d.dot(&a), a),
        Motion::AcrossTwo(d, e) => {
            let a = d.fused(-d.dot(&a), a);
            e.fused(-e.dot(&a), a)
        }
    }
}
