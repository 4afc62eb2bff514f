//! The general linear solver (`analytic::linear`) against the hand-derived forms and against
//! small scenes solved by hand.
use crosscheck::case;
use crosscheck::engines::History;
use crosscheck::engines::analytic::{linear, springs};
use std::path::Path;

fn column(h: &History, name: &str) -> Vec<f64> {
    h.column(name)
        .unwrap_or_else(|| panic!("no column `{name}`"))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn peak(a: &[f64]) -> f64 {
    a.iter().map(|x| x.abs()).fold(0.0, f64::max)
}

/// Largest |column − f(t)| over the rows.
fn worst(h: &History, name: &str, f: impl Fn(f64) -> f64) -> f64 {
    let t = column(h, "t");
    let expected: Vec<f64> = t.iter().map(|&t| f(t)).collect();
    max_diff(&column(h, name), &expected)
}

/// On the five spring cases the general solver equals the hand-derived forms. Both are exact,
/// so they differ only by the round-off of the matrix exponential (a 3×3 or 5×5 augmented one
/// here, a 4×4 one or sin/cos/exp there): 1e-12 of each column's peak is ~10⁴ roundings of
/// 1e-16, far below any modelling difference.
#[test]
fn matches_hand_derived_spring_forms() {
    for id in [
        "springs_grounded_a",
        "springs_grounded_b",
        "springs_grounded_c",
        "springs_n2n_b",
        "springs_n2n_c",
    ] {
        let scene = case::load(&case::cases_dir().join(format!("{id}.toml"))).unwrap();
        let general = linear::solve(&scene).unwrap();
        let hand = springs::solve(&scene).unwrap();
        assert_eq!(column(&general, "t"), column(&hand, "t"));
        assert!(column(&general, "valid").iter().all(|&v| v == 1.0));
        for name in ["u_end", "u_mid", "v_end", "v_mid"] {
            let (x, y) = (column(&general, name), column(&hand, name));
            let d = max_diff(&x, &y);
            let p = peak(&y);
            println!(
                "{id} {name}: {:.2e} of the peak {p:.3e}",
                d / p.max(f64::MIN_POSITIVE)
            );
            assert!(d <= 1e-12 * p, "{id} {name}: differs by {d:e} (peak {p:e})");
        }
    }
}

/// A body pinned at its reference node O with inertia I = 2 about O and a grounded rotational
/// spring k = 8 on rz, spun at ω₀ = 1: I θ̈ + k θ = 0, so θ = (ω₀/ω) sin ωt with ω = √(k/I) = 2,
/// θ = sin(2t)/2; a massless body point P at (0, 1) moves by θ × ρ, so ux_P = −θ. The 3D twin
/// turns about the tilted frame axis (−1, 1, 0)/√2 of O, the other rotations held.
#[test]
fn pinned_body_on_rotational_spring() {
    let two_d = r#"
id = "x"
title = "pinned body on a rotational spring"
family = "rigid_body"
dimension = 2
[time]
increment = 1.0e-4
[output]
rows = 201
[[output.columns]]
name = "rz"
rotation = "body"
[[output.columns]]
name = "ux"
displacement = "O"
direction = [1.0, 0.0]
[[output.columns]]
name = "ux_node"
zero = "no contact node"
[[output.columns]]
name = "contact_force"
zero = "no contact"
[[output.columns]]
name = "ux_p"
displacement = "P"
direction = [1.0, 0.0]
[[nodes]]
id = "O"
at = [0.0, 0.0]
[[nodes]]
id = "P"
at = [0.0, 1.0]
body = "body"
[[bodies]]
id = "body"
reference = "O"
mass = 1.0
inertia = 2.0
[[springs]]
kind = "grounded"
nodes = ["O"]
dof = "rz"
stiffness = 8.0
[[initial_velocities]]
node = "O"
angular = 1.0
[[steps]]
kind = "dynamic"
duration = 3.0
hold = [{ node = "O", dofs = ["ux", "uy"] }]
"#;
    let h = linear::solve(&case::parse(two_d, Path::new("x.toml")).unwrap()).unwrap();
    let theta = |t: f64| (2.0 * t).sin() / 2.0;
    let d_rz = worst(&h, "rz", theta);
    let d_p = worst(&h, "ux_p", |t| -theta(t));
    let d_o = worst(&h, "ux", |_| 0.0);
    println!("2D pinned body: rz {d_rz:.2e}, ux_P {d_p:.2e}, ux_O {d_o:.2e}");
    assert!(d_rz <= 1e-12 && d_p <= 1e-12 && d_o == 0.0);

    let three_d = r#"
id = "x"
title = "pinned body on a rotational spring, 3D"
family = "rigid_body"
dimension = 3
[time]
increment = 1.0e-4
[output]
rows = 201
[[output.columns]]
name = "rz"
rotation = "body"
axis = [-1.0, 1.0, 0.0]
[[output.columns]]
name = "ux"
displacement = "O"
direction = [1.0, 0.0, 0.0]
[[output.columns]]
name = "ux_node"
zero = "no contact node"
[[output.columns]]
name = "contact_force"
zero = "no contact"
[[frames]]
id = "tilted"
x_axis = [1.0, 1.0, 0.0]
y_axis = [-1.0, 1.0, 0.0]
[[nodes]]
id = "O"
at = [0.0, 0.0, 0.0]
frame = "tilted"
[[bodies]]
id = "body"
reference = "O"
mass = 1.0
inertia = [2.0, 2.0, 2.0]
[[springs]]
kind = "grounded"
nodes = ["O"]
dof = "ry"
stiffness = 8.0
[[initial_velocities]]
node = "O"
angular = [-0.7071067811865476, 0.7071067811865476, 0.0]
[[steps]]
kind = "dynamic"
duration = 3.0
hold = [{ node = "O", dofs = ["ux", "uy", "uz", "rx", "rz"] }]
"#;
    let h = linear::solve(&case::parse(three_d, Path::new("x.toml")).unwrap()).unwrap();
    let d3 = worst(&h, "rz", theta);
    println!("3D pinned body about a tilted axis: rz {d3:.2e}");
    assert!(d3 <= 1e-12);
}

/// A free particle (m = 2) between two axial springs along x (k = 3 and 5 to fixed nodes),
/// launched at v₀ = (1, 0.5): along x, m ü + (k₁ + k₂) u = 0 with ω = √(8/2) = 2, so
/// u_x = sin(2t)/2, v_x = cos 2t; the linearised axial springs do not resist y, so
/// u_y = 0.5 t, v_y = 0.5 (a zero-frequency mode, also exact through the exponential).
#[test]
fn particle_between_two_springs() {
    let text = r#"
id = "x"
title = "particle between two springs"
family = "springs"
dimension = 2
[time]
increment = 1.0e-4
[output]
rows = 201
[[output.columns]]
name = "u_end"
displacement = "P"
direction = [1.0, 0.0]
[[output.columns]]
name = "u_mid"
displacement = "P"
direction = [0.0, 1.0]
[[output.columns]]
name = "v_end"
velocity = "P"
direction = [1.0, 0.0]
[[output.columns]]
name = "v_mid"
velocity = "P"
direction = [0.0, 1.0]
[[nodes]]
id = "G1"
at = [-1.0, 0.0]
fixed = true
[[nodes]]
id = "P"
at = [0.0, 0.0]
[[nodes]]
id = "G2"
at = [1.0, 0.0]
fixed = true
[[masses]]
node = "P"
mass = 2.0
[[springs]]
kind = "axial"
nodes = ["G1", "P"]
stiffness = 3.0
[[springs]]
kind = "axial"
nodes = ["P", "G2"]
stiffness = 5.0
[[initial_velocities]]
node = "P"
velocity = [1.0, 0.5]
[[steps]]
kind = "dynamic"
duration = 3.0
"#;
    let h = linear::solve(&case::parse(text, Path::new("x.toml")).unwrap()).unwrap();
    let d = [
        worst(&h, "u_end", |t| (2.0 * t).sin() / 2.0),
        worst(&h, "v_end", |t| (2.0 * t).cos()),
        worst(&h, "u_mid", |t| 0.5 * t),
        worst(&h, "v_mid", |_| 0.5),
    ];
    println!(
        "particle: u_x {:.2e}, v_x {:.2e}, u_y {:.2e}, v_y {:.2e}",
        d[0], d[1], d[2], d[3]
    );
    assert!(d.iter().all(|&x| x <= 1e-12), "{d:?}");
}
