//! Motion from forces: the bodies' mass properties, the accelerations under a step's
//! constraints, the update of velocities and positions, the kinetic energy; and the kinematics
//! the consistent contact start sets (a pair's penetration and gap rate).

use super::axis::{ParticleKernel, move_along, step_along};
use super::body_solve::{BodyOperator, project};
use super::model::*;
use super::space::{BodyInertia, Lin, Space, compensated_add};
use super::state::note_largest;

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Mass properties of a body at orientation `r` (finite rotation): the centre in world
    /// axes, the inertia with its orientation.
    pub(super) fn oriented(&self, b: usize, r: &S::R) -> BodyInertia<S> {
        let i = &self.bodies[b].inertia;
        BodyInertia {
            mass: i.mass,
            // A body whose mass centre is its reference node (lumped) keeps it there.
            centre: if i.centre == S::V::zero() {
                i.centre
            } else {
                S::rotate(r, &i.centre)
            },
            inertia: i.inertia,
            orientation: Some(*r),
        }
    }

    /// Accelerations from forces, with body angular velocities `omega` for the centripetal and
    /// gyroscopic terms (finite rotation only), honouring the step's held DOFs. No particle
    /// force reads the velocity.
    pub fn accelerations(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        self.particle_accelerations(forces, held, out);
        self.body_accelerations(cfg, forces, vel, held, out, counters);
    }

    /// [`Model::accelerations`] with the bodies' solve operators already formed at `cfg` under
    /// `held` ([`Model::body_operators`]): what the passes of an iteration at one
    /// configuration share, formed once for all of them. The same arithmetic, bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn accelerations_with(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        operators: &[BodyOperator<S>],
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        self.particle_accelerations(forces, held, out);
        self.body_accelerations_with(cfg, forces, vel, held, Some(operators), out, counters);
    }

    /// Every body's solve operator at `cfg` under `held` into `out`: the step's where it has
    /// one ([`Constraints::body_operators`]), otherwise formed from the configuration's mass
    /// properties.
    pub(super) fn body_operators(
        &self,
        cfg: &Config<S>,
        held: &Constraints<S>,
        out: &mut Vec<BodyOperator<S>>,
    ) {
        out.clear();
        out.extend((0..self.bodies.len()).map(|b| {
            held.body_operators[b].unwrap_or_else(|| {
                BodyOperator::of(&cfg.inertia[b], &held.body_held_t[b], &held.body_free_r[b])
            })
        }));
    }

    /// The inverse masses along the axis of a step under [`ParticleKernel::Along`]: 0 for a
    /// particle held on every coordinate axis ([`Constraints::along_inverse_masses`]).
    #[inline(always)]
    fn along_masses<'a>(&'a self, held: &'a Constraints<S>) -> &'a [f64] {
        if held.along_inverse_masses.is_empty() {
            &self.inverse_masses
        } else {
            &held.along_inverse_masses
        }
    }

    /// The particles' part of [`Model::accelerations`] (it reads the forces alone).
    #[inline(always)]
    pub(super) fn particle_accelerations(
        &self,
        forces: &Forces<S>,
        held: &Constraints<S>,
        out: &mut Rates<S>,
    ) {
        match held.particle_kernel {
            ParticleKernel::Along(k) => {
                let (a, f) = (out.p.component_mut(k), forces.p.component(k));
                for ((a, f), m) in a.iter_mut().zip(f).zip(self.along_masses(held)) {
                    *a = *f * *m;
                }
                // The held components exactly 0, as the projection gives them (along `k`, a
                // particle held on every axis has ±0).
                out.p.fill_zero_except(k);
            }
            ParticleKernel::General => {
                let particles = self.inverse_masses.iter().zip(&held.particle_motion);
                for (i, (m, motion)) in particles.enumerate() {
                    let a = held.motions[*motion as usize].project(forces.p.get(i) * *m);
                    out.p.set(i, a);
                }
            }
        }
    }

    /// The bodies' part of [`Model::accelerations`].
    #[inline(always)]
    pub fn body_accelerations(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        self.body_accelerations_with(cfg, forces, vel, held, None, out, counters);
    }

    /// The bodies' accelerations, each solved with its operator from `operators` where given,
    /// otherwise with the step's or one formed here ([`Constraints::body_accelerations`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn body_accelerations_with(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        operators: Option<&[BodyOperator<S>]>,
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        for b in 0..self.bodies.len() {
            let formed = operators.map(|formed| &formed[b]);
            let (a, alpha) = self.body_acceleration(cfg, forces, vel, held, (b, formed), counters);
            out.b[b] = a;
            out.w[b] = alpha;
        }
    }

    /// Body `b`'s accelerations at velocities `vel`, solved with the operator `formed` where
    /// given ([`Constraints::body_accelerations`]).
    #[inline(always)]
    fn body_acceleration(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        (b, formed): (usize, Option<&BodyOperator<S>>),
        counters: &mut Counters,
    ) -> (S::V, S::W) {
        let inertia = &cfg.inertia[b];
        let mut f = forces.b[b];
        let mut m = forces.m[b];
        if FINITE && held.velocity_terms[b] {
            let w = vel.w[b];
            f -= S::cross(&w, &S::cross(&w, &inertia.centre)) * inertia.mass;
            // ω × I ω is perpendicular to ω: on a body turning about one axis g (ω along
            // g, the held components removed) the solve, which reads only the moment along
            // g, would see round-off of it alone.
            if held.body_free_r[b].len() > 1 {
                m -= S::gyroscopic(&w, &inertia.apply(&w));
            }
        }
        counters.body_solves += 1;
        held.body_accelerations((inertia, b), formed, &f, &m)
    }

    /// One pass of the centred velocity iteration over the bodies alone, where no dashpot acts
    /// (the velocity enters through the bodies' centripetal and gyroscopic terms alone), in one
    /// loop: each body's accelerations `acc` at the rates `guess` (with
    /// its operator from `operators`, one per body), its centred rates
    /// `v_n = v(n−½) + (h/2)·acc`, and their change from `guess`. Returns the largest squared
    /// norm of a body's change and of its rates, as [`Rates::max_difference`] takes them
    /// before its square roots. The arithmetic of [`Model::body_accelerations_with`],
    /// [`Rates::set_plus_bodies`] and that difference, bit for bit.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn centred_body_pass(
        &self,
        (cfg, forces, held): (&Config<S>, &Forces<S>, &Constraints<S>),
        operators: &[BodyOperator<S>],
        (v_half, h): (&Rates<S>, f64),
        guess: &Rates<S>,
        v_n: &mut Rates<S>,
        acc: &mut Rates<S>,
        counters: &mut Counters,
    ) -> (f64, f64) {
        debug_assert_eq!(operators.len(), self.bodies.len());
        let (mut d, mut m) = (0.0, 0.0);
        let s = 0.5 * h;
        for (b, operator) in operators.iter().enumerate() {
            let formed = Some(operator);
            let (a, alpha) =
                self.body_acceleration(cfg, forces, guess, held, (b, formed), counters);
            (acc.b[b], acc.w[b]) = (a, alpha);
            let (v, w) = (v_half.b[b] + a * s, v_half.w[b] + alpha * s);
            (v_n.b[b], v_n.w[b]) = (v, w);
            let (e, f) = (v - guess.b[b], w - guess.w[b]);
            note_largest(&mut d, &mut m, e.dot(&e), v.dot(&v));
            note_largest(&mut d, &mut m, f.dot(&f), w.dot(&w));
        }
        (d, m)
    }

    /// The bodies' part of the centred velocity in closed form, where every body whose
    /// accelerations read the velocity turns about one free axis g (a planar body, or a 3D one
    /// held on the other two): at ω = ω·g its velocity terms are the centripetal force alone,
    /// ω² times `q = −m·g×(g×c)`, so with `(a₀, α₀)` its accelerations under the position
    /// forces and `(a₁, α₁)` under `q` (two solves with its operator from `operators`), the
    /// centred rate about g solves `ω = C + k·ω²`, `C = g·ω(n−½) + (h/2)·g·α₀`,
    /// `k = (h/2)·g·α₁`, whose root near C is `2C/(1 + √(1 − 4kC))`. The fixed-point
    /// iteration contracts at that root by `ρ = |1 − √(1 − 4kC)|`; the root is taken where
    /// ρ ≤ ½, where the iteration's stop ([`converged`](super::velocity)) finds the same rate
    /// within its tolerance. Writes each body's accelerations `(a₀ + ω² a₁, α₀ + ω² α₁)` into
    /// `acc` and its centred rates into `v_n`; false, with nothing it wrote to be read, where a
    /// body turns about more than one axis or ρ > ½ (or a rate is not finite): the iteration
    /// is then left to it.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn centred_bodies_solved(
        &self,
        (cfg, forces, held): (&Config<S>, &Forces<S>, &Constraints<S>),
        operators: &[BodyOperator<S>],
        (v_half, h): (&Rates<S>, f64),
        v_n: &mut Rates<S>,
        acc: &mut Rates<S>,
        counters: &mut Counters,
    ) -> bool {
        let s = 0.5 * h;
        for (b, operator) in operators.iter().enumerate() {
            let (inertia, formed) = (&cfg.inertia[b], Some(operator));
            let (mut a, mut alpha) =
                held.body_accelerations((inertia, b), formed, &forces.b[b], &forces.m[b]);
            counters.body_solves += 1;
            if FINITE && held.velocity_terms[b] {
                let [g] = held.body_free_r[b][..] else {
                    return false;
                };
                let q = S::cross(&g, &S::cross(&g, &inertia.centre)) * -inertia.mass;
                let (a1, alpha1) = held.body_accelerations((inertia, b), formed, &q, &S::W::zero());
                counters.body_solves += 1;
                let c = g.dot(&v_half.w[b]) + s * g.dot(&alpha);
                let k = s * g.dot(&alpha1);
                let root = (1.0 - 4.0 * k * c).sqrt();
                if !(0.5..=1.5).contains(&root) {
                    return false;
                }
                let w = 2.0 * c / (1.0 + root);
                (a, alpha) = (a + a1 * (w * w), alpha + alpha1 * (w * w));
            }
            (acc.b[b], acc.w[b]) = (a, alpha);
            (v_n.b[b], v_n.w[b]) = (v_half.b[b] + a * s, v_half.w[b] + alpha * s);
        }
        true
    }

    /// Kinetic energy at velocities `vel`.
    pub fn kinetic_energy(&self, cfg: &Config<S>, vel: &Rates<S>) -> f64 {
        let mut e = 0.0;
        for (i, p) in self.particles.iter().enumerate() {
            let v = vel.p.get(i);
            e += 0.5 * p.mass * v.dot(&v);
        }
        for b in 0..self.bodies.len() {
            let (f, m) = self.body_momentum(cfg, b, &vel.b[b], &vel.w[b]);
            e += 0.5 * (vel.b[b].dot(&f) + vel.w[b].dot(&m));
        }
        e
    }

    /// The body mass matrix applied to `(v, ω)`: `(m v + m ω×c, m c×v + I ω)`.
    pub fn body_momentum(&self, cfg: &Config<S>, b: usize, v: &S::V, w: &S::W) -> (S::V, S::W) {
        let i = &cfg.inertia[b];
        (
            (*v + S::cross(w, &i.centre)) * i.mass,
            S::moment(&i.centre, v) * i.mass + i.apply(w),
        )
    }

    /// Advance positions by `h · vel`, rotating only the bodies that can rotate.
    ///
    /// Translations (and small rotations) are summed with Kahan compensation kept in `carry`:
    /// the rounding of `x + h·v` then stays O(ε|x|) instead of growing as ε|x|√N, which matters
    /// because the penalty multiplies position errors by k_p.
    pub fn advance(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        vel: &Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        advance_flat(cfg.u.flat_mut(), carry.p.flat_mut(), vel.p.flat(), h);
        self.advance_bodies(cfg, carry, h, vel, held, counters);
    }

    /// The particles' part of an increment whose forces do not read the velocity:
    /// a(n) = P M⁻¹ f(n) (into `acc`), v(n+½) = v(n−½) + h·a(n) in place of v(n−½) in
    /// `v_half`, and x(n+1) = x(n) + h·v(n+½) into `cfg` (compensated); the components of the
    /// particle forces it read cleared for the next force pass (any other component a pass
    /// wrote stays marked in [`Forces::written`] for [`Forces::clear`]). The arithmetic of [`Model::accelerations`],
    /// [`Rates::set_plus`] and [`Model::advance`], bit for bit (a held particle's acceleration
    /// ±0 for +0). Where every particle moves along one axis or is held on every axis
    /// ([`ParticleKernel::Along`]), in one pass over that component (each particle's data read once, the
    /// acceleration written only where `STORE_ACC`: where a later increment reads it); otherwise
    /// the projections first, then each pass over every component alike.
    #[allow(clippy::too_many_arguments)]
    pub fn step_particles<const STORE_ACC: bool>(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        forces: &mut Forces<S>,
        held: &Constraints<S>,
        v_half: &mut Rates<S>,
        acc: &mut Rates<S>,
    ) {
        match held.particle_kernel {
            ParticleKernel::Along(k) => {
                let x = cfg.u.component_mut(k);
                let c = carry.p.component_mut(k);
                let v = v_half.p.component_mut(k);
                let f = forces.p.component_mut(k);
                let a = acc.p.component_mut(k);
                let state = (x.iter_mut().zip(c.iter_mut())).zip(v.iter_mut());
                let data = (f.iter_mut().zip(self.along_masses(held))).zip(a);
                for (((x, c), v), ((f, m), a)) in state.zip(data) {
                    let acceleration = step_along(x, c, v, f, *m, h);
                    if STORE_ACC {
                        *a = acceleration;
                    }
                }
                if STORE_ACC {
                    // The held components' accelerations, exactly 0 as the projection gives
                    // them.
                    acc.p.fill_zero_except(k);
                }
                forces.written[k] = false;
            }
            ParticleKernel::General => {
                // Each particle's acceleration (its projection), then every component alike.
                let particles = self.inverse_masses.iter().zip(&held.particle_motion);
                for (i, (m, motion)) in particles.enumerate() {
                    let a = held.motions[*motion as usize].project(forces.p.get(i) * *m);
                    acc.p.set(i, a);
                }
                self.move_particles(cfg, carry, h, held, v_half, acc);
                forces.p.fill_zero();
                forces.written = [false; 3];
            }
        }
    }

    /// The particles' motion from accelerations `acc` already formed under `held`:
    /// v(n+½) = v(n−½) + h·a(n) in place of v(n−½) in `v_half`, and x(n+1) = x(n) + h·v(n+½)
    /// into `cfg` (compensated). The arithmetic of [`Rates::set_plus`] and [`Model::advance`]
    /// on the particles, bit for bit; under [`ParticleKernel::Along`], on that component alone
    /// (the others, held, keep their values as in [`Model::step_particles`]), otherwise each
    /// pass over every component alike.
    pub fn move_particles(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        held: &Constraints<S>,
        v_half: &mut Rates<S>,
        acc: &Rates<S>,
    ) {
        match held.particle_kernel {
            ParticleKernel::Along(k) => {
                let x = cfg.u.component_mut(k);
                let c = carry.p.component_mut(k);
                let v = v_half.p.component_mut(k);
                let state = (x.iter_mut().zip(c.iter_mut())).zip(v.iter_mut());
                for (((x, c), v), a) in state.zip(acc.p.component(k)) {
                    move_along(x, c, v, *a, h);
                }
            }
            ParticleKernel::General => {
                for (v, a) in v_half.p.flat_mut().iter_mut().zip(acc.p.flat()) {
                    *v += *a * h;
                }
                advance_flat(cfg.u.flat_mut(), carry.p.flat_mut(), v_half.p.flat(), h);
            }
        }
    }

    /// The bodies' part of [`Model::advance`].
    #[inline(always)]
    pub fn advance_bodies(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        vel: &Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        for b in 0..self.bodies.len() {
            self.move_body(b, (cfg, carry), h, (vel.b[b], vel.w[b]), held, counters);
        }
    }

    /// The bodies' part of an increment from their accelerations `acc`: v(n+½) = v(n−½) + h·a(n)
    /// in place of v(n−½) in `v_half`, and the configuration moved by it, in one pass over
    /// the bodies. The arithmetic of [`Rates::set_plus_bodies`] and [`Model::advance_bodies`],
    /// bit for bit.
    #[inline(always)]
    pub fn step_bodies(
        &self,
        (cfg, carry): (&mut Config<S>, &mut Rates<S>),
        h: f64,
        v_half: &mut Rates<S>,
        acc: &Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        let n = self.bodies.len();
        let (vb, vw) = (&mut v_half.b[..n], &mut v_half.w[..n]);
        let (ab, aw) = (&acc.b[..n], &acc.w[..n]);
        for b in 0..n {
            (vb[b], vw[b]) = (vb[b] + ab[b] * h, vw[b] + aw[b] * h);
            self.move_body(b, (cfg, carry), h, (vb[b], vw[b]), held, counters);
        }
    }

    /// Body `b` moved over an increment of `h` at the rates `(v, ω)`: its reference node by
    /// a compensated sum, its orientation (where it can turn) by the exact exponential, with
    /// its mass properties.
    #[inline(always)]
    fn move_body(
        &self,
        b: usize,
        (cfg, carry): (&mut Config<S>, &mut Rates<S>),
        h: f64,
        (v, w): (S::V, S::W),
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        compensated_add(&mut cfg.bu[b], &mut carry.b[b], v * h);
        if !held.rotating[b] {
            return;
        }
        counters.rotation_updates += 1;
        if FINITE {
            // The mass properties from the new orientation while it is still in registers,
            // not read back from the configuration just written.
            let r = S::advance_compensated(&cfg.br[b], &mut cfg.br_carry[b], &(w * h));
            cfg.inertia[b] = self.oriented(b, &r);
            cfg.br[b] = r;
        } else {
            compensated_add(&mut cfg.bth[b], &mut carry.w[b], w * h);
        }
    }

    /// Remove velocity components along held directions.
    pub fn enforce(&self, vel: &mut Rates<S>, held: &Constraints<S>) {
        for (i, m) in held.particle_motion.iter().enumerate() {
            let v = project(&held.held_sets[*m as usize], vel.p.get(i));
            vel.p.set(i, v);
        }
        for b in 0..self.bodies.len() {
            vel.b[b] = project(&held.body_held_t[b], vel.b[b]);
            vel.w[b] = project(&held.body_held_r[b], vel.w[b]);
        }
    }

    /// Push a contact node (a ball's body) into its face so that its gap becomes `-depth`.
    pub fn set_penetration(&self, cfg: &mut Config<S>, k: usize, depth: f64) {
        let (d, n) = self.gap(cfg, k);
        match self.contacts[k].slave {
            Point::Particle(i) => cfg.u.sub(i, n * (d + depth)),
            Point::Body { body, .. } => cfg.bu[body] -= n * (d + depth),
            Point::Ground(_) => {}
        }
    }

    /// State reached from `(cfg, vel)` after `s` seconds with acceleration `acc` and jerk
    /// `jerk` (third-order Taylor expansion; rotations through the exponential of the
    /// expanded rotation vector). That expansion is exact to third order while ω, α and α̇
    /// share one axis (every shipped case with contact: the contact start is its user). About
    /// changing axes the rotation vector's cubic term also holds ½ ω×α (the first Magnus
    /// commutator), left out here: a third-order error in the turned state, which reaches the
    /// contact start's lead as an O(h²·|ω×α|) error in the gap rate.
    pub fn extrapolate(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        acc: &Rates<S>,
        jerk: &Rates<S>,
        s: f64,
    ) -> (Config<S>, Rates<S>) {
        let (s2, s3) = (0.5 * s * s, s * s * s / 6.0);
        let mut out = cfg.clone();
        for i in 0..cfg.u.len() {
            let u = cfg.u.get(i) + vel.p.get(i) * s + acc.p.get(i) * s2 + jerk.p.get(i) * s3;
            out.u.set(i, u);
        }
        for (b, u) in out.bu.iter_mut().enumerate() {
            *u = cfg.bu[b] + vel.b[b] * s + acc.b[b] * s2 + jerk.b[b] * s3;
        }
        for b in 0..self.bodies.len() {
            let turn = vel.w[b] * s + acc.w[b] * s2 + jerk.w[b] * s3;
            out.bth[b] = cfg.bth[b] + turn;
            out.br_carry[b] = Default::default();
            if FINITE {
                out.br[b] = S::advance(&cfg.br[b], &turn);
                out.inertia[b] = self.oriented(b, &out.br[b]);
            }
        }
        (out, vel.plus(s, acc).plus(s2, jerk))
    }

    /// Time derivative of a contact pair's gap.
    pub fn gap_rate(&self, cfg: &Config<S>, vel: &Rates<S>, k: usize) -> f64 {
        let c = &self.contacts[k];
        if c.solid.is_some() {
            let (_, n) = self.gap(cfg, k);
            return self.normal_rate(cfg, vel, k, &n);
        }
        let (node, b) = (self.node_velocity(cfg, vel, &c.slave), c.body);
        if FINITE {
            let r = &cfg.br[b];
            let n = S::rotate(r, &c.normal);
            let f = S::rotate(r, &c.face);
            let p_dot = vel.b[b] + S::cross(&vel.w[b], &f);
            S::cross(&vel.w[b], &n).dot(&self.face_to_node(cfg, k)) + n.dot(&(node - p_dot))
        } else {
            c.normal.dot(&(node - vel.b[b])) - c.normal.dot(&S::cross(&vel.w[b], &c.arm0))
        }
    }

    /// Change the contact node's (a ball's body's) velocity along the face normal so the gap
    /// rate becomes `rate`.
    pub fn set_gap_rate(&self, cfg: &Config<S>, vel: &mut Rates<S>, k: usize, rate: f64) {
        let current = self.gap_rate(cfg, vel, k);
        let (_, n) = self.gap(cfg, k);
        match self.contacts[k].slave {
            Point::Particle(i) => vel.p.add(i, n * (rate - current)),
            Point::Body { body, .. } => vel.b[body] += n * (rate - current),
            Point::Ground(_) => {}
        }
    }

    /// Second time derivative of a contact pair's gap, exact for the given velocities and
    /// accelerations (finite: the face point and normal rotate with the body). On a solid,
    /// whose curvature parry does not give, it is the central difference of the gap's rate
    /// along the motion extrapolated ±τ, τ small enough that the node moves 1e-6 of the
    /// solid's half thickness relative to the body and the body turns 1e-6 rad (truncation
    /// ~1e-12, round-off ~1e-10 of the rate's scale), and at most `longest` (the increment:
    /// a node at rest on a still solid has no scale of its own).
    pub fn gap_acceleration(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        acc: &Rates<S>,
        k: usize,
        longest: f64,
    ) -> f64 {
        let c = &self.contacts[k];
        let b = c.body;
        let (node_v, node_a) = (
            self.node_velocity(cfg, vel, &c.slave),
            self.node_acceleration(cfg, vel, acc, k),
        );
        if let Some((_, shape)) = &c.solid {
            let depth = S::thinnest(shape);
            // The node's motion relative to the body point it touches: a body carrying the
            // pair fast through space does not shrink τ.
            let arm = self.contact_arm(cfg, k);
            let (w, alpha) = (vel.w[b], acc.w[b]);
            let v = node_v - vel.b[b] - S::cross(&w, &arm);
            let a = node_a - acc.b[b] - S::cross(&alpha, &arm) - S::cross(&w, &S::cross(&w, &arm));
            let (speed, pace, spin) = (v.dot(&v).sqrt(), a.dot(&a).sqrt(), w.dot(&w).sqrt());
            let tau =
                (1e-6 * (depth / speed).min((depth / pace).sqrt()).min(1.0 / spin)).min(longest);
            let zero = self.zero_rates();
            let rate = |s: f64| {
                let (c, v) = self.extrapolate(cfg, vel, acc, &zero, s);
                self.gap_rate(&c, &v, k)
            };
            return (rate(tau) - rate(-tau)) / (2.0 * tau);
        }
        if FINITE {
            let r = &cfg.br[b];
            let (w, alpha) = (vel.w[b], acc.w[b]);
            let n = S::rotate(r, &c.normal);
            let f = S::rotate(r, &c.face);
            let n_dot = S::cross(&w, &n);
            let n_ddot = S::cross(&alpha, &n) + S::cross(&w, &n_dot);
            let p_dot = vel.b[b] + S::cross(&w, &f);
            let p_ddot = acc.b[b] + S::cross(&alpha, &f) + S::cross(&w, &S::cross(&w, &f));
            n_ddot.dot(&self.face_to_node(cfg, k))
                + n_dot.dot(&(node_v - p_dot)) * 2.0
                + n.dot(&(node_a - p_ddot))
        } else {
            c.normal.dot(&(node_a - acc.b[b])) - c.normal.dot(&S::cross(&acc.w[b], &c.arm0))
        }
    }
}

/// `x += h · v` component by component, compensated (`carry`): the particles' positions from
/// their velocities, every component alike.
#[inline(always)]
fn advance_flat(x: &mut [f64], carry: &mut [f64], v: &[f64], h: f64) {
    for ((x, c), v) in x.iter_mut().zip(carry.iter_mut()).zip(v) {
        compensated_add(x, c, *v * h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case;
    use crate::engines::explicit::space::Planar;

    /// rigid2d_slide_surface's body turns about z with its mass centre off its reference node,
    /// so its accelerations read ω² through the centripetal force. Turned by 0.3 rad, with the
    /// contact node then deep in its face (a large penalty force) and v(n−½) its
    /// initial rates, at ten times the case's increment, the iteration contracts by ρ = 0.12
    /// per pass (measured from its first iterates): the closed-form rate and accelerations are
    /// the fixed point the iteration of [`Model::centred_body_pass`] converges to, to a few
    /// ulps (60 passes take the iterate within ρ⁶⁰ of it, far below round-off).
    #[test]
    fn the_closed_form_centred_rate_is_the_iterations_fixed_point() {
        let scene = case::load(&case::cases_dir().join("rigid2d_slide_surface.toml")).unwrap();
        let model = Model::<Planar, true>::compile(&scene, 1e10);
        // Turned by 0.3 rad: at the start the centre (0, −1.5) lies along the held y, where the
        // centripetal force moves nothing.
        let mut cfg = model.initial_config();
        cfg.br[0] = crate::engines::explicit::space::Heading::new(0.3);
        cfg.inertia[0] = model.oriented(0, &cfg.br[0]);
        let held = model.constraints(scene.steps.last().unwrap());
        assert!(held.velocity_terms[0]);
        let mut counters = Counters::default();
        let mut forces = model.zero_forces();
        model.forces(&cfg, ContactMode::Unilateral, &mut forces, &mut counters);
        let mut operators = Vec::new();
        model.body_operators(&cfg, &held, &mut operators);
        let mut v_half = model.zero_rates();
        (v_half.b[0], v_half.w[0]) = (nalgebra::Vector2::new(15.0, 0.0), 10.0);
        let h = 1e-4;
        let state = (&cfg, &forces, &held);
        let (mut v_n, mut acc) = (model.zero_rates(), model.zero_rates());
        let solved = model.centred_bodies_solved(
            state,
            &operators,
            (&v_half, h),
            &mut v_n,
            &mut acc,
            &mut counters,
        );
        assert!(solved);
        let (mut guess, mut next, mut iterated) =
            (v_half.clone(), model.zero_rates(), model.zero_rates());
        let mut rates = Vec::new();
        for _ in 0..60 {
            let pass = (&v_half, h);
            let (next, acc) = (&mut next, &mut iterated);
            model.centred_body_pass(state, &operators, pass, &guess, next, acc, &mut counters);
            guess.clone_from(next);
            rates.push(guess.w[0]);
        }
        // The contraction per pass, from the first three iterates.
        let rho = ((rates[2] - rates[1]) / (rates[1] - rates[0])).abs();
        assert!((0.05..0.5).contains(&rho), "{rho}");
        // 45 ulps: the two forms round differently (a₀ + ω²a₁ against a solve under f + mω²c).
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-14 * a.abs().max(b.abs());
        assert!(near(v_n.w[0], guess.w[0]), "{} {}", v_n.w[0], guess.w[0]);
        assert!(
            near(v_n.b[0].x, guess.b[0].x),
            "{} {}",
            v_n.b[0].x,
            guess.b[0].x
        );
        assert!(
            near(acc.w[0], iterated.w[0]),
            "{} {}",
            acc.w[0],
            iterated.w[0]
        );
        assert!(
            near(acc.b[0].x, iterated.b[0].x),
            "{} {}",
            acc.b[0].x,
            iterated.b[0].x
        );
    }
}
