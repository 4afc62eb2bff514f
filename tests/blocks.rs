//! The explicit engine's increment by blocks of springs (`Model::step_by_blocks`) against the
//! force pass and the one-pass update it fuses (`Model::forces_with`, then `Model::step`): the
//! same sums in the same order per particle, so the same state bit for bit, on scenes whose
//! springs are scattered over many blocks, with loads, grounded springs, ground ends,
//! particles no spring touches and particles under different held directions, in 2D and 3D
//! and under both rotation models; and the same increments on the one-dimensional store of a
//! scene on one axis (`Model::step_axial`) against them.
mod common;
use common::*;
use crosscheck::case::chain::Chain;
use crosscheck::engines::explicit::blocks::AxialStore;
use crosscheck::engines::explicit::model::{ContactMode, Counters, Model, Point};
use crosscheck::engines::explicit::space::{Lin, Planar, Space, Spatial};
use crosscheck::scene::{
    BoundaryCondition, Connection, Dof, Element, PointLoad, Scene, Step, StepKind,
};
use nalgebra::{Rotation3, Vector3};

/// A chain of `n` masses with its springs in a scrambled order (so that a particle's last
/// spring lies in a far block, and the particles a block finishes are not consecutive),
/// and with what a chain lacks: loads, grounded springs, a spring to the ground mid-chain,
/// a node no spring touches, and particles held in x as well as y, or in neither.
fn scattered_chain(n: usize) -> Scene {
    let mut scene = Chain::new(n, 100).scene();
    let springs = scene.springs.len();
    // 37 and n + 1 share no factor for the sizes below: a permutation.
    let scrambled: Vec<Element> = (0..springs)
        .map(|k| scene.springs[(k * 37) % springs].clone())
        .collect();
    // Nodes 300 (loaded below) and 500 (not) lose both their springs: touched by none.
    scene.springs = scrambled
        .into_iter()
        .filter(|e| {
            !matches!(e.connection, Connection::FixedDirection { nodes, .. }
                if nodes.contains(&300) || nodes.contains(&500))
        })
        .collect();
    scene.springs.push(Element {
        name: "to-ground".into(),
        connection: Connection::FixedDirection {
            nodes: [n + 1, 150],
            direction: Vector3::new(0.6, 0.8, 0.0),
        },
        coefficient: 3.0e3,
    });
    for node in [7, 150, 151, n] {
        scene.springs.push(Element {
            name: format!("grounded-{node}"),
            connection: Connection::Grounded {
                node,
                dof: Dof::Translation(0),
            },
            coefficient: 2.0e3,
        });
    }
    for (node, force) in [(150, 1.0), (300, -2.0), (150, 0.5), (n / 2, 3.0)] {
        scene.loads.push(PointLoad {
            node,
            force: Vector3::new(force, 0.25 * force, 0.0),
        });
    }
    // Node 20 held in x too (held), node 40 free in y (free), and nodes 60..70 held along a
    // tilted direction instead of y (their frame turned by 0.5 rad about z: the held DOF is
    // the frame's second axis).
    for node in 60..70 {
        scene.nodes[node].frame = *Rotation3::from_axis_angle(&Vector3::z_axis(), 0.5).matrix();
    }
    let dynamic = scene
        .steps
        .iter_mut()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .expect("the chain has a dynamic step");
    dynamic.conditions.push(BoundaryCondition {
        node: 20,
        dof: Dof::Translation(0),
        value: None,
    });
    dynamic.conditions.retain(|c| c.node != 40);
    scene
}

/// The scene's dynamic step.
fn dynamic(scene: &Scene) -> &Step {
    scene
        .steps
        .iter()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .expect("the chain has a dynamic step")
}

/// Two runs' positions, rounding carries and velocities are equal (`==`: bit for bit but for
/// the sign of a zero), finite, and moved from `start` (the comparison is not of two untouched
/// copies); `how` names the two runs in the message.
fn assert_same_state<S: Space>(start: &[S::V], a: [&[S::V]; 3], b: [&[S::V]; 3], how: [&str; 2]) {
    let moved = a[0].iter().zip(start).filter(|(u, u0)| u != u0).count();
    assert!(moved > a[0].len() / 2, "{moved} of {} moved", a[0].len());
    for (what, (a, b)) in ["position", "rounding carry", "velocity"]
        .iter()
        .zip(a.iter().zip(b))
    {
        assert!(a.iter().all(|x| x.dot(x).is_finite()), "{what}: not finite");
        if let Some(i) = (0..a.len()).find(|i| a[*i] != b[*i]) {
            panic!(
                "{what} of particle {i}: {:?} {}, {:?} {}",
                a[i], how[0], b[i], how[1]
            );
        }
    }
}

/// Run `increments` increments from a displaced, moving state both ways; the states must
/// agree bit for bit, and the pending forces must be zero again.
fn fused_equals_unfused<S: Space, const FINITE: bool>(scene: &Scene, increments: usize) {
    let model = Model::<S, FINITE>::compile(scene, 0.0);
    assert!(model.can_step_by_blocks(), "{}", scene.id);
    let step = dynamic(scene);
    let held = model.constraints(scene, step);
    let mut cfg = model.initial_config();
    let mut vel = model.zero_rates();
    for (i, (u, v)) in cfg.u.iter_mut().zip(vel.p.iter_mut()).enumerate() {
        let x = i as f64;
        *u = S::v(&Vector3::new(
            1e-3 * (0.1 * x).sin(),
            1e-4 * (0.3 * x).cos(),
            2e-4,
        ));
        *v = S::v(&Vector3::new(1e-2 * (0.2 * x).cos(), 0.0, -1e-3));
    }
    model.enforce(&mut vel, &held);
    let start = cfg.u.clone();
    let h = 1e-3;
    let (mut cfg_b, mut vel_b) = (cfg.clone(), vel.clone());
    let (mut carry, mut carry_b) = (model.zero_rates(), model.zero_rates());
    let (mut forces, mut pending) = (model.zero_forces(), model.zero_forces());
    let mut acc = model.zero_rates();
    let mut counters = Counters::default();
    for _ in 0..increments {
        model.forces_with::<false>(&cfg, ContactMode::Unilateral, &mut forces, &mut counters);
        model.step(
            &mut cfg,
            &mut carry,
            h,
            &forces,
            &mut vel,
            &held,
            &mut acc,
            &mut counters,
        );
        model.step_by_blocks(
            &mut cfg_b,
            &mut carry_b,
            h,
            &mut vel_b,
            &held,
            &mut pending,
            &mut counters,
        );
    }
    // Same operations in the same order: equal bit for bit, not merely to round-off.
    assert_same_state::<S>(
        &start,
        [&cfg.u, &carry.p, &vel.p],
        [&cfg_b.u, &carry_b.p, &vel_b.p],
        ["by passes", "by blocks"],
    );
    assert!(
        pending.p.iter().all(|f| *f == S::v(&Vector3::zeros())),
        "pending forces left non-zero"
    );
}

#[test]
fn blocks_give_the_two_passes_bit_for_bit_in_2d() {
    // 698 line springs (the chain's 701, less the four the cuts remove, and one to the
    // ground): blocks of 256, 256 and 186 springs, then the block after the loads.
    fused_equals_unfused::<Planar, true>(&scattered_chain(700), 50);
}

#[test]
fn blocks_give_the_two_passes_bit_for_bit_in_3d() {
    let mut scene = scattered_chain(700);
    scene.dimension = crosscheck::scene::Dimension::Three;
    // The chain's nodes move in z too in 3D; its ends are held in z as well (massless nodes
    // held in every DOF are the ground).
    for step in &mut scene.steps {
        for node in [0, 701] {
            step.conditions.push(BoundaryCondition {
                node,
                dof: Dof::Translation(2),
                value: None,
            });
        }
    }
    fused_equals_unfused::<Spatial, true>(&scene, 50);
}

#[test]
fn blocks_give_the_two_passes_bit_for_bit_under_small_rotation() {
    fused_equals_unfused::<Planar, false>(&scattered_chain(700), 50);
}

#[test]
fn blocks_without_line_springs_finish_every_particle_after_the_loads() {
    let mut scene = scattered_chain(700);
    scene
        .springs
        .retain(|e| matches!(e.connection, Connection::Grounded { .. }));
    fused_equals_unfused::<Planar, true>(&scene, 50);
}

#[test]
fn blocks_apply_to_particles_and_springs_only() {
    assert!(Model::<Planar, true>::compile(&Chain::new(10, 100).scene(), 0.0).can_step_by_blocks());
    assert!(
        Model::<Planar, true>::compile(&scene("stress/stress_pair_undamped"), 0.0)
            .can_step_by_blocks()
    );
    // Dashpots, bodies and contacts keep the general increment.
    for id in [
        "springs_grounded_a",
        "springs_n2n_c",
        "rigid2d_pin_lumped",
        "stress/contact_drop_e1",
    ] {
        assert!(
            !Model::<Planar, true>::compile(&scene(id), 1e6).can_step_by_blocks(),
            "{id}"
        );
    }
}

/// `scattered_chain` without what takes a particle off the x axis: the spring to the ground
/// along (0.6, 0.8) and the tilted held directions are gone, and the loads act along x. What
/// remains of it: scrambled springs over many blocks, grounded springs along x (two on node
/// 7), loads, a spring to the ground mid-chain along −x, nodes no spring touches, a node held
/// in x as well (held) and one free in y (which only loads off the axis could move off it).
fn axial_chain(n: usize) -> Scene {
    let mut scene = scattered_chain(n);
    scene.springs.retain(|e| e.name != "to-ground");
    scene.springs.push(Element {
        name: "to-ground-along-x".into(),
        connection: Connection::FixedDirection {
            nodes: [150, n + 1],
            direction: -Vector3::x(),
        },
        coefficient: 3.0e3,
    });
    scene.springs.push(Element {
        name: "grounded-7-again".into(),
        connection: Connection::Grounded {
            node: 7,
            dof: Dof::Translation(0),
        },
        coefficient: 5.0e2,
    });
    for node in &mut scene.nodes {
        node.frame = nalgebra::Matrix3::identity();
    }
    for load in &mut scene.loads {
        load.force.y = 0.0;
    }
    scene
}

/// `axial_chain_3d` with nodes 40 and 41 changed: 40 held off the axis in y and z (no
/// particle is free off it), 41 held in y only (free along x and z).
fn axial_chain_3d_across(n: usize) -> Scene {
    let mut scene = axial_chain_3d(n);
    let dynamic = scene
        .steps
        .iter_mut()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .unwrap();
    dynamic
        .conditions
        .retain(|c| c.node != 41 || c.dof != Dof::Translation(2));
    for dof in [1, 2] {
        dynamic.conditions.push(BoundaryCondition {
            node: 40,
            dof: Dof::Translation(dof),
            value: None,
        });
    }
    scene
}

/// The scene with coordinates `a` and `b` swapped: positions, spring directions, loads and
/// the translation DOFs of boundary conditions and grounded springs (frames are the identity).
fn swapped(mut scene: Scene, a: usize, b: usize) -> Scene {
    let swap = |v: &mut Vector3<f64>| v.swap_rows(a, b);
    let dof = |d: &mut Dof| {
        if let Dof::Translation(k) = d {
            *k = if *k == a {
                b
            } else if *k == b {
                a
            } else {
                *k
            };
        }
    };
    for node in &mut scene.nodes {
        swap(&mut node.position);
    }
    for spring in &mut scene.springs {
        match &mut spring.connection {
            Connection::FixedDirection { direction, .. } => swap(direction),
            Connection::Grounded { dof: d, .. } => dof(d),
            Connection::Axial { .. } => {}
        }
    }
    for load in &mut scene.loads {
        swap(&mut load.force);
    }
    for step in &mut scene.steps {
        for c in &mut step.conditions {
            dof(&mut c.dof);
        }
    }
    scene
}

/// The state after `increments` increments by blocks on the 2D or 3D store, and on the
/// one-dimensional one along `axis` (written back twice on the way, with an increment by
/// blocks on the written-back state between, as a row's increment takes one): equal, to the
/// bit but for the sign of a zero (`==`). Off the axis, the displacements keep a value of
/// their own.
fn axial_equals_blocks<S: Space>(scene: &Scene, increments: usize, axis: usize) {
    let model = Model::<S, true>::compile(scene, 0.0);
    let step = dynamic(scene);
    let held = model.constraints(scene, step);
    let mut store = model
        .axial_store(&held)
        .unwrap_or_else(|| panic!("{}: every particle moves along axis {axis}", scene.id));
    let mut cfg = model.initial_config();
    let mut vel = model.zero_rates();
    for (i, (u, v)) in cfg.u.iter_mut().zip(vel.p.iter_mut()).enumerate() {
        let x = i as f64;
        let mut u3 = Vector3::new(2e-4, -3e-4, 4e-4);
        u3[axis] = 1e-3 * (0.1 * x).sin();
        let mut v3 = Vector3::zeros();
        v3[axis] = 1e-2 * (0.2 * x).cos();
        (*u, *v) = (S::v(&u3), S::v(&v3));
    }
    model.enforce(&mut vel, &held);
    let start = cfg.u.clone();
    let h = 1e-3;
    let (mut cfg_b, mut vel_b) = (cfg.clone(), vel.clone());
    let (mut carry, mut carry_b) = (model.zero_rates(), model.zero_rates());
    let (mut pending, mut pending_b) = (model.zero_forces(), model.zero_forces());
    let mut counters = Counters::default();
    let mut counters_b = Counters::default();
    let rows = [increments / 3, 2 * increments / 3];
    for k in 0..increments {
        model.step_by_blocks(
            &mut cfg,
            &mut carry,
            h,
            &mut vel,
            &held,
            &mut pending,
            &mut counters,
        );
        if rows.contains(&k) {
            store.write_back::<S>(&mut cfg_b.u, &mut carry_b.p, &mut vel_b.p);
            model.step_by_blocks(
                &mut cfg_b,
                &mut carry_b,
                h,
                &mut vel_b,
                &held,
                &mut pending_b,
                &mut counters_b,
            );
        } else {
            assert!(model.step_axial(
                &mut store,
                &cfg_b,
                &carry_b,
                h,
                &vel_b,
                &held,
                &mut counters_b
            ));
        }
    }
    store.write_back::<S>(&mut cfg_b.u, &mut carry_b.p, &mut vel_b.p);
    assert_eq!(counters_b.block_increments, increments as u64);
    assert_eq!(counters_b.axial_increments, increments as u64 - 2);
    assert_same_state::<S>(
        &start,
        [&cfg.u, &carry.p, &vel.p],
        [&cfg_b.u, &carry_b.p, &vel_b.p],
        ["on the 2D or 3D store", "on the axis"],
    );
    // Off the axis, the displacements are as they started.
    for (u, u0) in cfg_b.u.iter().zip(&start) {
        let (u, u0) = (S::v3(u), S::v3(u0));
        assert!(
            (0..3).all(|j| j == axis || u[j] == u0[j]),
            "{u:?} from {u0:?}"
        );
    }
}

/// `axial_chain` in 3D: the chain's nodes held in z as in y (ends included), so the moving
/// ones keep x only; node 40, free in y, stays free in z.
fn axial_chain_3d(n: usize) -> Scene {
    let mut scene = axial_chain(n);
    scene.dimension = crosscheck::scene::Dimension::Three;
    for step in &mut scene.steps {
        let z: Vec<BoundaryCondition> = step
            .conditions
            .iter()
            .filter(|c| c.dof == Dof::Translation(1))
            .map(|c| BoundaryCondition {
                node: c.node,
                dof: Dof::Translation(2),
                value: None,
            })
            .collect();
        step.conditions.extend(z);
    }
    scene
}

#[test]
fn the_axis_store_gives_the_blocks_bit_for_bit_in_2d() {
    axial_equals_blocks::<Planar>(&axial_chain(700), 50, 0);
    axial_equals_blocks::<Planar>(&swapped(axial_chain(700), 0, 1), 50, 1);
}

#[test]
fn the_axis_store_gives_the_blocks_bit_for_bit_in_3d() {
    axial_equals_blocks::<Spatial>(&axial_chain_3d(700), 50, 0);
    axial_equals_blocks::<Spatial>(&swapped(axial_chain_3d(700), 0, 2), 50, 2);
    axial_equals_blocks::<Spatial>(&swapped(axial_chain_3d_across(700), 0, 1), 50, 1);
}

/// What would take a particle off the axis keeps the scene on its 2D or 3D store: a spring,
/// a grounded spring or a held direction off the axis (no store), a load off it on a particle
/// free off it (no store), a velocity or rounding carry off it (the store does not load, and
/// the increment is not taken).
#[test]
fn the_axis_store_is_refused_where_a_particle_could_leave_the_axis() {
    fn store<S: Space>(scene: &Scene) -> Option<AxialStore> {
        let model = Model::<S, true>::compile(scene, 0.0);
        let step = dynamic(scene);
        model.axial_store(&model.constraints(scene, step))
    }
    assert!(store::<Planar>(&axial_chain(700)).is_some());
    assert!(
        store::<Planar>(&scattered_chain(700)).is_none(),
        "a spring off the axis"
    );
    let mut tilted = axial_chain(700);
    tilted.nodes[60].frame = *Rotation3::from_axis_angle(&Vector3::z_axis(), 0.5).matrix();
    assert!(
        store::<Planar>(&tilted).is_none(),
        "a held direction off the axis"
    );
    let mut grounded_y = axial_chain(700);
    grounded_y.springs.push(Element {
        name: "grounded-in-y".into(),
        connection: Connection::Grounded {
            node: 7,
            dof: Dof::Translation(1),
        },
        coefficient: 1.0,
    });
    assert!(
        store::<Planar>(&grounded_y).is_none(),
        "a grounded spring off the axis"
    );
    let mut pushed = axial_chain(700);
    pushed.loads[0].force.y = 1.0;
    assert!(
        store::<Planar>(&pushed).is_none(),
        "a load off the axis, node 40 free in y"
    );
    // Held in y, node 40 may carry a load off the axis: the projection removes it.
    let mut pushed_held = pushed.clone();
    for step in &mut pushed_held.steps {
        step.conditions.push(BoundaryCondition {
            node: 40,
            dof: Dof::Translation(1),
            value: None,
        });
    }
    assert!(
        store::<Planar>(&pushed_held).is_some(),
        "every particle held off the axis"
    );
    // In 3D, node 41 held in y only is free in z. A load off the axis anywhere refuses the
    // store then, in z as in y: the check is one per scene, not per particle (a load in y on
    // node 150, held in y and z, could not move it off the axis; the store is refused anyway).
    let across = axial_chain_3d_across(700);
    assert!(store::<Spatial>(&across).is_some());
    let mut pushed_z = across.clone();
    pushed_z.loads[0].force.z = 1.0;
    assert!(
        store::<Spatial>(&pushed_z).is_none(),
        "a load in z, node 41 free in z"
    );
    let mut pushed_y = across;
    pushed_y.loads[0].force.y = 1.0;
    assert!(
        store::<Spatial>(&pushed_y).is_none(),
        "a load in y, node 41 free in z"
    );

    let scene = axial_chain(700);
    let model = Model::<Planar, true>::compile(&scene, 0.0);
    let step = dynamic(&scene);
    let held = model.constraints(&scene, step);
    let mut store = model.axial_store(&held).unwrap();
    let (cfg, mut carry, mut vel) = (
        model.initial_config(),
        model.zero_rates(),
        model.zero_rates(),
    );
    let Point::Particle(i) = model.points[40] else {
        panic!("node 40 is a particle");
    };
    let mut counters = Counters::default();
    vel.p[i].y = 1e-3;
    assert!(!model.step_axial(&mut store, &cfg, &carry, 1e-3, &vel, &held, &mut counters));
    vel.p[i].y = 0.0;
    carry.p[i].y = 1e-20;
    assert!(!model.step_axial(&mut store, &cfg, &carry, 1e-3, &vel, &held, &mut counters));
    assert_eq!(counters, Counters::default());
    carry.p[i].y = 0.0;
    assert!(model.step_axial(&mut store, &cfg, &carry, 1e-3, &vel, &held, &mut counters));
    assert_eq!(counters.axial_increments, 1);
}
