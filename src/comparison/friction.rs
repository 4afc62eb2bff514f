//! The friction cases' events, read the same way from every history, the exact solution's
//! included: when the node first moves and when it settles for good (at rest, or a ball at the
//! speed it rolls on at), where it ends up,
//! and how far it moves where the exact solution does not (creep on a stick, drift off an
//! isotropic slide's line).
//!
//! The node and the direction are the scene's first velocity column's, with the displacement
//! column of the same node and direction. A node is at rest where its speed is at most
//! [`REST`] of the exact solution's peak speed (1e-6 of the scene's extent per unit time where
//! the exact solution never moves, its speed zero to round-off): above the ringing of an elastic stick (μg√(m/k), 8e-4
//! of the peak on the shipped cases), far below any slide. Times are output-row times, so an
//! event is placed within one row interval; the same rule on the exact history places the
//! exact event within the same interval, and the difference of the two is what the report
//! shows.

use crate::contract::History;
use crate::scene::{Probe, Scene};
use serde::{Deserialize, Serialize};

/// At rest: a speed at most this fraction of the exact solution's peak speed.
pub const REST: f64 = 1e-2;

/// What one history says of the node's motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Motion {
    /// The first row time at which the node moves (`None`: never).
    pub starts: Option<f64>,
    /// The row time from which it keeps the exact solution's final speed to the end: at rest
    /// where that is 0, rolling on where a ball ends rolling (`None`: not settled at the end).
    pub rests: Option<f64>,
    /// Its displacement along the direction at the last row.
    pub end: f64,
    /// The largest |value| of its displacement columns in the face's plane whose exact solution
    /// is zero: creep on a stick, drift off a slide's line.
    pub stray: f64,
    /// The energy friction dissipated by the last row (its `e_frictional`; `None`: the history
    /// has no energy columns, as an exact solution's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dissipated: Option<f64>,
    /// Its energy balance at the last row (`e_balance`): with friction's dissipation counted,
    /// the energy its integration lost or gained.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub balance: Option<f64>,
}

/// One engine's motion beside the exact solution's, read by the same rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrictionEvents {
    /// The engine's.
    pub engine: Motion,
    /// The exact solution's.
    pub exact: Motion,
}

/// The friction events of `history` against `exact`, on a scene with friction and a velocity
/// column whose displacement column exists; `None` otherwise.
pub fn measure(scene: &Scene, exact: &History, history: &History) -> Option<FrictionEvents> {
    if !scene.has_friction() {
        return None;
    }
    let (speed, along, others) = columns(scene)?;
    let exact_speed = exact.column(speed)?;
    let peak = super::peak(&exact_speed);
    let extent = scene
        .nodes
        .iter()
        .fold(0.0_f64, |m, n| m.max(n.position.norm()));
    let rest = if peak > super::round_off(scene, speed) {
        REST * peak
    } else {
        1e-6 * extent / scene.duration()
    };
    let still: Vec<&str> = others
        .into_iter()
        .filter(|c| {
            exact
                .column(c)
                .is_some_and(|x| super::peak(&x) <= super::round_off(scene, c))
        })
        .collect();
    let settled = settled_speed(&exact_speed);
    let read = |h: &History| motion(h, speed, along, &still, rest, settled);
    Some(FrictionEvents {
        engine: read(history)?,
        exact: read(exact)?,
    })
}

/// The first velocity column's name, the displacement column of its node and direction, and
/// every displacement column of that node in the plane of its contact's face (its motion
/// into the face is the penalty's, not friction's).
fn columns(scene: &Scene) -> Option<(&str, &str, Vec<&str>)> {
    let (speed, node, direction) = scene.columns.iter().find_map(|c| match c.probe {
        Probe::Velocity { node, direction } => Some((c.name.as_str(), node, direction)),
        _ => None,
    })?;
    let normal = scene
        .contacts
        .iter()
        .find(|c| c.node == node)
        .and_then(|c| c.plane())
        .map(|(_, n)| n);
    let in_face = move |d: &nalgebra::Vector3<f64>| normal.is_none_or(|n| n.dot(d).abs() < 1e-9);
    let displacements = || {
        scene.columns.iter().filter_map(move |c| match c.probe {
            Probe::Displacement {
                node: n,
                direction: d,
            } if n == node => Some((c.name.as_str(), d)),
            _ => None,
        })
    };
    let along = displacements()
        .find(|(_, d)| (d - direction).norm() < 1e-12)?
        .0;
    let in_plane = displacements().filter(|(_, d)| in_face(d)).map(|(c, _)| c);
    Some((speed, along, in_plane.collect()))
}

/// The speed the exact solution settles at: its last row's where its last two rows agree (a
/// ball that rolls on at a constant speed), else 0 (a node at rest, or one that keeps
/// accelerating and never settles).
fn settled_speed(exact_speed: &[f64]) -> f64 {
    match exact_speed {
        [.., before, last] if before == last => *last,
        _ => 0.0,
    }
}

/// A history's [`Motion`] by the rule of the module: it moves where its speed is above `rest`,
/// and rests from the row after which it stays within `rest` of `settled`.
pub fn motion(
    h: &History,
    speed: &str,
    along: &str,
    still: &[&str],
    rest: f64,
    settled: f64,
) -> Option<Motion> {
    let (t, v, x) = (h.column("t")?, h.column(speed)?, h.column(along)?);
    let moving = |i: usize| v[i].abs() > rest;
    let starts = (0..v.len()).find(|&i| moving(i)).map(|i| t[i]);
    let unsettled = |i: usize| (v[i] - settled).abs() > rest;
    let rests = match (0..v.len()).rposition(unsettled) {
        None => Some(t[0]),
        Some(i) if i + 1 < v.len() => Some(t[i + 1]),
        Some(_) => None,
    };
    let stray = still
        .iter()
        .filter_map(|c| h.column(c))
        .map(|x| super::peak(&x))
        .fold(0.0, f64::max);
    let last = |name: &str| h.column(name).and_then(|c| c.last().copied());
    Some(Motion {
        starts,
        rests,
        end: *x.last()?,
        stray,
        dissipated: last(crate::contract::E_FRICTIONAL),
        balance: last(crate::contract::E_BALANCE),
    })
}
