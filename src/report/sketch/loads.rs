//! What acts on a scene, drawn: loads as arrows labelled with their magnitude, initial
//! velocities as arrows, and initial angular velocities as curved arrows about their node.

use super::canvas::{ARROW_LAYER, Label};
use super::geometry::{V2, inside_polygon, v2};
use super::symbols::spin_arrow;
use super::{LOAD, LOAD_LENGTH, Sketch, VELOCITY, VELOCITY_LENGTH};
use crate::report::format::tick;
use crate::scene::{InitialVelocity, PointLoad};

impl Sketch<'_> {
    /// Loads: arrows of fixed length along the force, labelled with the magnitude.
    pub(super) fn loads(&mut self) {
        let scene = self.scene;
        for l in &scene.loads {
            self.present.load = true;
            let Some(p) = self.px(l.node) else { continue };
            self.load(l, p);
        }
    }

    /// A load at `p`: an arrow pointing at the node or away from it, whichever crosses less
    /// (and stays out of the bodies), labelled at its far end.
    fn load(&mut self, l: &PointLoad, p: V2) {
        let magnitude = l.force.norm();
        let text = format!("F = {} N", tick(magnitude, magnitude));
        let Some(d) = self.view.dir(&l.force) else {
            self.canvas
                .label(Label::new(format!("{text} (⟂ sketch)"), p, LOAD, 3));
            return;
        };
        let candidates = [
            (p + d * 7.0, p + d * (LOAD_LENGTH + 7.0)),
            (p - d * (LOAD_LENGTH + 7.0), p - d * 7.0),
        ];
        let (tail, tip) = candidates
            .into_iter()
            .min_by_key(|(t, h)| {
                let inside = self
                    .hulls
                    .iter()
                    .any(|o| inside_polygon((*t + *h) * 0.5, o));
                self.canvas.hits(*t, *h, 3.0) + usize::from(inside)
            })
            .unwrap_or(candidates[0]);
        self.canvas.arrow(ARROW_LAYER, tail, tip, LOAD, 3);
        let far = if (tail - p).norm() > (tip - p).norm() {
            tail
        } else {
            tip
        };
        self.canvas
            .label(Label::new(text, far, LOAD, 3).prefer(&[d.perp(), -d.perp(), far - p]));
    }

    /// Initial velocities: arrows (beside the node when the line is taken) and ω as a curved
    /// arrow about the node.
    pub(super) fn initial_velocities(&mut self) {
        let scene = self.scene;
        for iv in &scene.initial_velocities {
            let Some(p) = self.px(iv.node) else { continue };
            if iv.velocity.norm() > 0.0 {
                self.velocity(iv, p);
            }
            self.spin(iv, p);
        }
    }

    /// A non-zero initial velocity at `p`: an arrow along it, offset sideways where the line
    /// through the node is taken, labelled with the speed.
    fn velocity(&mut self, iv: &InitialVelocity, p: V2) {
        let speed = iv.velocity.norm();
        self.present.velocity = true;
        let text = format!("v = {} m/s", tick(speed, speed));
        let Some(d) = self.view.dir(&iv.velocity) else {
            self.canvas
                .label(Label::new(format!("{text} (⟂ sketch)"), p, VELOCITY, 3));
            return;
        };
        let canvas = &mut self.canvas;
        let (tail, tip) = [0.0, 13.0, -13.0, 24.0, -24.0]
            .into_iter()
            .map(|o| {
                let s = p + d.perp() * o;
                (s + d * 7.0, s + d * (VELOCITY_LENGTH + 7.0))
            })
            .min_by_key(|(t, h)| canvas.hits(*t + d * 3.0, *h, 3.0))
            .unwrap_or((p, p + d * VELOCITY_LENGTH));
        canvas.arrow(ARROW_LAYER, tail, tip, VELOCITY, 2);
        canvas.label(Label::new(text, tip, VELOCITY, 3).prefer(&[d, d.perp(), -d.perp()]));
    }

    /// An initial angular velocity at `p`: about the sketch's normal, a curved arrow open
    /// towards the node's support; about an axis in the plane, its components in words.
    fn spin(&mut self, iv: &InitialVelocity, p: V2) {
        let normal = self.view.normal_axis();
        let spin = iv.angular[normal] * self.view.handedness();
        let tilt = (0..3)
            .filter(|i| *i != normal)
            .map(|i| iv.angular[i].abs())
            .fold(0.0, f64::max);
        if spin != 0.0 {
            self.present.velocity = true;
            let w = iv.angular[normal].abs();
            let axis = ["x", "y", "z"][normal];
            let gap = self
                .support_sides
                .iter()
                .find(|(n, _)| *n == iv.node)
                .map_or(v2(0.0, 1.0), |(_, s)| *s);
            let top = spin_arrow(&mut self.canvas, p, spin > 0.0, gap);
            self.canvas.label(
                Label::new(format!("ω{axis} = {} rad/s", tick(w, w)), top, VELOCITY, 3).prefer(&[
                    v2(0.0, -1.0),
                    v2(1.0, -1.0),
                    v2(-1.0, -1.0),
                ]),
            );
        }
        if tilt > 0.0 {
            let w = iv.angular;
            self.canvas.label(Label::new(
                format!(
                    "ω = ({}, {}, {}) rad/s",
                    tick(w[0], tilt),
                    tick(w[1], tilt),
                    tick(w[2], tilt)
                ),
                p,
                VELOCITY,
                3,
            ));
        }
    }
}
