//! Contact pairs whose slave is a body's node carrying a ball (a disc in 2D) that touches a
//! plane face of another body: a body rolling (or sliding) on a face.
//!
//! The pair touches at the contact point c = p − r·n (p the node, r the ball's radius, n the
//! face's outward normal, turning with the face's body); its gap is n·(p − face point) − r.
//! Every force of the pair (the normal penalty, its dashpot, the stick of friction) acts at c:
//! on the slave body as a force and its moment about the reference node (arm R·ρ − r·n, ρ the
//! node's offset in the body), and back on the face's body at the same point. The normal force
//! passes through the ball's centre, so it turns the ball only where the node is off the
//! reference node; friction turns it.
//!
//! Friction slips where the two bodies' material points at c move apart: the slip rate is
//! v + ω × (R·ρ − r·n) on the slave less the face body's velocity at c. The contact point itself
//! moves over both bodies as the ball rolls, so the stick spring is not the distance from a
//! fixed stick point to c (a rolling ball would stretch it by the distance rolled): each
//! increment stretches it by the relative displacement of the material points that touched at
//! the last increment ([`Model::material_arm`]), and the stick point is then carried along with
//! the contact point ([`super::friction`]). Where the slave is a particle, c is the node and the
//! two views coincide.

use super::model::{ContactMode, Forces, Model, Point};
use super::space::{Lin, Space};
use super::state::{Config, Rates};

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// The body that carries pair `k`'s ball and the node's offset in it, or `None` for a
    /// particle.
    #[inline(always)]
    pub(super) fn rolling_body(&self, k: usize) -> Option<(usize, S::V)> {
        match self.contacts[k].slave {
            Point::Body { body, rho } => Some((body, rho)),
            _ => None,
        }
    }

    /// A contact node's displacement ([`Model::displacement`]), the particle's read in line and
    /// a body's point out of line: the particles' contact loop stays small.
    #[inline(always)]
    pub(super) fn node_displacement(&self, cfg: &Config<S>, slave: &Point<S>) -> S::V {
        match slave {
            Point::Particle(i) => cfg.u.get(*i),
            _ => self.displacement_out_of_line(cfg, slave),
        }
    }

    #[cold]
    #[inline(never)]
    fn displacement_out_of_line(&self, cfg: &Config<S>, p: &Point<S>) -> S::V {
        self.displacement(cfg, p)
    }

    /// A contact node's velocity ([`Model::velocity`]), as [`Model::node_displacement`].
    #[inline(always)]
    pub(super) fn node_velocity(&self, cfg: &Config<S>, vel: &Rates<S>, slave: &Point<S>) -> S::V {
        match slave {
            Point::Particle(i) => vel.p.get(*i),
            _ => self.velocity_out_of_line(cfg, vel, slave),
        }
    }

    #[cold]
    #[inline(never)]
    fn velocity_out_of_line(&self, cfg: &Config<S>, vel: &Rates<S>, p: &Point<S>) -> S::V {
        self.velocity(cfg, vel, p)
    }

    /// Pair `k`'s outward normal in the world.
    #[inline]
    pub(super) fn world_normal(&self, cfg: &Config<S>, k: usize) -> S::V {
        let c = &self.contacts[k];
        self.to_world(cfg, c.body, &c.normal)
    }

    /// From the face body's reference node to pair `k`'s contact point: the node less the
    /// ball's radius along the world normal `n`.
    #[inline]
    pub(super) fn touch_arm(&self, cfg: &Config<S>, k: usize, n: &S::V) -> S::V {
        self.contact_arm(cfg, k) - *n * self.contacts[k].radius
    }

    /// Add a force `f` (world) at rolling pair `k`'s contact point on the ball's body (with
    /// its moment about the reference node), and its reaction on the face's body, to `out`;
    /// `n` is the world normal. Kept out of line: the particles' contact loop stays small.
    #[cold]
    #[inline(never)]
    pub(super) fn push_at_touch(
        &self,
        cfg: &Config<S>,
        k: usize,
        n: &S::V,
        f: S::V,
        out: &mut Forces<S>,
    ) {
        let c = &self.contacts[k];
        let (slave, rho) = self.rolling_body(k).expect("a rolling pair");
        let arm = self.arm(cfg, slave, &rho) - *n * c.radius;
        out.b[slave] += f;
        out.m[slave] += S::moment(&arm, &f);
        out.b[c.body] -= f;
        out.m[c.body] -= S::moment(&self.touch_arm(cfg, k, n), &f);
    }

    /// Rolling pair `k`'s gap: the node's less the ball's radius; and the outward normal.
    #[cold]
    #[inline(never)]
    pub(super) fn touch_gap(&self, cfg: &Config<S>, k: usize) -> (f64, S::V) {
        let c = &self.contacts[k];
        let (d, n) = self.gap_at(cfg, k, self.displacement(cfg, &c.slave));
        (d - c.radius, n)
    }

    /// The force pass's normal penalty on rolling pair `k` under `mode` (as for a particle's
    /// pair, at the contact point): the force and gap into `out`, and the penalty's elastic
    /// energy when `ENERGY` (0 otherwise, and under given forces).
    #[cold]
    #[inline(never)]
    pub(super) fn touch_penalty<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        k: usize,
        mode: ContactMode,
        out: &mut Forces<S>,
    ) -> f64 {
        let (d, n) = self.touch_gap(cfg, k);
        let f = self.penalty_force(k, mode, d);
        out.contact[k] = f;
        out.gap[k] = d;
        self.push_at_touch(cfg, k, &n, n * f, out);
        if ENERGY && !matches!(mode, ContactMode::Given(_)) {
            0.5 * f * f / self.penalty
        } else {
            0.0
        }
    }

    /// Rolling pair `k`'s contact point relative to the face body's reference node, in that
    /// body's frame.
    #[cold]
    #[inline(never)]
    pub(super) fn touch_in_body_frame(&self, cfg: &Config<S>, k: usize) -> S::V {
        let c = &self.contacts[k];
        self.local(cfg, k, &S::V::zero()) - c.normal * c.radius
    }

    /// Add a tangential force `f` (the face body's frame) at rolling pair `k`'s contact point,
    /// and its reaction, to `out` ([`Model::push_at_touch`]).
    #[cold]
    #[inline(never)]
    pub(super) fn push_tangential_at_touch(
        &self,
        cfg: &Config<S>,
        k: usize,
        f: &S::V,
        out: &mut Forces<S>,
    ) {
        let f = self.to_world(cfg, self.contacts[k].body, f);
        self.push_at_touch(cfg, k, &self.world_normal(cfg, k), f, out);
    }

    /// Where the ball's material point that touches at `cfg` is, relative to the node, in the
    /// ball's body frame: −r·Rᵀn.
    pub(super) fn touching_material(&self, cfg: &Config<S>, k: usize) -> S::V {
        let (slave, _) = self.rolling_body(k).expect("a rolling pair");
        let n = self.world_normal(cfg, k);
        self.to_body(cfg, slave, &(n * -self.contacts[k].radius))
    }

    /// The ball's material point `sigma` ([`Model::touching_material`]) at `cfg`, relative
    /// to the face body's reference node in that body's frame.
    pub(super) fn material_arm(&self, cfg: &Config<S>, k: usize, sigma: &S::V) -> S::V {
        let (slave, _) = self.rolling_body(k).expect("a rolling pair");
        let c = &self.contacts[k];
        let node = self.local(cfg, k, &S::V::zero());
        node + self.to_body(cfg, c.body, &self.arm(cfg, slave, sigma))
    }

    /// The velocity of the ball's material point at rolling pair `k`'s contact point relative
    /// to the face body's point there (world), `n` the world normal.
    pub(super) fn touch_slip(&self, cfg: &Config<S>, vel: &Rates<S>, k: usize, n: &S::V) -> S::V {
        let c = &self.contacts[k];
        let (slave, rho) = self.rolling_body(k).expect("a rolling pair");
        let arm = self.arm(cfg, slave, &rho) - *n * c.radius;
        let ball = vel.b[slave] + S::cross(&vel.w[slave], &arm);
        let b = c.body;
        ball - vel.b[b] - S::cross(&vel.w[b], &self.touch_arm(cfg, k, n))
    }

    /// The acceleration of pair `k`'s node at velocities `vel` and accelerations `acc`.
    pub(super) fn node_acceleration(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        acc: &Rates<S>,
        k: usize,
    ) -> S::V {
        match self.contacts[k].slave {
            Point::Particle(i) => acc.p.get(i),
            Point::Body { body, rho } => {
                let (w, arm) = (vel.w[body], self.arm(cfg, body, &rho));
                acc.b[body] + S::cross(&acc.w[body], &arm) + S::cross(&w, &S::cross(&w, &arm))
            }
            Point::Ground(_) => S::V::zero(),
        }
    }
}
