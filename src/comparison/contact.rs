//! Contact that opens and closes, measured from each run: when it strikes, what each impact
//! does to the energy, and how high the first rebound rises (what the report's contact
//! section shows against the event-driven `reference`).

use crate::contract::{E_ELASTIC, E_KINETIC, History, W_EXTERNAL};
use crate::scene::{ContactState, Probe, Scene, parallel, surface_distance};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What a run did at its contact events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Impacts {
    /// Impact times: the engine's own (`impact_<i>_time` measures: the reference's located
    /// events, the explicit engine's increments, rapier's steps) or, for an engine that
    /// reports none, the rows where the first pair's contact force turns positive.
    pub times: Vec<f64>,
    /// How many impacts the engine counted (where it reports them).
    pub count: Option<u64>,
    /// Per impact (engines that keep energies): mechanical energy (kinetic + elastic − work
    /// of the loads) after it minus before, over the kinetic energy before; from the rows
    /// bracketing it (the last before the increment that holds it; after, the first where the
    /// force is released or, for a pair that comes to rest, the last before the next impact or the run's end).
    pub energy_change: Vec<f64>,
    /// The first impact's rebound height over the drop (a scene with one pair that starts
    /// open, whose `ux_node` column measures its node along the surface normal).
    pub rebound: Option<f64>,
    /// The deepest penetration at the rows (the largest −gap over the scene's `gap` columns,
    /// 0 if the node never went in); `None` without a `gap` column.
    #[serde(default)]
    pub penetration: Option<f64>,
}

/// The contact events of one run, for a scene where contact opens and closes (a pair that
/// starts open, or a run that counted impacts); `None` otherwise. `increment` is the run's
/// (0 for the reference): an impact reported at time t happened within the increment before
/// it, so the energy before it is read at t − increment or earlier.
pub fn measure(
    scene: &Scene,
    history: &History,
    measures: &BTreeMap<String, f64>,
    increment: f64,
) -> Option<Impacts> {
    if scene.contacts.is_empty() {
        return None;
    }
    let opens = scene
        .contacts
        .iter()
        .any(|c| c.initially == ContactState::Open);
    let count = measures.get("impacts").map(|n| *n as u64);
    if !opens && count.unwrap_or(0) == 0 {
        return None;
    }
    let t = history.column("t")?;
    let force = history.column("contact_force")?;
    let mut times: Vec<f64> = (1..)
        .map_while(|i| measures.get(&format!("impact_{i}_time")).copied())
        .collect();
    if count.is_none() {
        times = (1..t.len())
            .filter(|&i| force[i] > 0.0 && force[i - 1] <= 0.0)
            .map(|i| t[i])
            .collect();
    }
    let energy = match (
        history.column(E_KINETIC),
        history.column(E_ELASTIC),
        history.column(W_EXTERNAL),
    ) {
        (Some(k), Some(e), Some(w)) => Some((k, e, w)),
        _ => None,
    };
    let mut energy_change = Vec::new();
    if let Some((kinetic, elastic, work)) = &energy {
        for (n, &at) in times.iter().enumerate() {
            let Some(before) = t.iter().rposition(|x| *x < at - increment) else {
                continue;
            };
            // After: the first row where the pair has let go; a pair that comes to rest never
            // does, and then it is the last row before the next impact (or the run's end).
            let until = times.get(n + 1).copied().unwrap_or(f64::INFINITY);
            let resting = t.iter().rposition(|x| *x < until).filter(|&i| i > before);
            let Some(after) = (before + 1..t.len())
                .find(|&i| t[i] > at && t[i] < until && force[i] <= 0.0)
                .or(resting)
            else {
                continue;
            };
            let mechanical = |i: usize| kinetic[i] + elastic[i] - work[i];
            if kinetic[before] > 0.0 {
                energy_change.push((mechanical(after) - mechanical(before)) / kinetic[before]);
            }
        }
    }
    let gaps: Vec<Vec<f64>> = scene
        .columns
        .iter()
        .filter(|c| matches!(c.probe, Probe::Gap { .. }))
        .filter_map(|c| history.column(&c.name))
        .collect();
    let penetration =
        (!gaps.is_empty()).then(|| gaps.iter().flatten().fold(0.0_f64, |m, g| m.max(-g)));
    Some(Impacts {
        rebound: rebound(scene, history, &times),
        penetration,
        times,
        count,
        energy_change,
    })
}

/// The first rebound's height over the drop, measured on `ux_node` (see [`Impacts::rebound`]).
fn rebound(scene: &Scene, history: &History, times: &[f64]) -> Option<f64> {
    let [pair] = scene.contacts.as_slice() else {
        return None;
    };
    if pair.initially != ContactState::Open {
        return None;
    }
    let column = scene.columns.iter().find(|c| c.name == "ux_node")?;
    let Probe::Displacement { node, direction } = &column.probe else {
        return None;
    };
    let (drop, normal) = surface_distance(&pair.surface, &scene.nodes[*node].position);
    if *node != pair.node || !parallel(direction, &normal) {
        return None;
    }
    let sign = direction.dot(&normal).signum();
    let t = history.column("t")?;
    let x = history.column("ux_node")?;
    let first = *times.first()?;
    let until = times.get(1).copied().unwrap_or(f64::INFINITY);
    // The highest row between the first impact and the next; where the next follows within a
    // row (a node that does not leave the face), the first row after the impact.
    let after = t.iter().position(|t| *t > first)?;
    let apex = t
        .iter()
        .zip(&x)
        .skip(after)
        .take_while(|(t, _)| **t < until)
        .map(|(_, x)| sign * x)
        .fold(sign * x[after], f64::max);
    apex.is_finite().then(|| (drop + apex) / drop)
}
