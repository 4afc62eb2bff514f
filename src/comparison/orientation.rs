//! A body's orientation compared as a rotation, not as a number that turns without end.
//!
//! An engine writes a body's rotation as one scalar column (`rz`: its twist about the axis,
//! unwrapped, as the contract asks). Two engines can unwrap the same orientation onto branches
//! 2π apart, and a free body's accumulated angle grows with every turn; neither says how far
//! apart the two orientations are. So the error of a rotation column is:
//!
//! - where the scene has three body points of the body, not on one line, each with its
//!   displacement along three independent directions (a 3D body free to turn about any axis,
//!   whose twist alone is blind to its swing): the angle of R_exactᵀ·R, the geodesic distance
//!   between the two orientations, each recovered from its body points;
//! - otherwise (2D, or a body turning about one axis): the difference of the two angles
//!   wrapped into (−π, π], which is the same distance for a rotation about one axis;
//!
//! and its scale is the smaller of π and how far the exact orientation gets from where it
//! starts (the geodesic distance from its first row; the peak of the angle where there are no
//! body points): the swing for a body that swings a few degrees (an error is then over the
//! motion), π for a body that turns (the largest distance two orientations can have, whatever
//! the number of turns).

use crate::contract::History;
use crate::scene::{Attachment, BodyId, Probe, Scene};
use nalgebra::{Matrix3, Vector3};
use std::f64::consts::PI;

/// `angle` wrapped into (−π, π].
pub fn wrap(angle: f64) -> f64 {
    let w = angle.rem_euclid(2.0 * PI);
    if w > PI { w - 2.0 * PI } else { w }
}

/// The scale of an orientation error whose exact orientation gets `range` from its start.
pub fn scale(range: f64) -> f64 {
    range.min(PI)
}

/// The angle between two rotations, R_aᵀ·R_b, from its axis part and its trace (accurate
/// for small and large angles alike).
pub fn geodesic(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let r = a.transpose() * b;
    let axis = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    );
    (0.5 * axis.norm()).atan2(0.5 * (r.trace() - 1.0))
}

/// A point of a body: its position at t = 0 and its displacement columns (name, direction).
type Point = (Vector3<f64>, Vec<(String, Vector3<f64>)>);

/// A body's points that fix its orientation: three nodes of the body, not on one line, each
/// with the names of its displacement columns and the directions they measure along.
#[derive(Debug, Clone)]
pub struct BodyPoints {
    points: Vec<Point>,
}

/// The body points of `body` in `scene`, where it has three (see the module doc).
pub fn body_points(scene: &Scene, body: BodyId) -> Option<BodyPoints> {
    if scene.dimension != crate::scene::Dimension::Three {
        return None;
    }
    let mut points: Vec<Point> = Vec::new();
    for (i, node) in scene.nodes.iter().enumerate() {
        let on = matches!(node.attachment, Attachment::OnBody(b) | Attachment::Reference(b) if b == body);
        if !on {
            continue;
        }
        let columns: Vec<(String, Vector3<f64>)> = scene
            .columns
            .iter()
            .filter_map(|c| match &c.probe {
                Probe::Displacement { node, direction } if *node == i => {
                    Some((c.name.clone(), *direction))
                }
                _ => None,
            })
            .collect();
        if columns.len() == 3 && directions(&columns).determinant().abs() > 1e-6 {
            points.push((node.position, columns));
        }
    }
    // Three points, the first two spanning a triangle with one of the rest.
    let (a, b) = (points.first()?.0, points.get(1)?.0);
    let third = points
        .iter()
        .skip(2)
        .position(|p| (b - a).cross(&(p.0 - a)).norm() > 1e-9)?;
    points.swap(2, third + 2);
    points.truncate(3);
    Some(BodyPoints { points })
}

fn directions(columns: &[(String, Vector3<f64>)]) -> Matrix3<f64> {
    Matrix3::from_rows(&[
        columns[0].1.transpose(),
        columns[1].1.transpose(),
        columns[2].1.transpose(),
    ])
}

/// An orthonormal frame from three points: along the first edge, in their plane, normal to it.
fn frame(p: &[Vector3<f64>; 3]) -> Matrix3<f64> {
    let e1 = (p[1] - p[0]).normalize();
    let e3 = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
    Matrix3::from_columns(&[e1, e3.cross(&e1), e3])
}

impl BodyPoints {
    /// The body's rotation at each row of `history` (`None` where a column is missing).
    pub fn rotations(&self, history: &History) -> Option<Vec<Matrix3<f64>>> {
        let initial: [Vector3<f64>; 3] = std::array::from_fn(|k| self.points[k].0);
        let start = frame(&initial);
        let mut columns: Vec<(Matrix3<f64>, [Vec<f64>; 3])> = Vec::new();
        for (_, cols) in &self.points {
            let values: [Vec<f64>; 3] = [
                history.column(&cols[0].0)?,
                history.column(&cols[1].0)?,
                history.column(&cols[2].0)?,
            ];
            columns.push((directions(cols).try_inverse()?, values));
        }
        Some(
            (0..history.rows.len())
                .map(|row| {
                    let now: [Vector3<f64>; 3] = std::array::from_fn(|k| {
                        let (inverse, values) = &columns[k];
                        let measured = Vector3::new(values[0][row], values[1][row], values[2][row]);
                        self.points[k].0 + inverse * measured
                    });
                    frame(&now) * start.transpose()
                })
                .collect(),
        )
    }
}

/// The orientation error of body `body` at each of the rows `rows`, and its scale (see the
/// module doc): the geodesic distance where the body has three body points, else the wrapped
/// difference of the rotation column `column` (exact, candidate), whose exact peak is `peak`.
pub fn errors(
    scene: &Scene,
    body: BodyId,
    (exact, candidate): (&History, &History),
    column: (&[f64], &[f64]),
    rows: std::ops::Range<usize>,
) -> (Vec<f64>, f64) {
    let from_points = body_points(scene, body).and_then(|p| {
        let (a, b) = (p.rotations(exact)?, p.rotations(candidate)?);
        let range = (0..rows.end)
            .map(|k| geodesic(&a[0], &a[k]))
            .fold(0.0f64, f64::max);
        let errors = rows.clone().map(|k| geodesic(&a[k], &b[k])).collect();
        Some((errors, scale(range)))
    });
    from_points.unwrap_or_else(|| {
        let peak = column.0[..rows.end]
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let errors = rows
            .map(|k| wrap(column.1[k] - column.0[k]).abs())
            .collect();
        (errors, scale(peak))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    /// A spin passing ±π many times: the twist of each engine unwrapped onto branches 2π
    /// apart, or wrapped at different rows, is the same orientation, error 0; a phase lag of
    /// 0.75 rad is 0.75 rad at every row however many turns were made, so over π it misses a
    /// 5e-2 tolerance (0.24).
    #[test]
    fn a_spin_through_many_turns_is_compared_modulo_a_turn() {
        let omega = 1000.0;
        let exact: Vec<f64> = (0..501).map(|k| omega * k as f64 * 1e-4).collect();
        let branch: Vec<f64> = exact.iter().map(|a| a - 4.0 * PI).collect();
        let wrapped: Vec<f64> = exact.iter().map(|a| wrap(*a)).collect();
        let lagging: Vec<f64> = exact.iter().map(|a| a - 0.75).collect();
        let peak = exact.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(peak > 15.0 * PI, "{peak}");
        let worst = |b: &[f64]| {
            exact
                .iter()
                .zip(b)
                .map(|(a, b)| wrap(b - a).abs())
                .fold(0.0f64, f64::max)
                / scale(peak)
        };
        assert!(worst(&branch) < 1e-12);
        assert!(worst(&wrapped) < 1e-12);
        let lag = worst(&lagging);
        assert!((lag - 0.75 / PI).abs() < 1e-12, "{lag}");
        assert!(lag > 5e-2);
        // Divided by the accumulated angle, as a plain column would be, the lag would pass.
        assert!(0.75 / peak < 5e-2);
    }

    /// The geodesic distance is the angle of the relative rotation, whatever the axes.
    #[test]
    fn the_geodesic_distance_is_the_relative_angle() {
        let a = Rotation3::from_euler_angles(0.3, -1.2, 2.9);
        for angle in [1e-9, 1e-4, 0.75, 2.0, 3.1] {
            let axis = Vector3::new(0.2, -0.5, 0.8).normalize();
            let b = a * Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            let d = geodesic(a.matrix(), b.matrix());
            assert!((d - angle).abs() <= 1e-12 * angle.max(1.0), "{angle}: {d}");
        }
    }
}
