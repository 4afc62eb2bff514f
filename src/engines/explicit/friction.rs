//! Coulomb friction as Abaqus/Explicit's penalty friction does it: an elastic stick and a
//! return to the slip cone.
//!
//! Each pair with friction keeps a stick point on its body (in the body's frame). The
//! node's tangential offset from it, d_t, loads a tangential penalty of the normal penalty's
//! stiffness: f_t = −k·d_t. While |f_t| ≤ μ·f_n the node sticks (elastically, by
//! |f_t|/k); beyond it, the stick point is drawn after the node until |f_t| = μ_k·f_n (the
//! node slips), and the energy μ_k·f_n × the stick point's travel is dissipated. A sticking
//! node resists up to μ_s·f_n; once it slips it resists μ_k·f_n until the stick spring
//! unloads below that (the slip stopped or reversed). A pair without a normal force carries
//! no tangential force, and its stick point follows the node.
//!
//! The force depends on the configuration and the stick points alone, so it enters the force
//! pass of central differences like the normal penalty. Its effect on the stable increment:
//! the stick is a penalty of stiffness k in the face's tangent directions, which the
//! linearisation includes ([`Model::stick_forces_about_start`]); on a node against a held
//! face it adds modes at the normal penalty's frequency, so the limit does not move. On a
//! ball rolling on a held face ([`super::rolling`]) the stick acts at the contact point, off
//! the ball's centre, and moves the mass m·I/(I + m·r²) (a disc: m/3, a ball: 2m/7): its mode
//! is √3 (√(7/2)) faster than the normal one, and sets the limit.
//!
//! A ball's contact point moves over both bodies as it rolls: its pair's stick point is
//! carried along with it, and its spring stretched by the slip of the material points that
//! touch ([`Model::material_arm`]).

use super::model::{Forces, Model, Point};
use super::space::{Lin, Space};
use super::state::{Config, Rates};
use crate::scene::Friction;

/// The stick points of a run's pairs and the energy their slip dissipated.
#[derive(Debug, Clone)]
pub struct Sticks<S: Space> {
    /// Per pair: where the node sticks, relative to the body's reference node in its frame
    /// (`None` for a frictionless pair).
    points: Vec<Option<S::V>>,
    /// Per pair: whether the node slipped at the last increment (its resistance then μ_k).
    slipping: Vec<bool>,
    /// Per rolling pair with friction: the ball's material point that touched at the last
    /// increment ([`Model::touching_material`]); `None` for the other pairs.
    material: Vec<Option<S::V>>,
    /// Energy dissipated by slip since the start.
    pub dissipated: f64,
    /// Increments at which some pair slipped.
    pub slips: u64,
    /// Pair evaluations.
    pub evaluations: u64,
}

impl<S: Space> Sticks<S> {
    /// The stick points at `cfg` (each node sticks where it is); `None` for a scene without
    /// friction, which then computes none.
    pub fn new<const FINITE: bool>(model: &Model<S, FINITE>, cfg: &Config<S>) -> Option<Self> {
        if !model.has_friction() {
            return None;
        }
        let points = (0..model.contacts.len())
            .map(|k| {
                model.contacts[k]
                    .friction
                    .map(|_| model.body_frame_arm(cfg, k))
            })
            .collect();
        let material = (0..model.contacts.len())
            .map(|k| {
                let rolls = model.contacts[k].friction.is_some() && model.rolling_body(k).is_some();
                rolls.then(|| model.touching_material(cfg, k))
            })
            .collect();
        Some(Sticks {
            points,
            slipping: vec![false; model.contacts.len()],
            material,
            dissipated: 0.0,
            slips: 0,
            evaluations: 0,
        })
    }

    /// The stick points at the start of the first dynamic step, at `cfg` with velocities
    /// `vel` and the force pass's `forces` (without friction), as the consistent contact
    /// start places the normal penalty: so the stick spring starts carrying the force the
    /// rigid law would, instead of ringing from unloaded.
    /// - A node sliding relative to its surface starts on the slip cone: its stick point
    ///   μ_k·f_n/k behind it, so the first increment already resists with μ_k·f_n.
    /// - A node at rest relative to it starts stuck, its stick spring loaded with the
    ///   tangential force that holds the node's other forces (exact against a held body; for
    ///   a ball, the force on its body, its moment left out); where that exceeds μ_s·f_n, on
    ///   the cone in the direction that force drives it.
    pub fn start<const FINITE: bool>(
        &mut self,
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        vel: &Rates<S>,
        forces: &Forces<S>,
    ) {
        for (k, point) in self.points.iter_mut().enumerate() {
            let (Some(point), Some(friction)) = (point.as_mut(), model.contacts[k].friction) else {
                continue;
            };
            if let Some(sigma) = self.material[k].as_mut() {
                *sigma = model.touching_material(cfg, k);
            }
            let arm = model.body_frame_arm(cfg, k);
            let normal = forces.contact[k];
            let slip = model.tangential_slip_rate(cfg, vel, k, &arm);
            let speed = slip.dot(&slip).sqrt();
            let held = model.tangential_load(cfg, forces, k, &arm) * (1.0 / model.penalty);
            let hold = held.dot(&held).sqrt() * model.penalty;
            let cone = friction.kinetic_coefficient * normal / model.penalty;
            (*point, self.slipping[k]) = if normal <= 0.0 {
                (arm, false)
            } else if speed > 0.0 {
                (arm - slip * (cone / speed), true)
            } else if hold <= friction.static_coefficient * normal {
                (arm - held, false)
            } else {
                (arm - held * (cone * model.penalty / hold), true)
            };
        }
    }
}

/// One pair's stick as [`Model::friction_forces`] updates it.
struct Stick<'a, S: Space> {
    /// Where the node sticks (the body's frame).
    point: &'a mut S::V,
    /// Whether it slipped at the last increment.
    slipping: &'a mut bool,
    /// The run's energy dissipated by slip.
    dissipated: &'a mut f64,
}

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Whether any contact pair has friction.
    pub fn has_friction(&self) -> bool {
        self.contacts.iter().any(|c| c.friction.is_some())
    }

    /// Pair `k`'s node (a ball's contact point) relative to its body's reference node, in the
    /// body's frame.
    #[inline(always)]
    pub(super) fn body_frame_arm(&self, cfg: &Config<S>, k: usize) -> S::V {
        match self.contacts[k].slave {
            Point::Particle(_) => self.local(cfg, k, &S::V::zero()),
            _ => self.touch_in_body_frame(cfg, k),
        }
    }

    /// Pair `k`'s node's (a ball's touching material point's) velocity relative to the body
    /// point it touches, in the body's frame and in the surface's tangent plane at `arm`.
    fn tangential_slip_rate(&self, cfg: &Config<S>, vel: &Rates<S>, k: usize, arm: &S::V) -> S::V {
        let c = &self.contacts[k];
        let b = c.body;
        let world = match c.slave {
            Point::Particle(i) => {
                vel.p.get(i) - vel.b[b] - S::cross(&vel.w[b], &self.contact_arm(cfg, k))
            }
            _ => self.touch_slip(cfg, vel, k, &self.world_normal(cfg, k)),
        };
        let relative = self.to_body(cfg, b, &world);
        let n = self.body_frame_normal(k, arm);
        relative - n * n.dot(&relative)
    }

    /// The tangential part of the force `forces` puts on pair `k`'s node (a ball's body), in
    /// the body's frame at `arm`.
    fn tangential_load(&self, cfg: &Config<S>, forces: &Forces<S>, k: usize, arm: &S::V) -> S::V {
        let c = &self.contacts[k];
        let on_node = match c.slave {
            Point::Particle(i) => forces.p.get(i),
            Point::Body { body, .. } => forces.b[body],
            Point::Ground(_) => S::V::zero(),
        };
        let load = self.to_body(cfg, c.body, &on_node);
        let n = self.body_frame_normal(k, arm);
        load - n * n.dot(&load)
    }

    /// A world direction in body `b`'s frame (small rotation: Rᵀ ≈ 1 − [θ]×).
    pub(super) fn to_body(&self, cfg: &Config<S>, b: usize, x: &S::V) -> S::V {
        if FINITE {
            S::unrotate(&cfg.br[b], x)
        } else {
            *x - S::cross(&cfg.bth[b], x)
        }
    }

    /// Pair `k`'s outward normal at `arm` (the node in the body's frame).
    fn body_frame_normal(&self, k: usize, arm: &S::V) -> S::V {
        let c = &self.contacts[k];
        match &c.solid {
            Some((centre, shape)) => S::solid_gap(shape, &(*arm - *centre)).1,
            None => c.normal,
        }
    }

    /// Add the friction forces at `cfg` to `out`, whose normal forces the force pass has
    /// set; move the stick points of the pairs that slip, and add the stick springs' energy
    /// to `out.elastic` when `ENERGY`.
    pub fn friction_forces<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        sticks: &mut Sticks<S>,
        out: &mut Forces<S>,
    ) {
        let k_t = self.penalty;
        let mut slipped = false;
        for (k, c) in self.contacts.iter().enumerate() {
            let (Some(friction), Some(point)) = (c.friction, sticks.points[k].as_mut()) else {
                continue;
            };
            sticks.evaluations += 1;
            let (slipping, dissipated) = (&mut sticks.slipping[k], &mut sticks.dissipated);
            let mut stick = Stick {
                point,
                slipping,
                dissipated,
            };
            let Point::Particle(i) = c.slave else {
                let sigma = sticks.material[k]
                    .as_mut()
                    .expect("a rolling pair's material point");
                let stick = &mut stick;
                slipped |= self.rolling_friction::<ENERGY>(cfg, k, friction, stick, sigma, out);
                continue;
            };
            let arm = self.local_at(cfg, k, cfg.u.get(i), &S::V::zero());
            if let Some((elastic, slips)) = self.stick_or_slip(k, friction, &mut stick, arm, out) {
                slipped |= slips;
                if ENERGY {
                    out.elastic += 0.5 * k_t * elastic.dot(&elastic);
                }
                self.push_on_particle(cfg, k, i, &(elastic * -k_t), out);
            }
        }
        sticks.slips += u64::from(slipped);
    }

    /// Pair `k`'s stick with the node (contact point) at `arm` under the normal force the
    /// force pass put in `out`: the stick spring's stretch and whether it slipped, the stick
    /// point drawn after the node where it slips; `None` (the stick point on the node) where
    /// the pair carries no normal force.
    #[inline(always)]
    fn stick_or_slip(
        &self,
        k: usize,
        friction: Friction,
        stick: &mut Stick<'_, S>,
        arm: S::V,
        out: &Forces<S>,
    ) -> Option<(S::V, bool)> {
        let k_t = self.penalty;
        let (point, slipping) = (&mut *stick.point, &mut *stick.slipping);
        let normal_force = out.contact[k];
        if normal_force <= 0.0 {
            *point = arm;
            *slipping = false;
            return None;
        }
        let n = self.body_frame_normal(k, &arm);
        let offset = arm - *point;
        let tangential = offset - n * n.dot(&offset);
        let stretch = tangential.dot(&tangential).sqrt();
        let mu = if *slipping {
            friction.kinetic_coefficient
        } else {
            friction.static_coefficient
        };
        let mut elastic = tangential;
        *slipping = k_t * stretch > mu * normal_force;
        if *slipping {
            let limit = friction.kinetic_coefficient * normal_force;
            let kept = limit / k_t;
            elastic = tangential * (kept / stretch);
            *point = arm - elastic;
            *stick.dissipated += limit * (stretch - kept);
        }
        Some((elastic, *slipping))
    }

    /// [`Model::friction_forces`] of rolling pair `k`: its spring stretched by the slip of the
    /// ball's material point `sigma` that touched at the last increment, then the stick point
    /// carried on with the contact point (the stretch kept) and `sigma` moved to the material
    /// point that touches now. Returns whether it slipped.
    #[inline(never)]
    fn rolling_friction<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        k: usize,
        friction: Friction,
        stick: &mut Stick<'_, S>,
        sigma: &mut S::V,
        out: &mut Forces<S>,
    ) -> bool {
        let arm = self.material_arm(cfg, k, sigma);
        let loaded = self.stick_or_slip(k, friction, stick, arm, out);
        if let Some((elastic, _)) = loaded {
            let k_t = self.penalty;
            if ENERGY {
                out.elastic += 0.5 * k_t * elastic.dot(&elastic);
            }
            self.push_tangential(cfg, k, &(elastic * -k_t), out);
        }
        *stick.point += self.body_frame_arm(cfg, k) - arm;
        *sigma = self.touching_material(cfg, k);
        loaded.is_some_and(|(_, slips)| slips)
    }

    /// Add a tangential force `f` (the body's frame) on pair `k`'s node (a ball's contact
    /// point), and its reaction on the body there, to `out`.
    fn push_tangential(&self, cfg: &Config<S>, k: usize, f: &S::V, out: &mut Forces<S>) {
        match self.contacts[k].slave {
            Point::Particle(i) => self.push_on_particle(cfg, k, i, f, out),
            _ => self.push_tangential_at_touch(cfg, k, f, out),
        }
    }

    /// [`Model::push_tangential`] on pair `k`, whose node is particle `i`.
    fn push_on_particle(&self, cfg: &Config<S>, k: usize, i: usize, f: &S::V, out: &mut Forces<S>) {
        let c = &self.contacts[k];
        let f = self.to_world(cfg, c.body, f);
        out.add_particle(i, f);
        out.b[c.body] -= f;
        out.m[c.body] -= S::moment(&self.arm_at(cfg, k, cfg.u.get(i)), &f);
    }

    /// The stick springs of the pairs with friction about the nodes' places at t = 0 (a ball's
    /// material point that touches then), added to `out`: the tangential stiffness a sticking
    /// pair adds, for the linearisation.
    pub fn stick_forces_about_start(&self, cfg: &Config<S>, out: &mut Forces<S>) {
        for (k, c) in self.contacts.iter().enumerate() {
            if c.friction.is_none() {
                continue;
            }
            let initial = self.initial_config();
            let (start, arm) = match self.rolling_body(k) {
                // The ball's material point that touches at t = 0.
                Some(_) => {
                    let sigma = self.touching_material(&initial, k);
                    let at = |cfg: &Config<S>| self.material_arm(cfg, k, &sigma);
                    (at(&initial), at(cfg))
                }
                None => (
                    self.body_frame_arm(&initial, k),
                    self.body_frame_arm(cfg, k),
                ),
            };
            let n = self.body_frame_normal(k, &arm);
            let offset = arm - start;
            let tangential = offset - n * n.dot(&offset);
            self.push_tangential(cfg, k, &(tangential * -self.penalty), out);
        }
    }
}
