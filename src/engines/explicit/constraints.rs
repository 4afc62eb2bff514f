//! A step's boundary conditions compiled, and the generalised DOFs they leave free: moving
//! along them, projecting on them, their mass, and a bound on their highest frequency.

use super::axis::{ParticleKernel, axis_of, free_axis};
use super::body_solve::BodyOperator;
use super::model::*;
use super::space::{Lin, Space};
use crate::scene::{BoundaryCondition, Dof, Step};

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Compile a step's boundary conditions.
    pub fn constraints(&self, step: &Step) -> Constraints<S> {
        let np = self.particles.len();
        let nb = self.bodies.len();
        // Held directions per particle while the conditions are read; kept as the distinct
        // sets and an index per particle.
        let mut particle_held: Vec<HeldSet<S::V>> = vec![HeldSet::default(); np];
        let mut c = Constraints {
            held_sets: Vec::new(),
            motions: Vec::new(),
            particle_motion: Vec::new(),
            particle_kernel: ParticleKernel::General,
            along_inverse_masses: Vec::new(),
            body_held_t: vec![Vec::new(); nb],
            body_held_r: vec![Vec::new(); nb],
            body_free_r: vec![Vec::new(); nb],
            prescribed: Vec::new(),
            rotating: vec![false; nb],
            velocity_terms: vec![false; nb],
            body_operators: vec![None; nb],
        };
        for bc in &step.conditions {
            let BoundaryCondition { node, dof, value } = *bc;
            let target = match (self.points[node], dof) {
                (Point::Ground(_), _) => continue,
                (Point::Particle(i), Dof::Translation(k)) => {
                    Target::Particle(i, self.particle_axes(i)[k.min(S::DIM - 1)])
                }
                (Point::Body { body, .. }, Dof::Translation(k)) => {
                    Target::Translation(body, self.bodies[body].axes[k.min(S::DIM - 1)])
                }
                (Point::Body { body, .. }, Dof::Rotation(k)) => {
                    Target::Rotation(body, self.bodies[body].rot_axes[k + S::ROT - 3])
                }
                (Point::Particle(_), Dof::Rotation(_)) => unreachable!("validated"),
            };
            match target {
                Target::Particle(i, d) => particle_held[i].push(d),
                Target::Translation(b, d) => c.body_held_t[b].push(d),
                Target::Rotation(b, g) => c.body_held_r[b].push(g),
            }
            if let Some(v) = value {
                c.prescribed.push((target, v));
            }
        }
        // The distinct held sets, each with its projection (the last one found is tried first:
        // neighbours usually share theirs; a set not among the first 64 is added again rather
        // than searched for, so a scene of many frames compiles in linear time).
        let mut distinct: Vec<&[S::V]> = Vec::new();
        let mut last = 0;
        c.particle_motion = particle_held
            .iter()
            .map(|h| {
                let h = h.directions();
                if distinct.get(last).is_none_or(|d| *d != h) {
                    last = distinct
                        .iter()
                        .take(64)
                        .position(|d| *d == h)
                        .unwrap_or_else(|| {
                            distinct.push(h);
                            distinct.len() - 1
                        });
                }
                u32::try_from(last).expect("fewer than 2^32 distinct projections")
            })
            .collect();
        c.motions = distinct.iter().map(|h| Motion::of(h, S::DIM)).collect();
        // Along one axis where every particle is free along it alone or held along every
        // coordinate axis: a held one moves by nothing under a zero inverse mass (a finite
        // force on it times 0), and its velocity, which the step's start projects to exactly
        // 0 on each axis, leaves its other components as they are. A hold in a turned frame
        // leaves round-off in the velocity, which the general kernel moves it by: it stays
        // there.
        let held_in_all =
            |h: &&[S::V]| h.len() == S::DIM && h.iter().all(|d| axis_of(d, S::DIM).is_some());
        let mut axes = distinct
            .iter()
            .filter(|h| !held_in_all(h))
            .map(|h| free_axis(h, S::DIM));
        c.particle_kernel = match axes.next() {
            Some(Some(k)) if axes.all(|a| a == Some(k)) => ParticleKernel::Along(k),
            _ => ParticleKernel::General,
        };
        if matches!(c.particle_kernel, ParticleKernel::Along(_)) && distinct.iter().any(held_in_all)
        {
            let particles = self.inverse_masses.iter().zip(&c.particle_motion);
            let mass = |(m, set): (&f64, &u32)| {
                if held_in_all(&distinct[*set as usize]) {
                    0.0
                } else {
                    *m
                }
            };
            c.along_inverse_masses = particles.map(mass).collect();
        }
        c.held_sets = distinct.into_iter().map(<[S::V]>::to_vec).collect();
        for b in 0..nb {
            c.body_free_r[b] = S::free_rotations(&c.body_held_r[b]);
            let free_r = S::ROT - c.body_held_r[b].len();
            let free_t = S::DIM - c.body_held_t[b].len();
            c.rotating[b] = free_r > 0;
            let centre = self.bodies[b].inertia.centre;
            let offset = centre.dot(&centre) > 0.0;
            c.velocity_terms[b] = FINITE && free_r > 0 && ((offset && free_t > 0) || free_r > 1);
            // Under small rotations the configuration's mass properties are the reference ones
            // throughout (`Model::initial_config`); under finite rotation in the plane the
            // operator reads only the inertia about the axis (g·I g with g unturned, see
            // `BodyInertia::axial`) and, unless pinned, the centre, which stays zero where it
            // starts there (`Model::oriented`): the same operator, bit for bit.
            if !FINITE || (S::ROT == 1 && self.turns_in_place(&c, b)) {
                c.body_operators[b] = Some(BodyOperator::of(
                    &self.bodies[b].inertia,
                    &c.body_held_t[b],
                    &c.body_free_r[b],
                ));
            }
        }
        c
    }

    /// The solve operators of the bodies that turn in place about one free axis under finite
    /// rotation in 3D, formed at `cfg` (a dynamic step's start) for the whole step: turning
    /// about the free axis g leaves Rᵀ g, and so g·I g, as it is, and the solve has no drag
    /// terms. Where g is a coordinate axis and every turn of the body so far was about g, the
    /// orientation's components off g stay exactly zero and the value is the one every
    /// increment would form, bit for bit; otherwise it differs from it by the round-off of
    /// turning g into the body's axes.
    pub(super) fn form_turning_operators(&self, held: &mut Constraints<S>, cfg: &Config<S>) {
        if !FINITE || S::ROT == 1 {
            return; // formed with the step's constraints already
        }
        for b in 0..self.bodies.len() {
            if held.body_operators[b].is_none()
                && held.body_free_r[b].len() == 1
                && self.turns_in_place(held, b)
            {
                let (held_t, free_r) = (&held.body_held_t[b], &held.body_free_r[b]);
                held.body_operators[b] = Some(BodyOperator::of(&cfg.inertia[b], held_t, free_r));
            }
        }
    }

    /// Whether body `b` turns in place under `held`: pinned at its reference node, or with its
    /// mass centre there (which turning leaves there, `Model::oriented`), so that its solve
    /// has no drag terms and, about one free axis, an operator that turning leaves as it is.
    pub(super) fn turns_in_place(&self, held: &Constraints<S>, b: usize) -> bool {
        held.body_held_t[b].len() == S::DIM || self.bodies[b].inertia.centre == S::V::zero()
    }

    /// Move a configuration along a generalised DOF by `delta`.
    pub fn perturb(&self, cfg: &mut Config<S>, target: &Target<S>, delta: f64) {
        match target {
            Target::Particle(i, d) => cfg.u.add(*i, *d * delta),
            Target::Translation(b, d) => cfg.bu[*b] += *d * delta,
            Target::Rotation(b, g) => {
                if FINITE {
                    cfg.br[*b] = S::advance(&cfg.br[*b], &(*g * delta));
                    // The carried rounding belonged to the rotation before the jump.
                    cfg.br_carry[*b] = Default::default();
                    cfg.inertia[*b] = self.oriented(*b, &cfg.br[*b]);
                } else {
                    cfg.bth[*b] += *g * delta;
                }
            }
        }
    }

    /// The generalised force along a DOF.
    pub fn project(&self, forces: &Forces<S>, target: &Target<S>) -> f64 {
        match target {
            Target::Particle(i, d) => d.dot(&forces.p.get(*i)),
            Target::Translation(b, d) => d.dot(&forces.b[*b]),
            Target::Rotation(b, g) => g.dot(&forces.m[*b]),
        }
    }

    /// The rate of a generalised DOF.
    pub fn rate_along(&self, rates: &Rates<S>, target: &Target<S>) -> f64 {
        match target {
            Target::Particle(i, d) => d.dot(&rates.p.get(*i)),
            Target::Translation(b, d) => d.dot(&rates.b[*b]),
            Target::Rotation(b, g) => g.dot(&rates.w[*b]),
        }
    }

    /// Unit rates along a DOF.
    pub fn unit_rate(&self, target: &Target<S>) -> Rates<S> {
        let mut r = self.zero_rates();
        match target {
            Target::Particle(i, d) => r.p.set(*i, *d),
            Target::Translation(b, d) => r.b[*b] = *d,
            Target::Rotation(b, g) => r.w[*b] = *g,
        }
        r
    }

    /// Generalised mass matrix entry between two DOFs.
    pub fn mass_entry(&self, cfg: &Config<S>, k: &Target<S>, l: &Target<S>) -> f64 {
        let ul = self.unit_rate(l);
        match k {
            Target::Particle(i, d) => self.particles[*i].mass * d.dot(&ul.p.get(*i)),
            Target::Translation(b, d) => {
                let (f, _) = self.body_momentum(cfg, *b, &ul.b[*b], &ul.w[*b]);
                d.dot(&f)
            }
            Target::Rotation(b, g) => {
                let (_, m) = self.body_momentum(cfg, *b, &ul.b[*b], &ul.w[*b]);
                g.dot(&m)
            }
        }
    }

    /// Upper bounds `(λ, γ)` on the eigenvalues of M⁻¹K and on the row sums of M⁻¹C in the
    /// free DOFs at `cfg`, from the elements alone (Gershgorin: every eigenvalue of M⁻¹K lies
    /// within the largest absolute row sum), without assembling a matrix; O(elements). `None`
    /// for scenes with bodies or contact (they take the assembled linearisation).
    ///
    /// An axial spring's tangent stiffness is `c ddᵀ + (T/L)(I − ddᵀ)`, T its tension; each
    /// entry between unit axes e, f is bounded by `c|e·d||d·f| + (|T|/L)(|e·f| + |e·d||d·f|)`.
    pub fn frequency_bound(&self, cfg: &Config<S>, held: &Constraints<S>) -> Option<(f64, f64)> {
        if !self.bodies.is_empty() || !self.contacts.is_empty() {
            return None;
        }
        let free = |i: usize| free_axes(self.particle_axes(i), held.particle_held(i));
        let mut stiffness = vec![0.0; self.particles.len() * S::DIM];
        let mut damping = vec![0.0; self.particles.len() * S::DIM];
        let entry = |e: &S::V, f: &S::V, d: &S::V, c: f64, t: f64| {
            let along = e.dot(d).abs() * d.dot(f).abs();
            c * along + t * (e.dot(f).abs() + along)
        };
        // Add one element's row sums to the rows of its particle ends.
        let add = |rows: &mut Vec<f64>, ends: [&Point<S>; 2], d: &S::V, c: f64, t: f64| {
            for end in ends {
                let Point::Particle(i) = end else { continue };
                let (axes, count) = free(*i);
                for (a, e) in axes[..count].iter().enumerate() {
                    let mut sum = 0.0;
                    for other in ends {
                        if let Point::Particle(j) = other {
                            let (axes, count) = free(*j);
                            let row = axes[..count].iter().map(|f| entry(e, f, d, c, t));
                            sum += row.sum::<f64>();
                        }
                    }
                    rows[*i * S::DIM + a] += sum;
                }
            }
        };
        let ground = Point::Ground(S::V::zero());
        for (rows, grounded) in [
            (&mut stiffness, &self.grounded_springs),
            (&mut damping, &self.grounded_dashpots),
        ] {
            for s in grounded {
                if let Some(d) = s.direction {
                    add(rows, [&s.point, &ground], &d, s.c, 0.0);
                }
            }
        }
        let direction = |s: &TwoPoint<S>| {
            if s.axial && FINITE {
                let l = s.span0 + (self.displacement(cfg, &s.b) - self.displacement(cfg, &s.a));
                let len = l.dot(&l).sqrt();
                (l * (1.0 / len), len)
            } else {
                (s.direction, s.length0)
            }
        };
        for s in self.line_springs.iter() {
            let [a, b] = s.ends();
            add(&mut stiffness, [&a, &b], &s.direction, s.c, 0.0);
        }
        for s in &self.springs {
            let (d, len) = direction(s);
            let tension = if s.axial && FINITE {
                (s.c * (len - s.length0) / len).abs()
            } else {
                0.0
            };
            add(&mut stiffness, [&s.a, &s.b], &d, s.c, tension);
        }
        for s in &self.dashpots {
            let (d, _) = direction(s);
            add(&mut damping, [&s.a, &s.b], &d, s.c, 0.0);
        }
        let largest = |rows: &[f64]| {
            rows.iter()
                .enumerate()
                .map(|(r, x)| x / self.particles[r / S::DIM].mass)
                .fold(0.0, f64::max)
        };
        Some((largest(&stiffness), largest(&damping)))
    }

    /// Free generalised DOFs under a step's constraints.
    pub fn free_dofs(&self, held: &Constraints<S>) -> Vec<Target<S>> {
        let mut out = Vec::new();
        for i in 0..self.particles.len() {
            let (free, count) = free_axes(self.particle_axes(i), held.particle_held(i));
            out.extend(free[..count].iter().map(|d| Target::Particle(i, *d)));
        }
        for (b, body) in self.bodies.iter().enumerate() {
            let (free, count) = free_axes(&body.axes, &held.body_held_t[b]);
            out.extend(free[..count].iter().map(|d| Target::Translation(b, *d)));
            let (free, count) = free_axes(&body.rot_axes, &held.body_held_r[b]);
            out.extend(free[..count].iter().map(|g| Target::Rotation(b, *g)));
        }
        out
    }

    /// How many generalised DOFs a step's constraints leave free ([`Model::free_dofs`]'s
    /// length, without listing them).
    pub fn free_dof_count(&self, held: &Constraints<S>) -> usize {
        let particles = (0..self.particles.len())
            .map(|i| free_axes(self.particle_axes(i), held.particle_held(i)).1);
        let bodies = self.bodies.iter().enumerate().map(|(b, body)| {
            free_axes(&body.axes, &held.body_held_t[b]).1
                + free_axes(&body.rot_axes, &held.body_held_r[b]).1
        });
        particles.sum::<usize>() + bodies.sum::<usize>()
    }
}

/// The axes of a node's frame that the held directions leave free (no held direction within
/// 60° of them): the first `count` of the array.
fn free_axes<V: Lin>(axes: &[V], held: &[V]) -> ([V; 3], usize) {
    let mut out = [V::zero(); 3];
    let mut count = 0;
    for a in axes {
        if held.iter().all(|h| h.dot(a).abs() < 0.5) {
            out[count] = *a;
            count += 1;
        }
    }
    (out, count)
}

/// The directions held on one particle while a step's conditions are read (at most three:
/// a fixed array, so that a scene of a million particles allocates none per particle).
#[derive(Debug, Clone, Copy)]
struct HeldSet<V: Lin> {
    directions: [V; 3],
    count: usize,
}

impl<V: Lin> Default for HeldSet<V> {
    fn default() -> Self {
        HeldSet {
            directions: [V::zero(); 3],
            count: 0,
        }
    }
}

impl<V: Lin> HeldSet<V> {
    /// Hold `d` too (a fourth direction adds nothing in three dimensions and is left out).
    fn push(&mut self, d: V) {
        if self.count < 3 {
            self.directions[self.count] = d;
            self.count += 1;
        }
    }

    fn directions(&self) -> &[V] {
        &self.directions[..self.count]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case;
    use crate::engines::explicit::space::Planar;
    use crate::scene::Scene;
    use nalgebra::{Matrix3, Vector2};

    /// springs_grounded_b and its model: ground 11, middle mass 12 (held in every direction in
    /// the dynamic step, `steps[1]`), end mass 13 (held across x).
    fn grounded_b() -> (Scene, Model<Planar, true>) {
        let path = case::cases_dir().join("springs_grounded_b.toml");
        let scene = case::load(&path).expect("the seed case");
        let model = Model::compile(&scene, 1.0);
        (scene, model)
    }

    fn particle(scene: &Scene, model: &Model<Planar, true>, name: &str) -> usize {
        match model.points[scene.node_named(name).unwrap()] {
            Point::Particle(i) => i,
            _ => panic!("node {name} is a particle"),
        }
    }

    /// The dynamic step holds 12 on both axes and leaves 13 free along x alone: the particles
    /// step along x, 12 with no inverse mass, 13 with its own (1/0.02588, the case's mass).
    /// Released along x, 12 is free along x too and the model's masses serve; released along
    /// y instead, the particles move along different axes and each is projected; held on both
    /// axes of a frame turned by 30°, it is not held on the coordinate axes, and each is
    /// projected too.
    #[test]
    fn a_particle_held_on_every_axis_steps_along_the_axis_with_no_inverse_mass() {
        let (mut scene, model) = grounded_b();
        let held = model.constraints(&scene.steps[1]);
        assert_eq!(held.particle_kernel, ParticleKernel::Along(0));
        let masses = &held.along_inverse_masses;
        assert_eq!(masses[particle(&scene, &model, "12")], 0.0);
        assert_eq!(masses[particle(&scene, &model, "13")], 1.0 / 0.02588);
        let n12 = scene.node_named("12").unwrap();
        let releasing = |k: usize| {
            let mut step = scene.steps[1].clone();
            let released = Dof::Translation(k);
            step.conditions
                .retain(|c| c.node != n12 || c.dof != released);
            model.constraints(&step)
        };
        let along_x = releasing(0);
        assert_eq!(along_x.particle_kernel, ParticleKernel::Along(0));
        assert!(along_x.along_inverse_masses.is_empty());
        assert_eq!(releasing(1).particle_kernel, ParticleKernel::General);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        scene.nodes[n12].frame = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let turned = Model::<Planar, true>::compile(&scene, 1.0);
        let held = turned.constraints(&scene.steps[1]);
        assert_eq!(held.particle_kernel, ParticleKernel::General);
    }

    /// springs_n2n_c's dynamic step holds 102 and 103 across the 45° line of their frame: each
    /// moves on the line through it along (1, 1)/√2, the springs' and the dashpot's, and on no
    /// line 1e-13 rad off it (a cosine of 1e-13 with the hold, ten times [`ACROSS`]), while
    /// 1e-16 rad off, a direction formed with round-off, it still does. Released across the
    /// line, 103 moves on no line; 12 of springs_grounded_b, held on both axes, on every line.
    #[test]
    fn a_particle_held_across_a_line_is_confined_to_it() {
        let scene = case::load(&case::cases_dir().join("springs_n2n_c.toml")).unwrap();
        let model = Model::<Planar, true>::compile(&scene, 1.0);
        let motion = |held: &Constraints<Planar>, i: usize| *held.particle_projection(i);
        let at = |angle: f64| Vector2::new(angle.cos(), angle.sin());
        let line = std::f64::consts::FRAC_PI_4;
        let held = model.constraints(&scene.steps[1]);
        for name in ["102", "103"] {
            let m = motion(&held, particle(&scene, &model, name));
            assert!(m.confines_to(Vector2::new(1.0, 1.0).normalize()), "{name}");
            assert!(m.confines_to(at(line + 1e-16)), "{name}");
            assert!(!m.confines_to(at(line + 1e-13)), "{name}");
            assert!(!m.confines_to(Vector2::x()), "{name}");
        }
        let n103 = scene.node_named("103").unwrap();
        let mut released = scene.steps[1].clone();
        released.conditions.retain(|c| c.node != n103);
        let free = model.constraints(&released);
        let m103 = motion(&free, particle(&scene, &model, "103"));
        assert!(!m103.confines_to(Vector2::new(1.0, 1.0).normalize()));
        let (scene_b, model_b) = grounded_b();
        let held_b = model_b.constraints(&scene_b.steps[1]);
        let m12 = motion(&held_b, particle(&scene_b, &model_b, "12"));
        assert!(m12.confines_to(Vector2::x()) && m12.confines_to(at(0.3)));
    }

    /// An increment of that step by the fused pass, then a further motion by the pass that takes
    /// formed accelerations, under the axis kernel and under the projections, from a state with
    /// every component of both particles set (but the velocities and carries on their held axes
    /// other than x, which the step's start leaves 0): the same positions, carries and
    /// velocities, bit for bit, and the same accelerations (12's ±0 for +0).
    #[test]
    fn the_axis_kernel_with_a_held_particle_steps_as_the_projections_do() {
        let (scene, model) = grounded_b();
        let along = model.constraints(&scene.steps[1]);
        let mut general = along.clone();
        general.particle_kernel = ParticleKernel::General;
        let mut cfg = model.initial_config();
        let (mut forces, mut v, mut carry) =
            (model.zero_forces(), model.zero_rates(), model.zero_rates());
        for (i, name) in ["12", "13"].iter().enumerate() {
            let p = particle(&scene, &model, name);
            let x = 0.3 + i as f64;
            cfg.u.set(p, Vector2::new(x, -0.7 * x));
            forces.add_particle(p, Vector2::new(-2.5 * x, 1.5 + x));
            carry.p.set(p, Vector2::new(3e-17 * (1.0 + x), 0.0));
        }
        v.p.set(particle(&scene, &model, "13"), Vector2::new(0.9, 0.0));
        let h = 5.0e-5;
        let step = |held: &Constraints<Planar>| {
            let (mut cfg, mut forces, mut v, mut carry) =
                (cfg.clone(), forces.clone(), v.clone(), carry.clone());
            let mut acc = model.zero_rates();
            model.particle_accelerations(&forces, held, &mut acc);
            let formed = acc.p.clone();
            model.step_particles::<true>(
                &mut cfg,
                &mut carry,
                h,
                &mut forces,
                held,
                &mut v,
                &mut acc,
            );
            assert_eq!(acc.p, formed, "the fused pass forms the same accelerations");
            model.move_particles(&mut cfg, &mut carry, h, held, &mut v, &acc);
            (cfg.u, carry.p, v.p, acc.p)
        };
        let (by_axis, by_projection) = (step(&along), step(&general));
        let bits =
            |x: &Vectors<Vector2<f64>>| x.flat().iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&by_axis.0), bits(&by_projection.0), "positions");
        assert_eq!(bits(&by_axis.1), bits(&by_projection.1), "carries");
        assert_eq!(bits(&by_axis.2), bits(&by_projection.2), "velocities");
        assert_eq!(by_axis.3, by_projection.3, "accelerations, ±0 alike");
        // Both pushed back along x: 12, held, does not move; 13, free, slows.
        let velocity = |name| by_axis.2.get(particle(&scene, &model, name));
        assert_eq!(velocity("12"), Vector2::zeros());
        assert!(velocity("13").x < 0.9);
    }
}
