//! A sketch of a scene, drawn from the [`Scene`] itself (not from a picture of the source
//! problem): nodes, rigid bodies, springs and dashpots, contact faces, loads, initial velocities
//! and the DOFs held during the run, with a legend and a scale bar, as one SVG document.
//!
//! The scene is projected onto its x–y plane (a 3D scene too; when its x–y extent is degenerate
//! but its z extent is not, onto the two axes of largest extent). Geometry is placed at scale;
//! symbols (grounded elements, supports, arrows) have fixed pixel sizes, and the scale is chosen
//! so that both fit. Labels are placed greedily where they cover no other label, line or node.

mod canvas;
mod geometry;
mod legend;
mod loads;
mod structure;
mod symbols;
mod view;

use crate::scene::{NodeId, RigidBody, Scene, Solid, Surface};
use canvas::{Canvas, draw};
use geometry::{Rect, V2, v2};
use nalgebra::Vector3;
use plotters::prelude::*;
use view::{View, axes, fit, reach};

/// Size of the sketch in pixels.
const WIDTH: u32 = 800;
/// Height of the sketch in pixels.
const HEIGHT: u32 = 500;
/// Left edge of the legend column (everything right of it is legend, never drawing).
const LEGEND_X: f64 = 604.0;
/// The drawing area (pixels): between the title and the scale bar, left of the legend.
const AREA: Rect = Rect {
    x0: 14.0,
    y0: 62.0,
    x1: 592.0,
    y1: 466.0,
};
/// Length of a grounded element, from its node to the ground hatch (pixels).
const GROUNDED_LENGTH: f64 = 100.0;
/// Length of a load arrow (pixels).
const LOAD_LENGTH: f64 = 60.0;
/// Length of an initial-velocity arrow (pixels).
const VELOCITY_LENGTH: f64 = 50.0;
/// Length of a contact face segment (pixels).
const FACE_LENGTH: f64 = 84.0;
/// Two-node elements shorter than this (pixels) are drawn as a loop of this length.
const MIN_LINK: f64 = 40.0;
/// Spacing of elements drawn in parallel between the same ends (pixels).
const PARALLEL_SPACING: f64 = 22.0;

const INK: RGBColor = RGBColor(30, 30, 30);
const BODY: RGBColor = RGBColor(31, 119, 180);
const SPRING: RGBColor = RGBColor(140, 86, 75);
const DASHPOT: RGBColor = RGBColor(148, 103, 189);
const CONTACT: RGBColor = RGBColor(230, 120, 0);
const LOAD: RGBColor = RGBColor(214, 39, 40);
const VELOCITY: RGBColor = RGBColor(44, 160, 44);
const SUPPORT: RGBColor = RGBColor(90, 90, 90);

/// Which legend entries the scene needs.
#[derive(Default)]
struct Present {
    node: bool,
    mass: bool,
    body: bool,
    spring: bool,
    dashpot: bool,
    contact: bool,
    load: bool,
    velocity: bool,
    pin: bool,
    roller: bool,
}

/// Points on a contact surface's outline in the x–y plane through its anchor (a plane: its
/// point only).
fn outline(surface: &Surface) -> Vec<Vector3<f64>> {
    let Surface::Solid { solid, centre } = surface else {
        return vec![surface.anchor()];
    };
    let centre = *centre;
    let arc = |at: Vector3<f64>, radius: f64, from: f64, to: f64| {
        (0..=16).map(move |i| {
            let a = from + (to - from) * f64::from(i) / 16.0;
            at + Vector3::new(a.cos(), a.sin(), 0.0) * radius
        })
    };
    let pi = std::f64::consts::PI;
    match *solid {
        Solid::Convex { ref polytope } => polytope.outline().iter().map(|c| centre + c).collect(),
        Solid::Ball { radius } => arc(centre, radius, 0.0, 2.0 * pi).take(16).collect(),
        Solid::Cuboid { half_extents: h } => [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
            .iter()
            .map(|(x, y)| centre + Vector3::new(x * h.x, y * h.y, 0.0))
            .collect(),
        Solid::Capsule {
            half_height,
            radius,
        } => {
            let up = Vector3::new(0.0, half_height, 0.0);
            arc(centre + up, radius, 0.0, pi)
                .chain(arc(centre - up, radius, pi, 2.0 * pi))
                .collect()
        }
    }
}

/// A sketch being drawn: the scene, its projection, the canvas, and what later parts and the
/// legend need from earlier ones.
struct Sketch<'a> {
    scene: &'a Scene,
    view: View,
    canvas: Canvas,
    /// The legend entries the parts drawn so far need.
    present: Present,
    /// The outlines of the rigid bodies drawn (load arrows keep out of them).
    hulls: Vec<Vec<V2>>,
    /// The side each support is drawn on, by node (a spin arrow leaves it open).
    support_sides: Vec<(NodeId, V2)>,
    /// DOFs held out of the sketch plane, one entry per node, for the note under the sketch.
    out_of_plane: Vec<String>,
}

impl<'a> Sketch<'a> {
    /// An empty sketch of `scene`, its view chosen so that the geometry and every symbol fit.
    fn new(scene: &'a Scene) -> Sketch<'a> {
        let mut world: Vec<Vector3<f64>> = scene.nodes.iter().map(|n| n.position).collect();
        world.extend(scene.contacts.iter().flat_map(|c| outline(&c.surface)));
        world.extend(scene.bodies.iter().filter_map(|b| mass_centre(scene, b)));
        let (a, b) = axes(&world);
        let proto = View {
            a,
            b,
            scale: 1.0,
            origin: v2(0.0, 0.0),
        };
        let reach = reach(scene, &world, &proto);
        Sketch {
            scene,
            view: fit(a, b, &reach, &world),
            canvas: Canvas::new(),
            present: Present::default(),
            hulls: Vec::new(),
            support_sides: Vec::new(),
            out_of_plane: Vec::new(),
        }
    }

    /// A node's position in pixels (`None`: the scene has no such node).
    fn px(&self, i: NodeId) -> Option<V2> {
        self.scene.nodes.get(i).map(|n| self.view.px(&n.position))
    }
}

/// Where a body's centre of mass is (`None`: its reference node is missing).
fn mass_centre(scene: &Scene, b: &RigidBody) -> Option<Vector3<f64>> {
    scene
        .nodes
        .get(b.reference)
        .map(|r| r.position + b.centre_offset)
}

/// A sketch of a scene drawn from the `Scene` itself: nodes (filled where they carry a point
/// mass), rigid bodies (outline of their nodes, reference node and centre of mass), springs and
/// dashpots, contact faces, loads, initial velocities and the DOFs held during the run, with a
/// title, a legend and a scale bar. An SVG document of about 800×500 px; `None` if the scene
/// has no nodes.
pub fn render(scene: &Scene) -> Option<String> {
    if scene.nodes.is_empty() {
        return None;
    }
    let mut sketch = Sketch::new(scene);
    sketch.bodies();
    sketch.elements();
    sketch.supports();
    sketch.contact_faces();
    sketch.nodes();
    sketch.body_marks();
    sketch.loads();
    sketch.initial_velocities();
    sketch.canvas.place_labels();
    legend::frame(
        &mut sketch.canvas,
        scene,
        &sketch.view,
        &sketch.present,
        &sketch.out_of_plane,
    );
    draw(sketch.canvas)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Attachment;
    use std::path::{Path, PathBuf};

    fn seeds() -> Vec<Scene> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
        let paths: Vec<PathBuf> = crate::case::discover(&dir).expect("cases directory");
        assert!(!paths.is_empty(), "no seed cases in {}", dir.display());
        paths
            .iter()
            .map(|p| crate::case::load(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
            .collect()
    }

    #[test]
    fn every_seed_case_sketches_with_every_named_part() {
        for scene in seeds() {
            let svg = render(&scene).unwrap_or_else(|| panic!("{}: no sketch", scene.id));
            assert!(svg.starts_with("<svg"), "{}: not an SVG document", scene.id);
            assert!(svg.contains(&scene.id), "{}: no title", scene.id);
            let names = scene
                .springs
                .iter()
                .chain(&scene.dashpots)
                .map(|e| &e.name)
                .chain(scene.contacts.iter().map(|c| &c.name))
                .chain(scene.bodies.iter().map(|b| &b.name))
                .chain(scene.nodes.iter().map(|n| &n.name));
            for name in names {
                assert!(
                    svg.contains(&format!(">\n{name}\n</text>")),
                    "{}: {name} is not labelled",
                    scene.id
                );
            }
        }
    }

    #[test]
    fn small_and_degenerate_scenes_render_without_panicking() {
        for scene in seeds() {
            // One node, nothing else.
            let mut one = scene.clone();
            one.nodes.truncate(1);
            one.nodes[0].attachment = Attachment::Free;
            one.bodies.clear();
            one.springs.clear();
            one.dashpots.clear();
            one.contacts.clear();
            one.loads.clear();
            one.initial_velocities.clear();
            one.steps.clear();
            assert!(
                render(&one).is_some_and(|s| s.starts_with("<svg")),
                "{}",
                scene.id
            );
            // Every node at one point (coincident nodes, zero extent).
            let mut point = scene.clone();
            for n in &mut point.nodes {
                n.position = Vector3::new(0.5, 0.5, 0.0);
            }
            for c in &mut point.contacts {
                if let Surface::Plane { point, .. } = &mut c.surface {
                    *point = Vector3::new(0.5, 0.5, 0.0);
                }
            }
            assert!(render(&point).is_some(), "{}", scene.id);
            // The scene turned into the x–z plane: drawn in x–z.
            let mut turned = scene.clone();
            let swap = |v: &mut Vector3<f64>| v.swap_rows(1, 2);
            for n in &mut turned.nodes {
                swap(&mut n.position);
            }
            for c in &mut turned.contacts {
                if let Surface::Plane { point, normal } = &mut c.surface {
                    swap(point);
                    swap(normal);
                }
            }
            for l in &mut turned.loads {
                swap(&mut l.force);
            }
            for b in &mut turned.bodies {
                swap(&mut b.centre_offset);
            }
            for v in &mut turned.initial_velocities {
                swap(&mut v.velocity);
                swap(&mut v.angular);
            }
            let svg = render(&turned).expect("turned scene");
            let flat = |i: usize| {
                turned
                    .nodes
                    .iter()
                    .all(|n| n.position[i] == turned.nodes[0].position[i])
            };
            if flat(1) && !flat(2) {
                assert!(svg.contains("sketch plane x–z"), "{}", scene.id);
            }
        }
        let mut empty = seeds().remove(0);
        empty.nodes.clear();
        assert!(render(&empty).is_none());
    }

    /// Writes every seed case's sketch to `/tmp/sketch/<id>.svg` (for looking at them).
    #[test]
    #[ignore]
    fn write_seed_sketches() {
        let out = Path::new("/tmp/sketch");
        std::fs::create_dir_all(out).unwrap();
        for scene in seeds() {
            let svg = render(&scene).unwrap();
            std::fs::write(out.join(format!("{}.svg", scene.id)), svg).unwrap();
        }
    }
}
