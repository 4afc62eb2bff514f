//! The malformed-case corpus: every file in `tests/malformed/` is a copy of a real case with
//! one defect, and must be refused with a message that says where (file, line, key path) and
//! what is wrong, both by the library (`case::load_checked`, the validation every run does
//! first) and by the binary (`crosscheck check` and `crosscheck run`, exit code 2, nothing
//! written).
//!
//! Adding a file to `tests/malformed/` without adding its expectation to [`CORPUS`] fails
//! [`every_file_in_the_corpus_has_an_expectation`].

use crosscheck::case::{self, CaseError};
use crosscheck::run::check_scene;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// (file stem, line the message points at, key path, fragment of the message).
///
/// The key path is what the one-line message shows between the location and the message:
/// `syntax` for a TOML error that is not inside a key.
const CORPUS: &[(&str, usize, &str, &str)] = &[
    // TOML syntax and schema (unknown key, wrong type, missing field).
    (
        "toml_syntax_error",
        83,
        "syntax",
        "missing comma between array elements",
    ),
    (
        "unknown_key_top_level",
        8,
        "gravity",
        "unknown field `gravity`, expected one of",
    ),
    (
        "unknown_key_nested",
        83,
        "springs[1].stifness",
        "unknown field `stifness`, expected one of",
    ),
    (
        "unknown_key_time",
        14,
        "time.incremnt",
        "unknown field `incremnt`, expected one of `increment`",
    ),
    (
        "wrong_type_string_for_number",
        63,
        "masses[0].mass",
        "invalid type: string \"0.02588\"",
    ),
    (
        "wrong_type_negative_rows",
        20,
        "output.rows",
        "invalid value: integer `-501`",
    ),
    (
        "missing_required_field",
        57,
        "nodes[2]",
        "missing field `at`",
    ),
    ("missing_title", 1, "(top level)", "missing field `title`"),
    // Family, dimension, id.
    (
        "family_invalid",
        6,
        "family",
        "`spring`: use `rigid_body` or `springs`",
    ),
    ("dimension_invalid", 7, "dimension", "is 4; use 2 or 3"),
    (
        "id_mismatch",
        4,
        "id",
        "is `springs_n2n_b` but the file is `id_mismatch.toml`; they must match",
    ),
    // Vectors and numbers.
    (
        "vector_wrong_components",
        59,
        "nodes[2].at",
        "has 3 components; a 2D case needs 2",
    ),
    (
        "direction_nan",
        82,
        "springs[1].direction",
        "has a non-finite component",
    ),
    (
        "position_inf",
        55,
        "nodes[1].at",
        "has a non-finite component",
    ),
    (
        "stiffness_inf",
        83,
        "springs[1].stiffness",
        "must be a finite number >= 0, got inf",
    ),
    (
        "direction_zero",
        82,
        "springs[1].direction",
        "is a zero vector; a direction is needed",
    ),
    // Mass, inertia, coefficients.
    (
        "mass_zero",
        63,
        "masses[0].mass",
        "a mass must be a finite number > 0, got 0",
    ),
    (
        "mass_negative_body",
        87,
        "bodies[0].mass",
        "a mass must be a finite number > 0, got -20",
    ),
    (
        "inertia_negative",
        88,
        "bodies[0].inertia",
        "the inertia must be positive semi-definite",
    ),
    (
        "inertia_not_symmetric",
        91,
        "bodies[0].inertia",
        "the inertia matrix must be symmetric",
    ),
    (
        "inertia_2d_array",
        88,
        "bodies[0].inertia",
        "in 2D the inertia is a number (about z)",
    ),
    (
        "stiffness_negative",
        83,
        "springs[1].stiffness",
        "must be a finite number >= 0, got -30",
    ),
    (
        "damping_negative",
        90,
        "dashpots[0].damping",
        "must be a finite number >= 0, got -0.12",
    ),
    (
        "element_both_coefficients",
        85,
        "dashpots[0]",
        "a dashpot takes exactly one coefficient: `damping`",
    ),
    (
        "element_no_coefficient",
        78,
        "springs[1]",
        "a spring takes exactly one coefficient: `stiffness`",
    ),
    // Elements.
    (
        "element_wrong_node_count",
        74,
        "springs[0].nodes",
        "a fixed_direction spring joins 2 node(s), got 1",
    ),
    (
        "element_unknown_kind",
        80,
        "springs[1].kind",
        "`linear`: use grounded, fixed_direction or axial",
    ),
    (
        "element_grounded_without_dof",
        54,
        "springs[0].dof",
        "a grounded element needs `dof`",
    ),
    (
        "element_fixed_direction_without_direction",
        71,
        "springs[0].direction",
        "a fixed_direction element needs `direction`",
    ),
    (
        "element_axial_coincident_nodes",
        90,
        "springs[1].nodes",
        "an axial element needs two nodes at different positions",
    ),
    // References to nodes, bodies, frames, contacts.
    (
        "unknown_node",
        81,
        "springs[1].nodes",
        "names node `14`, which the case does not define",
    ),
    (
        "unknown_body",
        61,
        "nodes[1].body",
        "names body `bdy`, which the case does not define",
    ),
    (
        "unknown_frame",
        60,
        "nodes[2].frame",
        "names frame `line`, which the case does not define",
    ),
    (
        "unknown_contact_in_column",
        44,
        "output.columns[3].contact_force",
        "names contact `fase`, which the case does not define",
    ),
    (
        "duplicate_node_id",
        58,
        "nodes[2].id",
        "`12` is defined twice",
    ),
    // DOFs.
    (
        "rotation_on_plain_node_hold",
        110,
        "steps[1].hold[1].dofs",
        "node `13` has no rotational DOF (it is not a reference node)",
    ),
    (
        "rotation_on_plain_node_spring",
        58,
        "springs[0].dof",
        "a rotational DOF exists only at a body's reference node",
    ),
    (
        "uz_in_2d",
        110,
        "steps[1].hold[1].dofs",
        "`uz` does not exist in 2D; use ux, uy or rz",
    ),
    (
        "dof_unknown_name",
        110,
        "steps[1].hold[1].dofs",
        "`y` is not a DOF; use ux, uy, uz, rx, ry or rz",
    ),
    // Contact.
    (
        "contact_off_face",
        115,
        "contacts[0].node",
        "from the face at t = 0; a closed contact must start on it",
    ),
    (
        "contact_inside_solid",
        76,
        "contacts[0].node",
        "is inside the cuboid's surface at t = 0",
    ),
    (
        "contact_extent_zero",
        80,
        "contacts[0].half_extents",
        "every half extent must be a finite number > 0, got 0",
    ),
    (
        "contact_restitution_above_one",
        82,
        "contacts[0].restitution",
        "a coefficient of restitution is in [0, 1], got 1.5",
    ),
    (
        "contact_shape_key",
        81,
        "contacts[0].radius",
        "a cuboid contact has no `radius`",
    ),
    (
        "contact_shape_unknown",
        78,
        "contacts[0].shape",
        "`torus`: use plane, ball, cuboid, capsule or convex",
    ),
    (
        "contact_convex_not_corner",
        93,
        "contacts[0].vertices[3]",
        "corner 3 (-0.5, -0.25, 0) is not a corner of the convex hull of the others",
    ),
    (
        "contact_convex_repeated",
        93,
        "contacts[0].vertices[3]",
        "corner 3 repeats corner 0",
    ),
    (
        "contact_convex_straight",
        93,
        "contacts[0].vertices[3]",
        "is almost straight: two faces that meet there turn by 2.0e-5 rad, less than 1e-3",
    ),
    (
        "contact_convex_flat",
        89,
        "contacts[0].vertices",
        "the corners are collinear: the polygon has no interior",
    ),
    (
        "contact_node_on_body",
        115,
        "contacts[0].node",
        "a node of a body touches through a ball: give `node_radius` (or use an independent node)",
    ),
    (
        "contact_radius_on_particle",
        89,
        "contacts[0].node_radius",
        "an independent node touches with itself (a particle has no turning); a ball belongs to a body's node",
    ),
    (
        "contact_radius_on_solid",
        91,
        "contacts[0].node_radius",
        "a node's ball touches a plane face only (give `face_point` and `face_normal`)",
    ),
    (
        "contact_radius_off_face",
        90,
        "contacts[0].node",
        "the ball (radius 0.4) of node `C` is 9.999999999999998e-2 from the face at t = 0; a closed contact must start on it",
    ),
    (
        "contact_normal_zero",
        118,
        "contacts[0].face_normal",
        "is a zero vector; a direction is needed",
    ),
    // Loads.
    (
        "load_on_held_dofs",
        125,
        "loads[0].force",
        "acts on node `O` only along held DOFs in every dynamic step, so it does nothing",
    ),
    (
        "load_on_fixed_node",
        125,
        "loads[0].force",
        "acts on node `G1` only along held DOFs in every dynamic step, so it does nothing",
    ),
    // Boundary conditions, steps, mass of what moves.
    (
        "held_and_prescribed",
        101,
        "steps[0].prescribe[0].dof",
        "ux of node `13` is both held and prescribed in this step",
    ),
    (
        "prescribe_on_fixed_node",
        101,
        "steps[0].prescribe[0].dof",
        "ux of node `11` is both held and prescribed in this step",
    ),
    (
        "prescribe_in_dynamic_step",
        112,
        "steps[1].prescribe[0]",
        "prescribed displacements are supported in static steps only",
    ),
    (
        "dynamic_without_duration",
        105,
        "steps[1].duration",
        "a dynamic step needs `duration`",
    ),
    (
        "duration_zero",
        107,
        "steps[1].duration",
        "a duration must be a finite number > 0, got 0",
    ),
    (
        "static_with_duration",
        97,
        "steps[0].duration",
        "a static step takes no duration",
    ),
    (
        "step_unknown_kind",
        96,
        "steps[0].kind",
        "`quasi_static`: use static or dynamic",
    ),
    (
        "no_dynamic_step",
        95,
        "steps",
        "a case needs at least one dynamic step",
    ),
    (
        "fixed_body_point",
        62,
        "nodes[1].fixed",
        "a body's material point cannot be fixed",
    ),
    (
        "massless_free_node",
        104,
        "steps[1].hold",
        "node `12` has no mass but is not held in every DOF",
    ),
    (
        "body_without_mass",
        84,
        "bodies[0].mass",
        "the body has no mass: give `mass` or put point masses on its nodes",
    ),
    (
        "body_without_inertia",
        84,
        "bodies[0].inertia",
        "rotation rz of body `body` is free in steps[0] but its inertia about that axis is 0: give `inertia`",
    ),
    (
        "angular_velocity_plain_node",
        138,
        "initial_velocities[1].angular",
        "only a body's reference node has an angular velocity",
    ),
    // Time incrementation.
    (
        "increment_zero",
        14,
        "time.increment",
        "an increment must be a finite number > 0, got 0",
    ),
    (
        "increment_negative",
        14,
        "time.increment",
        "an increment must be a finite number > 0, got -0.00005",
    ),
    (
        "increment_above_stable",
        14,
        "time.increment",
        "1e-1 is above this scene's stable increment",
    ),
    (
        "increment_and_accuracy",
        13,
        "time",
        "give `increment` or `accuracy`, not both",
    ),
    (
        "safety_above_one",
        14,
        "time.safety",
        "must be in (0, 1], got 1.5",
    ),
    ("safety_zero", 14, "time.safety", "must be in (0, 1], got 0"),
    (
        "tolerance_with_increment",
        15,
        "time.tolerance",
        "chooses the increment itself: give no `increment`, `accuracy` or `safety` with it",
    ),
    (
        "time_tolerance_negative",
        14,
        "time.tolerance",
        "a tolerance must be a finite number > 0, got -0.0001",
    ),
    (
        "damping_treatment_unknown",
        15,
        "time.damping",
        "`implicit`: use centred or lagged",
    ),
    (
        "penalty_both",
        15,
        "contact",
        "give `penalty_stiffness` or `penalty_ratio`, not both",
    ),
    // Output.
    (
        "rows_too_few",
        20,
        "output.rows",
        "is 100; the contract needs at least 200",
    ),
    (
        "columns_misordered",
        23,
        "output.columns[0]",
        "is `u_mid`, but column 1 of a springs case must be `u_end`",
    ),
    (
        "columns_missing",
        23,
        "output.columns[3]",
        "is missing, but column 4 of a springs case must be `v_mid`",
    ),
    (
        "column_gap_unknown_contact",
        60,
        "output.columns[5].gap",
        "names contact `drip`, which the case does not define",
    ),
    (
        "column_two_probes",
        23,
        "output.columns[0]",
        "give exactly one of displacement, velocity, rotation, contact_force, gap, zero",
    ),
    (
        "column_without_direction",
        23,
        "output.columns[0].direction",
        "this column needs `direction`",
    ),
    (
        "column_axis_in_2d",
        28,
        "output.columns[0].axis",
        "a 2D rotation is about z; drop `axis`",
    ),
    // Tolerances.
    (
        "tolerance_zero",
        120,
        "tolerances.explicit",
        "a tolerance must be a finite number > 0, got 0",
    ),
    (
        "tolerance_negative",
        119,
        "tolerances.explicit_small",
        "a tolerance must be a finite number > 0, got -0.0001",
    ),
    (
        "tolerance_not_a_number",
        120,
        "tolerances.explicit",
        "expected a finite number, got `\"1e-4\"`",
    ),
    // Defects found uncaught once, now refused.
    (
        "tolerance_unknown_engine",
        133,
        "tolerances.explicit_smal",
        "`explicit_smal` is not an engine; valid names: analytic, reference, exp",
    ),
    (
        "safety_with_increment",
        29,
        "time.safety",
        "applies only when neither `increment` nor `accuracy` is give",
    ),
    (
        "hold_all_and_more",
        112,
        "steps[0].hold[0].dofs",
        "\"all\" already holds every DOF; give it alone",
    ),
    (
        "hold_empty",
        113,
        "steps[0].hold[1].dofs",
        "is empty: name the held DOFs (ux, uy, uz, rx, ry, rz) or [\"a",
    ),
    (
        "self_joined_spring",
        88,
        "springs[0].nodes",
        "joins a node to itself; give two different nodes",
    ),
    (
        "direction_on_grounded",
        69,
        "springs[0].direction",
        "does not apply to a grounded spring; remove it",
    ),
    (
        "column_name_twice",
        43,
        "output.columns[1].name",
        "`u_end` is already a column",
    ),
    (
        "initial_velocity_on_held_dof",
        152,
        "initial_velocities[1].velocity",
        "moves node `N` along uy, which the first dynamic step holds;",
    ),
    (
        "initial_velocity_twice",
        151,
        "initial_velocities[1].node",
        "node `O` already has an initial velocity",
    ),
    (
        "load_zero",
        140,
        "loads[0].force",
        "is zero; give a non-zero force or remove the load",
    ),
    (
        "contact_id_twice",
        136,
        "contacts[1].id",
        "`face` is defined twice",
    ),
    // Hostile numbers and names: ids that would escape the report directory or break a
    // CSV header, engine-added column names, magnitudes that overflow or underflow.
    ("id_dotdot", 20, "id", "`..` is not a valid id"),
    ("id_slash", 20, "id", "`a/b` is not a valid id"),
    ("id_space", 21, "id", "`rigid pin` is not a valid id"),
    ("id_empty", 23, "id", "`` is not a valid id"),
    (
        "column_named_e_kinetic",
        55,
        "output.columns[3].name",
        "`e_kinetic` is a column an engine adds",
    ),
    (
        "column_named_t",
        55,
        "output.columns[3].name",
        "`t` is a column an engine adds",
    ),
    (
        "column_named_valid",
        60,
        "output.columns[3].name",
        "`valid` is a column an engine adds",
    ),
    (
        "column_name_comma",
        55,
        "output.columns[3].name",
        "`v,mid` is not a valid id",
    ),
    (
        "node_id_invalid",
        95,
        "nodes[5].id",
        "`P 1` is not a valid id",
    ),
    (
        "body_id_invalid",
        107,
        "bodies[0].id",
        "`bo\"dy` is not a valid id",
    ),
    (
        "contact_id_invalid",
        136,
        "contacts[0].id",
        "`face/1` is not a valid id",
    ),
    (
        "stiffness_huge",
        92,
        "springs[0].stiffness",
        "1e308 is outside the supported magnitude range",
    ),
    (
        "stiffness_denormal",
        119,
        "springs[0].stiffness",
        "1e-310 is outside the supported magnitude range",
    ),
    (
        "damping_huge",
        106,
        "dashpots[0].damping",
        "1e200 is outside the supported magnitude range",
    ),
    (
        "mass_denormal",
        79,
        "masses[0].mass",
        "1e-310 is outside the supported magnitude range",
    ),
    (
        "mass_huge",
        104,
        "bodies[0].mass",
        "1e300 is outside the supported magnitude range",
    ),
    (
        "inertia_denormal",
        105,
        "bodies[0].inertia",
        "1e-310 is outside the supported magnitude range",
    ),
    (
        "inertia_huge_3d",
        110,
        "bodies[0].inertia",
        "1e200 is outside the supported magnitude range",
    ),
    (
        "load_huge",
        142,
        "loads[0].force",
        "-1e308 is outside the supported magnitude range",
    ),
    (
        "load_denormal",
        146,
        "loads[0].force",
        "1e-320 is outside the supported magnitude range",
    ),
    (
        "position_huge",
        96,
        "nodes[5].at",
        "-1e300 is outside the supported magnitude range",
    ),
    (
        "position_denormal",
        99,
        "nodes[5].at",
        "1e-315 is outside the supported magnitude range",
    ),
    (
        "velocity_huge",
        154,
        "initial_velocities[0].velocity",
        "1.5e200 is outside the supported magnitude range",
    ),
    (
        "angular_velocity_tiny",
        155,
        "initial_velocities[0].angular",
        "1e-300 is outside the supported magnitude range",
    ),
    (
        "increment_denormal",
        30,
        "time.increment",
        "5e-324 is outside the supported magnitude range",
    ),
    (
        "increment_tiny",
        33,
        "time.increment",
        "1e-200 is outside the supported magnitude range",
    ),
    (
        "accuracy_tiny",
        30,
        "time.accuracy",
        "1e-300 is outside the supported magnitude range",
    ),
    (
        "duration_huge",
        123,
        "steps[1].duration",
        "1e200 is outside the supported magnitude range",
    ),
    (
        "duration_denormal",
        163,
        "steps[0].duration",
        "5e-324 is outside the supported magnitude range",
    ),
    (
        "penalty_ratio_huge",
        39,
        "contact.penalty_ratio",
        "1e300 is outside the supported magnitude range",
    ),
    (
        "penalty_stiffness_tiny",
        41,
        "contact.penalty_stiffness",
        "1e-200 is outside the supported magnitude range",
    ),
    (
        "tolerance_tiny",
        135,
        "tolerances.explicit_small",
        "1e-300 is outside the supported magnitude range",
    ),
    (
        "safety_denormal",
        30,
        "time.safety",
        "1e-310 is outside the supported magnitude range",
    ),
];

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed")
}

fn path_of(stem: &str) -> PathBuf {
    corpus_dir().join(format!("{stem}.toml"))
}

/// The text of 1-based line `line` of `path`.
fn source_line(path: &Path, line: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .nth(line - 1)
        .unwrap_or_else(|| panic!("{} has no line {line}", path.display()))
        .trim_end()
        .to_string()
}

fn crosscheck(args: &[&std::ffi::OsStr], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_crosscheck"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run crosscheck")
}

/// Checks one entry against the library; `Err` says what did not hold.
fn library_refuses(stem: &str, line: usize, key: &str, fragment: &str) -> Result<(), String> {
    let path = path_of(stem);
    let err: CaseError = match case::load_checked(&path, &check_scene) {
        Ok(_) => return Err(format!("{stem}: accepted, but it is malformed")),
        Err(e) => e,
    };
    let one = err.to_string();
    let mut problems = Vec::new();
    if !matches!(err, CaseError::Syntax { .. } | CaseError::Invalid { .. }) {
        problems.push("is neither a syntax nor a validation error".to_string());
    }
    if one.contains('\n') {
        problems.push("the message is more than one line".to_string());
    }
    let prefix = format!("{}:{line}:", path.display());
    if !one.starts_with(&prefix) {
        problems.push(format!("does not start with `{prefix}`"));
    }
    if !one.contains(&format!(": {key}: ")) {
        problems.push(format!("does not name the key `{key}`"));
    }
    if key != "syntax" && err.key() != Some(key) {
        problems.push(format!("key() is {:?}, expected {key:?}", err.key()));
    }
    if !one.contains(fragment) {
        problems.push(format!("does not say `{fragment}`"));
    }
    let rendered = err.render();
    let offending = source_line(&path, line);
    if offending.trim().is_empty() {
        problems.push(format!("line {line} is blank: nothing to show"));
    }
    if !rendered.contains(&offending) {
        problems.push(format!("render() does not show line {line} `{offending}`"));
    }
    if !rendered.contains(fragment) {
        problems.push("render() does not carry the message".to_string());
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{stem}: {}\n  message: {one}\n  rendered:\n{rendered}",
            problems.join("; ")
        ))
    }
}

#[test]
fn the_library_refuses_every_malformed_case_and_says_where_and_why() {
    let failures: Vec<String> = CORPUS
        .iter()
        .filter_map(|&(stem, line, key, fragment)| library_refuses(stem, line, key, fragment).err())
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} malformed case(s) not refused as expected:\n{}",
        failures.len(),
        CORPUS.len(),
        failures.join("\n")
    );
}

#[test]
fn check_exits_2_and_prints_the_located_message_for_every_malformed_case() {
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for &(stem, line, key, fragment) in CORPUS {
        let path = path_of(stem);
        let out = crosscheck(&["check".as_ref(), path.as_os_str()], dir.path());
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let located = format!("{}:{line}:", path.display());
        if out.status.code() != Some(2)
            || stdout.contains("ok:")
            || !stderr.contains(&located)
            || !stderr.contains(&format!(": {key}: "))
            || !stderr.contains(fragment)
            || !stderr.contains(&source_line(&path, line))
            || !stderr.contains("1 of 1 case file(s) invalid")
        {
            failures.push(format!(
                "{stem}: status {:?}\nstdout:\n{stdout}\nstderr:\n{stderr}",
                out.status
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn check_of_the_whole_corpus_at_once_reports_every_file_invalid() {
    let dir = tempfile::tempdir().unwrap();
    let paths: Vec<PathBuf> = CORPUS.iter().map(|(stem, ..)| path_of(stem)).collect();
    let mut args: Vec<&std::ffi::OsStr> = vec!["check".as_ref()];
    args.extend(paths.iter().map(|p| p.as_os_str()));
    let out = crosscheck(&args, dir.path());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stdout.contains("ok:"), "{stdout}");
    let summary = format!("{n} of {n} case file(s) invalid", n = CORPUS.len());
    assert!(stderr.contains(&summary), "no `{summary}` in:\n{stderr}");
    for (stem, line, ..) in CORPUS {
        let located = format!("{}:{line}:", path_of(stem).display());
        assert!(stderr.contains(&located), "no `{located}` in:\n{stderr}");
    }
}

#[test]
fn run_exits_2_and_writes_nothing_for_every_malformed_case() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let mut failures = Vec::new();
    for &(stem, line, _, fragment) in CORPUS {
        let path = path_of(stem);
        let out = crosscheck(
            &[
                "run".as_ref(),
                path.as_os_str(),
                "--out".as_ref(),
                out_dir.as_os_str(),
                "--quiet".as_ref(),
            ],
            dir.path(),
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        let located = format!("{}:{line}:", path.display());
        if out.status.code() != Some(2)
            || out_dir.exists()
            || !stderr.contains(&located)
            || !stderr.contains(fragment)
            || !stderr.contains("nothing was run")
        {
            failures.push(format!(
                "{stem}: status {:?}, {} exists: {}\nstderr:\n{stderr}",
                out.status,
                out_dir.display(),
                out_dir.exists()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Nothing else was written either (e.g. a default `report/` in the working directory).
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "run wrote {left:?}");
}

#[test]
fn every_file_in_the_corpus_has_an_expectation() {
    let mut stems: Vec<&str> = CORPUS.iter().map(|(stem, ..)| *stem).collect();
    stems.sort_unstable();
    let before = stems.len();
    stems.dedup();
    assert_eq!(stems.len(), before, "a stem appears twice in CORPUS");

    let mut files = Vec::new();
    for entry in std::fs::read_dir(corpus_dir()).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        files.push(name);
    }
    files.sort();
    assert!(
        files.len() >= 30,
        "the corpus has {} files; it should have at least 30",
        files.len()
    );
    let unexpected: Vec<&String> = files
        .iter()
        .filter(|f| {
            f.strip_suffix(".toml")
                .is_none_or(|stem| stems.binary_search(&stem).is_err())
        })
        .collect();
    assert!(
        unexpected.is_empty(),
        "files in tests/malformed/ without an expectation in CORPUS: {unexpected:?}"
    );
    let missing: Vec<&&str> = stems
        .iter()
        .filter(|s| !files.contains(&format!("{s}.toml")))
        .collect();
    assert!(
        missing.is_empty(),
        "CORPUS entries without a file: {missing:?}"
    );
}
