//! What a scene is made of, drawn: rigid bodies, springs and dashpots, the supports of the DOFs
//! held during the run, contact faces, nodes, reference nodes and centres of mass.

use super::canvas::{
    ARROW_LAYER, BODY_LAYER, ELEMENT_LAYER, Label, MARK_LAYER, NODE_LAYER, SUPPORT_LAYER,
};
use super::geometry::{V2, hull, polygon_area, v2};
use super::symbols::{Kind, best_side, centre_of_mass, ground, link, parallel, support};
use super::view::ground_direction;
use super::{
    BODY, CONTACT, FACE_LENGTH, GROUNDED_LENGTH, INK, PARALLEL_SPACING, SUPPORT, Sketch,
    mass_centre, outline,
};
use crate::scene::{
    Attachment, BodyId, BoundaryCondition, Connection, ContactPair, Dimension, Dof, Element, Node,
    NodeId, Scene, StepKind,
};
use nalgebra::Vector3;
use plotters::prelude::*;

/// Elements drawn together (in parallel): their kinds and names.
type Group<'a> = Vec<(Kind, &'a str)>;
/// Elements between one pair of nodes: the nodes, the first one's direction, the elements.
type Pair<'a> = ([NodeId; 2], Vector3<f64>, Group<'a>);
/// Grounded elements on one DOF of one node: the node, the DOF, the elements.
type Grounded<'a> = (NodeId, Dof, Group<'a>);

impl Sketch<'_> {
    /// Rigid bodies: the outline of their nodes (and contact face points), lightly filled.
    pub(super) fn bodies(&mut self) {
        let scene = self.scene;
        for (k, body) in scene.bodies.iter().enumerate() {
            self.present.body = true;
            let edge = self.body_outline(k);
            if edge.len() >= 3 {
                self.canvas.fill(BODY_LAYER, edge.clone(), BODY.mix(0.13));
                let mut closed = edge.clone();
                closed.push(edge[0]);
                self.canvas.line(BODY_LAYER, closed, BODY, 2);
                let centroid =
                    edge.iter().fold(v2(0.0, 0.0), |s, p| s + *p) * (1.0 / edge.len() as f64);
                let mut label = Label::new(body.name.clone(), centroid, BODY, 0);
                label.bold = true;
                label.size = 15.0;
                label.centred = true;
                self.canvas.label(label);
                self.hulls.push(edge);
            }
        }
    }

    /// The outline of body `k` in pixels: the hull of its nodes and contact outlines, or a
    /// rounded band around them where that hull is degenerate (a point or a line).
    fn body_outline(&self, k: BodyId) -> Vec<V2> {
        let scene = self.scene;
        let mut pts: Vec<V2> = body_nodes(scene, k)
            .into_iter()
            .filter_map(|i| self.px(i))
            .collect();
        pts.extend(
            scene
                .contacts
                .iter()
                .filter(|c| c.body == k)
                .flat_map(|c| outline(&c.surface))
                .map(|p| self.view.px(&p)),
        );
        let edge = hull(&pts);
        if edge.len() < 3 || polygon_area(&edge) < 40.0 {
            // Degenerate (a point or a line): a rounded band around it.
            let ring: Vec<V2> = edge
                .iter()
                .flat_map(|p| {
                    (0..16).map(move |j| {
                        let t = std::f64::consts::TAU * j as f64 / 16.0;
                        *p + v2(t.cos(), t.sin()) * 12.0
                    })
                })
                .collect();
            return hull(&ring);
        }
        edge
    }

    /// Springs and dashpots: between two nodes, grouped by their (unordered) pair of nodes;
    /// grounded, grouped by node and DOF.
    pub(super) fn elements(&mut self) {
        let scene = self.scene;
        let elements: Vec<(Kind, &Element)> = scene
            .springs
            .iter()
            .map(|e| (Kind::Spring, e))
            .chain(scene.dashpots.iter().map(|e| (Kind::Dashpot, e)))
            .collect();
        let mut pairs: Vec<Pair> = Vec::new();
        let mut grounds: Vec<Grounded> = Vec::new();
        for (kind, e) in &elements {
            match kind {
                Kind::Spring => self.present.spring = true,
                Kind::Dashpot => self.present.dashpot = true,
            }
            match &e.connection {
                Connection::FixedDirection { nodes, direction } => {
                    add_pair(&mut pairs, *nodes, *direction, *kind, &e.name)
                }
                Connection::Axial { nodes } => {
                    let d = match (scene.nodes.get(nodes[0]), scene.nodes.get(nodes[1])) {
                        (Some(p), Some(q)) => q.position - p.position,
                        _ => Vector3::x(),
                    };
                    add_pair(&mut pairs, *nodes, d, *kind, &e.name)
                }
                Connection::Grounded { node: i, dof } => {
                    match grounds.iter_mut().find(|g| g.0 == *i && g.1 == *dof) {
                        Some(g) => g.2.push((*kind, &e.name)),
                        None => grounds.push((*i, *dof, vec![(*kind, &e.name)])),
                    }
                }
            }
        }
        self.pairs(&pairs);
        self.grounded(&grounds);
    }

    /// Element groups between two nodes, each element labelled beside its symbol.
    fn pairs(&mut self, pairs: &[Pair]) {
        for (nodes, direction, group) in pairs {
            let (Some(p0), Some(p1)) = (self.px(nodes[0]), self.px(nodes[1])) else {
                continue;
            };
            let out = self.view.dir(direction).unwrap_or(v2(1.0, 0.0));
            let mids = link(&mut self.canvas, p0, p1, out, group);
            for ((kind, name), (mid, side)) in group.iter().zip(mids) {
                self.canvas
                    .label(Label::new(*name, mid, kind.colour(), 2).prefer(&[side, -side]));
            }
        }
    }

    /// Grounded element groups: along a translation, in parallel from the node to a ground;
    /// about a rotation, as coils.
    fn grounded(&mut self, grounds: &[Grounded]) {
        for (i, dof, group) in grounds {
            let Some(n) = self.scene.nodes.get(*i) else {
                continue;
            };
            let p = self.view.px(&n.position);
            match dof {
                Dof::Translation(_) => {
                    let d = ground_direction(&self.view, n, *dof);
                    let g = p - d * GROUNDED_LENGTH;
                    let mids = parallel(&mut self.canvas, p, g, group);
                    let half = 12.0 + PARALLEL_SPACING * (group.len() as f64 - 1.0) / 2.0;
                    ground(&mut self.canvas, SUPPORT_LAYER, g, -d, half);
                    for ((kind, name), (mid, side)) in group.iter().zip(mids) {
                        self.canvas
                            .label(Label::new(*name, mid, kind.colour(), 2).prefer(&[side, -side]));
                    }
                }
                Dof::Rotation(_) => self.torsional(p, *dof, group),
            }
        }
    }

    /// Torsional elements at `p`: a coil round the node each, grounded below it.
    fn torsional(&mut self, p: V2, dof: Dof, group: &[(Kind, &str)]) {
        for (j, (kind, name)) in group.iter().enumerate() {
            let r0 = 9.0 + 8.0 * j as f64;
            let coil: Vec<V2> = (0..=40)
                .map(|s| {
                    let t = 1.5 * std::f64::consts::TAU * s as f64 / 40.0;
                    p + v2(t.cos(), t.sin()) * (r0 + 6.0 * s as f64 / 40.0)
                })
                .collect();
            let end = *coil.last().unwrap_or(&p);
            self.canvas.line(ELEMENT_LAYER, coil, kind.colour(), 2);
            let g = end + v2(0.0, 18.0);
            self.canvas
                .line(ELEMENT_LAYER, vec![end, g], kind.colour(), 2);
            ground(&mut self.canvas, SUPPORT_LAYER, g, v2(0.0, 1.0), 9.0);
            self.canvas
                .label(Label::new(format!("{name} ({dof})"), g, kind.colour(), 2));
        }
    }

    /// Held DOFs during the run: a ground symbol per held translation in the plane.
    pub(super) fn supports(&mut self) {
        let scene = self.scene;
        let conditions = run_conditions(scene);
        for (i, n) in scene.nodes.iter().enumerate() {
            let held: Vec<Dof> = conditions
                .iter()
                .filter(|c| c.node == i)
                .map(|c| c.dof)
                .collect();
            if !held.is_empty() {
                self.support_of(i, n, &held);
            }
        }
    }

    /// The support of node `i`, which the run holds in `held`: a pin where two translations in
    /// the plane are held, a roller where one is; rotations held about the normal in words,
    /// and DOFs held out of the plane noted for the caption.
    fn support_of(&mut self, i: NodeId, n: &Node, held: &[Dof]) {
        let p = self.view.px(&n.position);
        let (dirs, elsewhere, rotation) = self.held_on_screen(n, held);
        if self.scene.dimension == Dimension::Three && !elsewhere.is_empty() {
            self.out_of_plane
                .push(format!("{} {}", n.name, elsewhere.join(" ")));
        }
        let both = dirs.len() >= 2 && dirs.iter().any(|d| d.cross(dirs[0]).abs() > 0.3);
        if both {
            self.present.pin = true;
            let sides = [v2(0.0, 1.0), v2(-1.0, 0.0), v2(1.0, 0.0), v2(0.0, -1.0)];
            let side = best_side(&self.canvas, p, &sides);
            support(&mut self.canvas, p, side, false);
            self.support_sides.push((i, side));
        } else if let Some(d) = dirs.first() {
            self.present.roller = true;
            // Below, or right, rather than above or left, when both are free.
            let d = if d.y < -1e-9 || (d.y.abs() <= 1e-9 && d.x < 0.0) {
                -*d
            } else {
                *d
            };
            let side = best_side(&self.canvas, p, &[d, -d]);
            support(&mut self.canvas, p, side, true);
            self.support_sides.push((i, side));
        }
        for r in rotation {
            self.canvas
                .label(Label::new(format!("{r} held"), p, SUPPORT, 4));
        }
    }

    /// A node's held DOFs as the sketch shows them: the screen directions of the translations
    /// held in the plane, the names of the DOFs held out of it, and the names of the rotations
    /// held about its normal.
    fn held_on_screen(&self, n: &Node, held: &[Dof]) -> (Vec<V2>, Vec<String>, Vec<String>) {
        let view = &self.view;
        let mut dirs: Vec<V2> = Vec::new();
        let mut elsewhere: Vec<String> = Vec::new();
        let mut rotation = Vec::new();
        for dof in held {
            let axis: Vector3<f64> = n.frame.column(dof.axis()).into_owned();
            let in_plane = v2(axis[view.a], axis[view.b]).norm() > 0.5 * axis.norm();
            let on_screen = view.dir(&axis).filter(|_| in_plane);
            match (dof, on_screen) {
                (Dof::Translation(_), Some(d)) => dirs.push(d),
                (Dof::Translation(_), None) => elsewhere.push(dof.to_string()),
                (Dof::Rotation(_), None) => rotation.push(dof.to_string()),
                (Dof::Rotation(_), Some(_)) => elsewhere.push(dof.to_string()),
            }
        }
        (dirs, elsewhere, rotation)
    }

    /// Contact faces: a segment across the normal, with a short normal arrow; a solid: its
    /// outline in the sketch plane, named at its centre.
    pub(super) fn contact_faces(&mut self) {
        let scene = self.scene;
        for c in &scene.contacts {
            self.present.contact = true;
            let Some((point, normal)) = c.plane() else {
                let mut ring: Vec<V2> = outline(&c.surface)
                    .iter()
                    .map(|p| self.view.px(p))
                    .collect();
                ring.push(ring[0]);
                self.canvas.line(ELEMENT_LAYER, ring, CONTACT, 3);
                self.canvas.label(Label::new(
                    c.name.clone(),
                    self.view.px(&c.anchor()),
                    CONTACT,
                    3,
                ));
                continue;
            };
            self.contact_face(c, point, normal);
        }
    }

    /// A plane contact face through `point` with `normal`: a segment across the normal
    /// (centred on the face point, or mostly on one side of it where the other is taken) and a
    /// normal arrow where it crosses least.
    fn contact_face(&mut self, c: &ContactPair, point: Vector3<f64>, normal: Vector3<f64>) {
        let canvas = &mut self.canvas;
        let fp = self.view.px(&point);
        let Some(nd) = self.view.dir(&normal) else {
            canvas.circle(ELEMENT_LAYER, fp, 4.0, CONTACT, false);
            canvas.label(Label::new(
                format!("{} (face ⟂ sketch)", c.name),
                fp,
                CONTACT,
                3,
            ));
            return;
        };
        let t = nd.perp();
        let (e0, e1) = [(0.5, 0.5), (0.1, 0.9), (0.9, 0.1)]
            .into_iter()
            .map(|(lo, hi)| (fp - t * (lo * FACE_LENGTH), fp + t * (hi * FACE_LENGTH)))
            .min_by_key(|(e0, e1)| {
                let gap = 9.0;
                let part = |e: V2| {
                    let u = (e - fp).unit().unwrap_or(t);
                    if (e - fp).norm() > gap {
                        canvas.hits(fp + u * gap, e, 2.0)
                    } else {
                        0
                    }
                };
                part(*e0) + part(*e1)
            })
            .unwrap_or((fp, fp));
        canvas.line(ELEMENT_LAYER, vec![e0, e1], CONTACT, 4);
        let base = [0.7, 0.3]
            .into_iter()
            .flat_map(|s| [e0 + (e1 - e0) * s, e1 + (e0 - e1) * s])
            .min_by_key(|q| canvas.hits(*q + nd * 4.0, *q + nd * 24.0, 2.0))
            .unwrap_or(fp);
        canvas.arrow(ARROW_LAYER, base + nd * 2.0, base + nd * 24.0, CONTACT, 2);
        canvas.label(Label::new(c.name.clone(), (e0 + e1) * 0.5, CONTACT, 3).prefer(&[-nd, nd]));
    }

    /// Nodes: open circles, filled where they carry a point mass.
    pub(super) fn nodes(&mut self) {
        let scene = self.scene;
        for n in &scene.nodes {
            let p = self.view.px(&n.position);
            if n.mass > 0.0 {
                self.present.mass = true;
                self.canvas.circle(NODE_LAYER, p, 5.0, INK, true);
            } else {
                self.present.node = true;
                self.canvas.circle(NODE_LAYER, p, 4.0, WHITE, true);
                self.canvas.circle(NODE_LAYER, p, 4.0, INK, false);
            }
            let mut label = Label::new(n.name.clone(), p, INK, 1);
            label.size = 13.0;
            self.canvas
                .label(label.prefer(&[v2(1.0, -1.0), v2(-1.0, -1.0)]));
        }
    }

    /// Reference nodes (a square) and centres of mass (the quartered circle).
    pub(super) fn body_marks(&mut self) {
        let scene = self.scene;
        for body in &scene.bodies {
            if let Some(p) = self.px(body.reference) {
                let r = 8.0;
                self.canvas.line(
                    MARK_LAYER,
                    vec![
                        p + v2(-r, -r),
                        p + v2(r, -r),
                        p + v2(r, r),
                        p + v2(-r, r),
                        p + v2(-r, -r),
                    ],
                    BODY,
                    2,
                );
            }
            if let Some(c) = mass_centre(scene, body) {
                centre_of_mass(&mut self.canvas, MARK_LAYER, self.view.px(&c));
            }
        }
    }
}

/// Add an element to the group of its pair of nodes (either order).
fn add_pair<'a>(
    pairs: &mut Vec<Pair<'a>>,
    nodes: [NodeId; 2],
    direction: Vector3<f64>,
    kind: Kind,
    name: &'a str,
) {
    let same = |p: &[NodeId; 2]| *p == nodes || *p == [nodes[1], nodes[0]];
    match pairs.iter_mut().find(|(p, _, _)| same(p)) {
        Some(g) => g.2.push((kind, name)),
        None => pairs.push((nodes, direction, vec![(kind, name)])),
    }
}

/// The conditions holding during the run: those of the first dynamic step (else the last).
fn run_conditions(scene: &Scene) -> Vec<BoundaryCondition> {
    scene
        .steps
        .iter()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .or(scene.steps.last())
        .map(|s| s.conditions.clone())
        .unwrap_or_default()
}

/// The nodes of a body: its reference node and the nodes on it.
fn body_nodes(scene: &Scene, body: BodyId) -> Vec<NodeId> {
    scene
        .nodes
        .iter()
        .enumerate()
        .filter(|(i, n)| match n.attachment {
            Attachment::Reference(b) => b == body || scene.bodies[body].reference == *i,
            Attachment::OnBody(b) => b == body,
            Attachment::Free => scene.bodies[body].reference == *i,
        })
        .map(|(i, _)| i)
        .collect()
}
