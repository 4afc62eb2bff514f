//! The dynamic steps: per step, the fixed bodies, the locked axes, the ground joints (the DOFs
//! held, and the grounded springs and dashpots as motors) and the velocities held at its start.

use super::super::steps::{Group, Placement, held_in_every_dof, locked_axes, moved, turns};
use super::{
    BodyKind, BodySpec, Frame, HeldVelocity, Holding, JointKind, JointSpec, Motor, NodeRef,
    StepSpec, frame_rotation, joint_axis, twist, unsupported,
};
use crate::engines::EngineError;
use crate::scene::{Connection, Dof, Node, NodeId, Scene, Step, StepKind};
use nalgebra::Vector3;

/// What the dynamic steps are planned from: the scene, and the plan made so far.
pub(super) struct PlanSoFar<'a> {
    pub(super) scene: &'a Scene,
    pub(super) holding: Holding,
    pub(super) nodes: &'a [NodeRef],
    pub(super) bodies: &'a [BodySpec],
    pub(super) placement: &'a Placement,
    pub(super) element_groups: &'a [Group],
}

impl PlanSoFar<'_> {
    /// The dynamic steps (from `first_dynamic` on), in order: each remembers which joint axes
    /// and bodies an earlier one left free to move.
    pub(super) fn steps(&self, first_dynamic: usize) -> Result<Vec<StepSpec>, EngineError> {
        let mut steps = Vec::new();
        // Per node, the joint axes some earlier dynamic step left free.
        let mut was_free = vec![[false; 6]; self.scene.nodes.len()];
        // Per plan body, whether an earlier dynamic step let it turn.
        let mut turned = vec![false; self.bodies.len()];
        for step in &self.scene.steps[first_dynamic..] {
            steps.push(self.step(step, &mut was_free, &mut turned)?);
        }
        Ok(steps)
    }

    /// One dynamic step: its fixed bodies and locked axes (none for a body that moved
    /// before), a ground joint for every node with something to hold, and the velocities held.
    fn step(
        &self,
        step: &Step,
        was_free: &mut [[bool; 6]],
        turned: &mut [bool],
    ) -> Result<StepSpec, EngineError> {
        let (scene, nodes, bodies, placement) =
            (self.scene, self.nodes, self.bodies, self.placement);
        let StepKind::Dynamic { duration } = step.kind else {
            unreachable!("checked above")
        };
        let mut joints = Vec::new();
        let mut held = Vec::new();
        let (mut fixed, mut locks) = match self.holding {
            Holding::Fixed => (
                held_in_every_dof(scene, step, nodes, bodies, placement),
                locked_axes(scene, step, nodes, bodies, placement),
            ),
            Holding::Joints => (
                bodies.iter().map(|b| b.kind == BodyKind::Ground).collect(),
                vec![None; bodies.len()],
            ),
        };
        for b in (1..bodies.len())
            .filter(|&b| moved(scene, nodes, self.element_groups, placement, turned, b))
        {
            fixed[b] = false;
            locks[b] = None;
        }
        for (id, node) in scene.nodes.iter().enumerate() {
            let r = nodes[id];
            if r.body == 0 || fixed[r.body] {
                // The ground and a fixed body need no joint, and their velocity is zero.
                continue;
            }
            let mut held_here = held_at(step, id, node, r, &mut held);
            // A particle never rotates: its rotations are not the joint's business.
            if bodies[r.body].kind == BodyKind::Particle {
                held_here[3..].fill(false);
            }
            let locked_by_body = locks[r.body].is_some();
            if let Some(joint) =
                self.ground_joint(id, node, held_here, locked_by_body, &mut was_free[id])?
            {
                joints.push(joint);
            }
        }
        for (b, t) in turned.iter_mut().enumerate() {
            *t |= !fixed[b] && turns(scene, step, nodes, bodies, b);
        }
        Ok(StepSpec {
            duration,
            joints,
            held,
            fixed,
            locks: locks.into_iter().map(Option::unwrap_or_default).collect(),
        })
    }

    /// Node `id`'s ground joint in a step that holds `held_here` there: it locks them (unless
    /// its body's locked axes do) and carries the node's grounded springs and dashpots on the
    /// DOFs left free as motors; `None` when it would do neither. `was_free` (the joint axes an
    /// earlier dynamic step left free) says which locks are refitted to the pose.
    fn ground_joint(
        &self,
        id: NodeId,
        node: &Node,
        held_here: [bool; 6],
        locked_by_body: bool,
        was_free: &mut [bool; 6],
    ) -> Result<Option<JointSpec>, EngineError> {
        let r = self.nodes[id];
        let locked = if locked_by_body {
            [false; 6]
        } else {
            held_here
        };
        let refit: [bool; 6] = std::array::from_fn(|i| locked[i] && was_free[i]);
        for (free, h) in was_free.iter_mut().zip(held_here) {
            *free |= !h;
        }
        let motors: Vec<Motor> = self
            .element_groups
            .iter()
            .filter_map(|g| match g.connection {
                Connection::Grounded { node: n, dof } if n == id => Some(Motor {
                    axis: joint_axis(dof),
                    stiffness: g.stiffness,
                    damping: g.damping,
                }),
                _ => None,
            })
            .filter(|m| !held_here[m.axis])
            .collect();
        if !locked.iter().any(|&l| l) && motors.is_empty() {
            return Ok(None);
        }
        let free_rotations = locked[3..].iter().filter(|l| !**l).count();
        if refit[3..].iter().any(|&r| r) && free_rotations > 1 && motors.iter().any(|m| m.axis >= 3)
        {
            return unsupported(format!(
                "node `{}`: a rotation held again after a dynamic step left it free, with a grounded rotational spring or dashpot on one of two rotations still free",
                node.name
            ));
        }
        let origin = held_where_left(node, r, &locked, self.placement)?;
        let rotation = frame_rotation(&node.frame);
        Ok(Some(JointSpec {
            body1: 0,
            body2: r.body,
            frame1: Frame { origin, rotation },
            frame2: Frame {
                origin: r.local,
                rotation,
            },
            kind: JointKind::Generic { locked, motors },
            refit,
        }))
    }
}

/// The joint axes a step holds at node `id` (on body `r`), each held velocity added to `held`.
fn held_at(
    step: &Step,
    id: NodeId,
    node: &Node,
    r: NodeRef,
    held: &mut Vec<HeldVelocity>,
) -> [bool; 6] {
    let mut held_here = [false; 6];
    for c in step.conditions.iter().filter(|c| c.node == id) {
        held_here[joint_axis(c.dof)] = true;
        match c.dof {
            Dof::Translation(i) => held.push(HeldVelocity::Translation {
                body: r.body,
                local: r.local,
                direction: node.frame.column(i).into_owned(),
            }),
            Dof::Rotation(i) => held.push(HeldVelocity::Rotation {
                body: r.body,
                axis: node.frame.column(i).into_owned(),
            }),
        }
    }
    held_here
}

/// The ground frame's origin of a node's joint: its position at t = 0, moved along each locked
/// translation by the displacement the static steps left there (motors measure from t = 0); a
/// locked rotation the static steps turned is unsupported.
fn held_where_left(
    node: &Node,
    r: NodeRef,
    locked: &[bool; 6],
    placement: &Placement,
) -> Result<Vector3<f64>, EngineError> {
    let x0 = node.position;
    let u = placement.point(&r) - x0;
    let mut origin = x0;
    let q = placement.rotation[r.body];
    for (i, _) in locked.iter().enumerate().filter(|(_, l)| **l) {
        if i < 3 {
            let e: Vector3<f64> = node.frame.column(i).into_owned();
            origin += e * e.dot(&u);
        } else {
            let a: Vector3<f64> = node.frame.column(i - 3).into_owned();
            if twist(&q, &a).abs() > 1e-12 {
                return unsupported(format!(
                    "node `{}`: rotation {} is held in a dynamic step after a static step turned it",
                    node.name,
                    Dof::Rotation(i - 3)
                ));
            }
        }
    }
    Ok(origin)
}
