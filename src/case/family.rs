//! A family of generated scenes for the cost study: any number of bodies, contacts and
//! particles, with springs and dashpots of every kind, written as case files and read through
//! the same parser and validation as a user's own case.
//!
//! A scene of the family (`Size { dimension, bodies, contacts, particles }`):
//! - body `b` is free (no DOF held in 2D), its reference node at (4b, 0), its mass and
//!   inertia lumped at the reference node. Each is held to the ground by two axial springs
//!   (along y and x at t = 0) from a body point and a grounded rotational spring at its
//!   reference node, so that every mode has a stiffness and the motion stays small: the
//!   stable increment of the start holds throughout (a body free to swing on one spring
//!   turns by a radian and stiffens beyond it). With `body_velocity`, odd bodies carry their
//!   mass on two point masses off the reference node (the centripetal and gyroscopic terms
//!   enter) and every body has a fixed-direction dashpot and a grounded rotational one;
//! - particle `p` (mass 1) sits on the right face x = 4b + 1 of body `b = p mod bodies`. It is
//!   held along x by a fixed-direction spring to a ground node one unit to its right; a second
//!   spring cycles through the kinds (grounded on uy, axial to the ground node, axial to a
//!   body point), and every other particle has a dashpot cycling through the kinds (grounded,
//!   fixed-direction, axial between two particles where there is a neighbour);
//! - the first `contacts` particles are in contact with their body's face (closed at t = 0)
//!   and pressed on it by a load; every particle starts with a small velocity across the face.
//!
//! Stiffnesses of 1e4 N/m, a penalty of 1e6 N/m, masses of about 1 kg: the scene's fastest
//! modes are near 10^3 to 10^4 rad/s. The cost study picks the increment from the engine's
//! stable increment, not from this file.

use crate::scene::{Dimension, Scene};
use std::fmt::Write;
use std::path::Path;

/// The size of one generated scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size {
    /// 2D or 3D.
    pub dimension: Dimension,
    /// Free rigid bodies (at least one).
    pub bodies: usize,
    /// Particles in contact with a body's face (at most `particles`).
    pub contacts: usize,
    /// Particles (at least one).
    pub particles: usize,
    /// Whether forces read the velocity of bodies: odd bodies off their centre of mass and
    /// dashpots on every body (the centred velocity is then found by iteration). Without,
    /// every body is lumped at its reference node and only particles carry dashpots.
    pub body_velocity: bool,
}

impl Size {
    /// The case id: `family_2d_b4_c1_p16`.
    pub fn id(&self) -> String {
        let d = match self.dimension {
            Dimension::Two => 2,
            Dimension::Three => 3,
        };
        let velocity = if self.body_velocity { "_v" } else { "" };
        format!(
            "family_{d}d_b{}_c{}_p{}{velocity}",
            self.bodies, self.contacts, self.particles
        )
    }

    /// The scene, through the case parser (an error names it `generated/<id>.toml`).
    pub fn scene(&self) -> Result<Scene, String> {
        let path = Path::new("generated").join(format!("{}.toml", self.id()));
        super::parse(&self.toml(), &path).map_err(|e| e.to_string())
    }

    /// The scene as a case file.
    pub fn toml(&self) -> String {
        assert!(self.bodies >= 1 && self.particles >= 1 && self.contacts <= self.particles);
        let mut s = String::new();
        let d = match self.dimension {
            Dimension::Two => 2,
            Dimension::Three => 3,
        };
        let _ = writeln!(
            s,
            "id = \"{}\"\ntitle = \"Generated scene\"\nfamily = \"rigid_body\"\ndimension = {d}\n",
            self.id()
        );
        s += "[time]\nincrement = 1.0e-5\n\n[contact]\npenalty_stiffness = 1.0e6\n\n";
        self.columns(&mut s);
        for b in 0..self.bodies {
            self.body(&mut s, b);
        }
        for p in 0..self.particles {
            self.particle(&mut s, p);
        }
        s += "[[steps]]\nkind = \"dynamic\"\nduration = 0.01\n";
        s += &self.held();
        s
    }

    /// In 3D, the motion is kept in the plane z = 0 as in the seed cases' 3D twins: the
    /// bodies' uz, rx and ry and the particles' uz are held (free, a body turns out of the
    /// plane by a radian and stiffens beyond the stable increment of the start).
    fn held(&self) -> String {
        if self.dimension == Dimension::Two {
            return String::new();
        }
        let bodies = (0..self.bodies)
            .map(|b| format!("{{ node = \"R{b}\", dofs = [\"uz\", \"rx\", \"ry\"] }}"));
        let particles =
            (0..self.particles).map(|p| format!("{{ node = \"N{p}\", dofs = [\"uz\"] }}"));
        let all: Vec<String> = bodies.chain(particles).collect();
        format!("hold = [\n    {},\n]\n", all.join(",\n    "))
    }

    /// The rigid-body contract's columns: body 0's turn, its reference node's and particle
    /// 0's x, and contact 0's force (identically zero without contacts).
    fn columns(&self, s: &mut String) {
        let x = self.vector(1.0, 0.0);
        s.push_str("[output]\nrows = 200\n\n");
        s.push_str("[[output.columns]]\nname = \"rz\"\nrotation = \"body0\"\n\n");
        let _ = writeln!(
            s,
            "[[output.columns]]\nname = \"ux\"\ndisplacement = \"R0\"\ndirection = {x}\n"
        );
        let _ = writeln!(
            s,
            "[[output.columns]]\nname = \"ux_node\"\ndisplacement = \"N0\"\ndirection = {x}\n"
        );
        s.push_str("[[output.columns]]\nname = \"contact_force\"\n");
        s.push_str(if self.contacts > 0 {
            "contact_force = \"c0\"\n\n"
        } else {
            "zero = \"no contact pair\"\n\n"
        });
    }

    /// `[x, y]` or `[x, y, 0.0]`.
    fn vector(&self, x: f64, y: f64) -> String {
        match self.dimension {
            Dimension::Two => format!("[{x:?}, {y:?}]"),
            Dimension::Three => format!("[{x:?}, {y:?}, 0.0]"),
        }
    }

    fn node(&self, s: &mut String, id: &str, (x, y): (f64, f64), role: &str) {
        let _ = writeln!(
            s,
            "[[nodes]]\nid = \"{id}\"\nat = {}\n{role}",
            self.vector(x, y)
        );
    }

    fn element(&self, s: &mut String, table: &str, kind: &str, nodes: &[&str], rest: &str) {
        let nodes: Vec<String> = nodes.iter().map(|n| format!("\"{n}\"")).collect();
        let _ = writeln!(
            s,
            "[[{table}]]\nkind = \"{kind}\"\nnodes = [{}]\n{rest}",
            nodes.join(", ")
        );
    }

    /// Body `b`: its nodes, its mass, its springs and dashpots to the ground.
    fn body(&self, s: &mut String, b: usize) {
        let x = 4.0 * b as f64;
        let (reference, point, ground) = (format!("R{b}"), format!("S{b}"), format!("G{b}"));
        self.node(s, &reference, (x, 0.0), "");
        self.node(s, &point, (x + 1.0, 1.0), &format!("body = \"body{b}\"\n"));
        self.node(s, &ground, (x + 1.0, 2.0), "fixed = true\n");
        let across = format!("H{b}");
        self.node(s, &across, (x + 2.0, 1.0), "fixed = true\n");
        let (inertia, angular) = match self.dimension {
            Dimension::Two => ("0.5".to_string(), "0.3".to_string()),
            Dimension::Three => ("[0.5, 0.6, 0.7]".to_string(), "[0.0, 0.0, 0.3]".to_string()),
        };
        if b.is_multiple_of(2) || !self.body_velocity {
            let _ = writeln!(
                s,
                "[[bodies]]\nid = \"body{b}\"\nreference = \"{reference}\"\nmass = 2.0\ninertia = {inertia}\n"
            );
        } else {
            let _ = writeln!(
                s,
                "[[bodies]]\nid = \"body{b}\"\nreference = \"{reference}\"\n"
            );
            for (k, dx) in [(0, -0.5), (1, 0.5)] {
                let id = format!("M{b}_{k}");
                self.node(s, &id, (x + dx, -1.0), &format!("body = \"body{b}\"\n"));
                let _ = writeln!(s, "[[masses]]\nnode = \"{id}\"\nmass = 1.0\n");
            }
        }
        let _ = writeln!(
            s,
            "[[initial_velocities]]\nnode = \"{reference}\"\nvelocity = {}\nangular = {angular}\n",
            self.vector(0.0, 0.1)
        );
        self.element(
            s,
            "springs",
            "axial",
            &[&point, &ground],
            "stiffness = 1.0e4\n",
        );
        self.element(
            s,
            "springs",
            "axial",
            &[&point, &across],
            "stiffness = 1.0e4\n",
        );
        self.element(
            s,
            "springs",
            "grounded",
            &[&reference],
            "dof = \"rz\"\nstiffness = 1.0e3\n",
        );
        if self.body_velocity {
            let along_y = format!("direction = {}\ndamping = 1.0\n", self.vector(0.0, 1.0));
            self.element(
                s,
                "dashpots",
                "fixed_direction",
                &[&point, &ground],
                &along_y,
            );
            self.element(
                s,
                "dashpots",
                "grounded",
                &[&reference],
                "dof = \"rz\"\ndamping = 0.1\n",
            );
        }
    }

    /// Particle `p`: its node, mass, springs, dashpot, contact and load.
    fn particle(&self, s: &mut String, p: usize) {
        let b = p % self.bodies;
        let row = (p / self.bodies) as f64;
        let (x, y) = (4.0 * b as f64 + 1.0, -0.5 - 0.25 * row);
        let (node, ground) = (format!("N{p}"), format!("F{p}"));
        self.node(s, &node, (x, y), "");
        self.node(s, &ground, (x + 1.0, y), "fixed = true\n");
        let _ = writeln!(s, "[[masses]]\nnode = \"{node}\"\nmass = 1.0\n");
        let along_x = format!("direction = {}\n", self.vector(1.0, 0.0));
        self.element(
            s,
            "springs",
            "fixed_direction",
            &[&node, &ground],
            &format!("{along_x}stiffness = 1.0e4\n"),
        );
        let body_point = format!("S{b}");
        match p % 3 {
            0 => self.element(
                s,
                "springs",
                "grounded",
                &[&node],
                "dof = \"uy\"\nstiffness = 1.0e4\n",
            ),
            1 => self.element(
                s,
                "springs",
                "axial",
                &[&node, &ground],
                "stiffness = 1.0e4\n",
            ),
            _ => self.element(
                s,
                "springs",
                "axial",
                &[&node, &body_point],
                "stiffness = 1.0e4\n",
            ),
        }
        self.particle_dashpot(s, p, &node, &ground, &along_x);
        let _ = writeln!(
            s,
            "[[initial_velocities]]\nnode = \"{node}\"\nvelocity = {}\n",
            self.vector(0.05, 0.02)
        );
        if p < self.contacts {
            let _ = writeln!(
                s,
                "[[contacts]]\nid = \"c{p}\"\nnode = \"{node}\"\nbody = \"body{b}\"\nface_point = {}\nface_normal = {}\n",
                self.vector(x, y),
                self.vector(1.0, 0.0)
            );
            let _ = writeln!(
                s,
                "[[loads]]\nnode = \"{node}\"\nforce = {}\n",
                self.vector(-10.0, 0.0)
            );
        }
    }

    /// Particle `p`'s dashpot, on particles 0, 2 and 4 of every six: grounded on ux, of fixed
    /// direction to its ground node, axial to the particle one row before it (or to its ground
    /// node in the first row).
    fn particle_dashpot(&self, s: &mut String, p: usize, node: &str, ground: &str, along_x: &str) {
        let neighbour = (p >= self.bodies).then(|| format!("N{}", p - self.bodies));
        match (p % 6, neighbour) {
            (0, _) => self.element(
                s,
                "dashpots",
                "grounded",
                &[node],
                "dof = \"ux\"\ndamping = 1.0\n",
            ),
            (2, _) => self.element(
                s,
                "dashpots",
                "fixed_direction",
                &[node, ground],
                &format!("{along_x}damping = 1.0\n"),
            ),
            (4, Some(n)) => self.element(s, "dashpots", "axial", &[node, &n], "damping = 1.0\n"),
            (4, None) => self.element(s, "dashpots", "axial", &[node, ground], "damping = 1.0\n"),
            _ => {}
        }
    }
}
