//! The force pass: springs, contact penalties and loads at a configuration; the dashpots at a
//! velocity; the work of the loads.

use super::model::*;
use super::space::{Lin, Space};

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Position-dependent forces: springs, contact, loads. Fills `out` (cleared first), with
    /// the elastic energy.
    pub fn forces(
        &self,
        cfg: &Config<S>,
        mode: ContactMode,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        self.forces_with::<true>(cfg, mode, out, counters);
    }

    /// [`Model::forces`], with the elastic energy summed only when `ENERGY` (an increment that
    /// writes no row does not read it; the sum is a chain of dependent additions, one per
    /// element, that would otherwise set the pace of a large scene's force pass). The forces
    /// are the same either way, bit for bit; without `ENERGY`, `out.elastic` is 0.
    pub fn forces_with<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        mode: ContactMode,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        out.clear();
        counters.force_evaluations += 1;
        let elastic = self.grounded_spring_forces::<ENERGY>(cfg, out);
        let line = &self.line_springs;
        let mut elastic = line.add_forces::<ENERGY>(&cfg.u, out, elastic);
        for s in &self.springs {
            let stretch = self.displacement(cfg, &s.b) - self.displacement(cfg, &s.a);
            let (e, dir) = if s.axial && FINITE {
                let l = s.span0 + stretch;
                let square = l.dot(&l);
                // 1/|l| as |l|·(1/|l|²): the square root and the division run side by side
                // instead of one after the other on the increment's chain.
                let len = square.sqrt();
                (len - s.length0, l * (len * (1.0 / square)))
            } else {
                (s.direction.dot(&stretch), s.direction)
            };
            if ENERGY {
                elastic += 0.5 * s.c * e * e;
            }
            let f = dir * (s.c * e);
            self.apply(cfg, &s.a, f, out);
            self.apply(cfg, &s.b, -f, out);
        }
        if !self.contacts.is_empty() && !matches!(mode, ContactMode::Off) {
            for (k, c) in self.contacts.iter().enumerate() {
                counters.contact_evaluations += 1;
                let Point::Particle(i) = c.slave else {
                    elastic += self.touch_penalty::<ENERGY>(cfg, k, mode, out);
                    continue;
                };
                let (d, n) = self.gap_at(cfg, k, cfg.u.get(i));
                let f = self.penalty_force(k, mode, d);
                if ENERGY && !matches!(mode, ContactMode::Given(_)) {
                    elastic += 0.5 * f * f / self.penalty;
                }
                out.contact[k] = f;
                out.gap[k] = d;
                self.push_on_node(cfg, k, i, n, f, out);
            }
        }
        for l in &self.loads {
            self.apply(cfg, &l.point, l.force, out);
        }
        out.elastic = elastic;
    }

    /// Add the grounded springs' forces to `out`; their elastic energy (0 unless `ENERGY`).
    #[inline(always)]
    pub(super) fn grounded_spring_forces<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        out: &mut Forces<S>,
    ) -> f64 {
        let mut elastic = 0.0;
        for s in &self.grounded_springs {
            if let Some(d) = s.direction {
                let u = d.dot(&self.displacement(cfg, &s.point));
                if ENERGY {
                    elastic += 0.5 * s.c * u * u;
                }
                self.apply(cfg, &s.point, d * (-s.c * u), out);
            }
            if let Some((b, axis)) = s.rotation {
                let angle = self.rotation_about(cfg, b, &axis);
                if ENERGY {
                    elastic += 0.5 * s.c * angle * angle;
                }
                out.m[b] -= axis * (s.c * angle);
            }
        }
        elastic
    }

    /// Add a normal force `f` (positive: pushing the node out of its surface) on pair `k` to
    /// `out`, as the penalty acts.
    pub fn push_along_normal(&self, cfg: &Config<S>, k: usize, f: f64, out: &mut Forces<S>) {
        let (_, n) = self.gap(cfg, k);
        self.push_along(cfg, k, n, f, out);
    }

    /// The normal force of pair `k` at gap `d` under `mode`.
    #[inline(always)]
    pub(super) fn penalty_force(&self, k: usize, mode: ContactMode, d: f64) -> f64 {
        match mode {
            ContactMode::Unilateral => self.penalty * (-d).max(0.0),
            ContactMode::Bilateral => -self.penalty * (d - self.contacts[k].open_gap),
            ContactMode::Given(f) => f[k],
            ContactMode::Off => unreachable!(),
        }
    }

    /// Add a force `f` along `n` on pair `k`'s node (a ball's contact point), and its reaction
    /// on the body, to `out`.
    #[inline(always)]
    pub(super) fn push_along(
        &self,
        cfg: &Config<S>,
        k: usize,
        n: S::V,
        f: f64,
        out: &mut Forces<S>,
    ) {
        match self.contacts[k].slave {
            Point::Particle(i) => self.push_on_node(cfg, k, i, n, f, out),
            _ => self.push_at_touch(cfg, k, &n, n * f, out),
        }
    }

    /// [`Model::push_along`] on pair `k`, whose node is particle `i`.
    #[inline(always)]
    fn push_on_node(
        &self,
        cfg: &Config<S>,
        k: usize,
        i: usize,
        n: S::V,
        f: f64,
        out: &mut Forces<S>,
    ) {
        let c = &self.contacts[k];
        out.add_particle(i, n * f);
        out.b[c.body] -= n * f;
        out.m[c.body] -= S::moment(&self.arm_at(cfg, k, cfg.u.get(i)), &n) * f;
    }

    /// One over the mass pair `k`'s normal force moves (the body's turning left out).
    pub fn contact_inverse_mass(&self, k: usize) -> f64 {
        self.contacts[k].inverse_mass
    }

    /// Add dashpot forces at velocities `vel` to `out`, and their dissipation power.
    pub fn damping(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        let mut directions = Vec::new();
        self.dashpot_directions(cfg, &mut directions);
        self.damping_along(cfg, &directions, vel, out, counters);
    }

    /// The line of action of every two-point dashpot at `cfg` (axial ones turn with their
    /// nodes under finite rotation), for [`Model::damping_along`]: a configuration's
    /// directions serve every velocity iterate of an increment.
    pub fn dashpot_directions(&self, cfg: &Config<S>, out: &mut Vec<S::V>) {
        out.clear();
        out.extend(self.dashpots.iter().enumerate().map(|(k, s)| {
            if s.axial && FINITE {
                self.dashpot_line(cfg, k)
            } else {
                s.direction
            }
        }));
    }

    /// The unit line from end a to end b of two-point dashpot `k` at `cfg` (not finite where
    /// its ends coincide).
    #[inline]
    pub fn dashpot_line(&self, cfg: &Config<S>, k: usize) -> S::V {
        let l = self.dashpot_span(cfg, k);
        l * (1.0 / l.dot(&l).sqrt())
    }

    /// The vector from end a to end b of two-point dashpot `k` at `cfg`: its line of action,
    /// not normalised.
    #[inline(always)]
    pub fn dashpot_span(&self, cfg: &Config<S>, k: usize) -> S::V {
        let s = &self.dashpots[k];
        s.span0 + (self.displacement(cfg, &s.b) - self.displacement(cfg, &s.a))
    }

    /// Every dashpot as a [`ParticleDashpot`], when every one acts between particles or a
    /// particle and the ground along a line (no body end, no rotational dashpot, no contact
    /// dashpot); None otherwise. Dashpots on the ground alone are left out (they never act).
    pub fn particle_dashpots(&self) -> Option<Vec<ParticleDashpot<S>>> {
        if self.contacts.iter().any(|c| c.damping != 0.0) {
            return None;
        }
        let mut out = Vec::new();
        for s in &self.grounded_dashpots {
            let (Some(d), None) = (s.direction, s.rotation) else {
                return None;
            };
            if let Some(b) = s.point.particle_or_ground()?
                && s.c != 0.0
            {
                out.push(ParticleDashpot {
                    c: s.c,
                    a: None,
                    b: Some(b),
                    line: DashpotLine::Fixed(d),
                });
            }
        }
        for (k, s) in self.dashpots.iter().enumerate() {
            let (a, b) = (s.a.particle_or_ground()?, s.b.particle_or_ground()?);
            if (a.is_some() || b.is_some()) && s.c != 0.0 {
                // Only an axial dashpot under finite rotation turns with its nodes
                // (`Model::dashpot_directions`); every other keeps its direction.
                let line = if s.axial && FINITE {
                    DashpotLine::TwoPoint {
                        dashpot: k,
                        scale: 1.0 / s.length0,
                    }
                } else {
                    DashpotLine::Fixed(s.direction)
                };
                out.push(ParticleDashpot { c: s.c, a, b, line });
            }
        }
        Some(out)
    }

    /// `P M⁻¹ f` for particle `i` under the step's constraints: the acceleration a force `f`
    /// gives it.
    #[inline]
    pub fn particle_response(&self, held: &Constraints<S>, i: usize, f: S::V) -> S::V {
        held.particle_projection(i)
            .project(f * self.inverse_masses[i])
    }

    /// [`Model::damping`] with the two-point dashpots' directions given (from
    /// [`Model::dashpot_directions`] at the same `cfg`).
    pub fn damping_along(
        &self,
        cfg: &Config<S>,
        directions: &[S::V],
        vel: &Rates<S>,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        counters.damping_evaluations += 1;
        let mut power = 0.0;
        for s in &self.grounded_dashpots {
            if let Some(d) = s.direction {
                let rate = d.dot(&self.velocity(cfg, vel, &s.point));
                power += s.c * rate * rate;
                self.apply(cfg, &s.point, d * (-s.c * rate), out);
            }
            if let Some((b, axis)) = s.rotation {
                let rate = vel.w[b].dot(&axis);
                power += s.c * rate * rate;
                out.m[b] -= axis * (s.c * rate);
            }
        }
        for (s, dir) in self.dashpots.iter().zip(directions) {
            let rate = dir.dot(&(self.velocity(cfg, vel, &s.b) - self.velocity(cfg, vel, &s.a)));
            power += s.c * rate * rate;
            let f = *dir * (s.c * rate);
            self.apply(cfg, &s.a, f, out);
            self.apply(cfg, &s.b, -f, out);
        }
        // Contact dashpots act while the node penetrates, against the gap's rate.
        for (k, c) in self.contacts.iter().enumerate() {
            if c.damping == 0.0 {
                continue;
            }
            let (d, n) = self.gap(cfg, k);
            if d >= 0.0 {
                continue;
            }
            let rate = self.normal_rate(cfg, vel, k, &n);
            power += c.damping * rate * rate;
            let f = -c.damping * rate;
            out.contact[k] += f;
            self.push_along(cfg, k, n, f, out);
        }
        out.dissipation = power;
    }

    /// Work of the constant loads since configuration `from`.
    pub fn external_work(&self, cfg: &Config<S>, from: &Config<S>) -> f64 {
        self.loads
            .iter()
            .map(|l| {
                l.force
                    .dot(&(self.displacement(cfg, &l.point) - self.displacement(from, &l.point)))
            })
            .sum()
    }
}
