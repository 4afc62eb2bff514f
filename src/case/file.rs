//! The case file as written on disk (`cases/<id>.toml`), before validation.
//!
//! Every table denies unknown keys so a typo is an error, not a silently ignored setting.
//! Vectors are written with as many components as the case's dimension (2 or 3).

use serde::Deserialize;

/// A whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// Stable id; must equal the file stem.
    pub id: String,
    /// One line saying what the case is.
    pub title: String,
    /// Output family: `rigid_body` or `springs` (decides the contract columns).
    pub family: String,
    /// 2 or 3.
    pub dimension: u8,
    /// Time incrementation.
    #[serde(default)]
    pub time: TimeTable,
    /// Penalty contact settings.
    #[serde(default)]
    pub contact: ContactTable,
    /// Output sampling and columns.
    pub output: OutputTable,
    /// Named local coordinate systems for nodal DOFs.
    #[serde(default)]
    pub frames: Vec<FrameTable>,
    /// Nodes.
    pub nodes: Vec<NodeTable>,
    /// Rigid bodies.
    #[serde(default)]
    pub bodies: Vec<BodyTable>,
    /// Point masses on nodes (on a body node they build the body's mass properties).
    #[serde(default)]
    pub masses: Vec<MassTable>,
    /// Springs.
    #[serde(default)]
    pub springs: Vec<ElementTable>,
    /// Dashpots.
    #[serde(default)]
    pub dashpots: Vec<ElementTable>,
    /// Node-to-face contact pairs.
    #[serde(default)]
    pub contacts: Vec<ContactPairTable>,
    /// Constant point loads.
    #[serde(default)]
    pub loads: Vec<LoadTable>,
    /// Initial velocities, applied at the start of the first dynamic step.
    #[serde(default)]
    pub initial_velocities: Vec<InitialVelocityTable>,
    /// Analysis steps, in order.
    pub steps: Vec<StepTable>,
    /// Tolerances each engine must meet against the closed form (read by the comparison).
    #[serde(default)]
    pub tolerances: toml::Table,
    /// Whether the main command sweeps this case (what accuracy costs) besides the seed cases.
    #[serde(default)]
    pub sweep: bool,
}

/// `[time]`: how the time increment is chosen.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeTable {
    /// A fixed increment (the role of the source problems' dummy element).
    pub increment: Option<f64>,
    /// Or: a target accumulated phase error of the highest structural mode.
    pub accuracy: Option<f64>,
    /// Fraction of the stable increment used when neither is given (default 0.9).
    pub safety: Option<f64>,
    /// Or: accuracy on request: the largest error (over each column's peak) the engines may make
    /// against their own model's exact solution; they choose the increment (and the penalty
    /// stiffness) themselves.
    pub tolerance: Option<f64>,
    /// `centred` (second order, default) or `lagged` (dashpots see the previous half-step velocity).
    pub damping: Option<String>,
}

/// `[contact]`: penalty settings.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactTable {
    /// Penalty stiffness k_p; overrides the rule.
    pub penalty_stiffness: Option<f64>,
    /// k_p = ratio × the largest spring stiffness in the scene (default 1000).
    pub penalty_ratio: Option<f64>,
    /// `consistent` (start at the penetration that carries the initial contact force) or `touching`.
    pub start: Option<String>,
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputTable {
    /// Rows in every CSV (uniform in time, first t = 0, last t = duration), at least 200.
    pub rows: usize,
    /// The columns after `t`, in order; the family's contract columns come first.
    pub columns: Vec<ColumnTable>,
}

/// One output column: exactly one of the probe keys.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnTable {
    /// Column name in the CSV header.
    pub name: String,
    /// Displacement of this node along `direction`.
    pub displacement: Option<String>,
    /// Velocity of this node along `direction`.
    pub velocity: Option<String>,
    /// Rotation of this body about `axis` (2D: about z).
    pub rotation: Option<String>,
    /// Normal force of this contact pair, compressive positive.
    pub contact_force: Option<String>,
    /// Gap of this contact pair: signed distance from its node to its surface (negative:
    /// penetration).
    pub gap: Option<String>,
    /// A column that is identically zero, with the reason (e.g. no middle mass).
    pub zero: Option<String>,
    /// Direction for displacement/velocity (global).
    pub direction: Option<Vec<f64>>,
    /// Axis for rotation (3D only; default z).
    pub axis: Option<Vec<f64>>,
}

/// `[[frames]]`: an orthonormal local system (x axis, and in 3D a y axis).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameTable {
    /// Name nodes refer to.
    pub id: String,
    /// Local x axis (normalised on reading).
    pub x_axis: Vec<f64>,
    /// Local y axis (3D only; made orthogonal to x).
    pub y_axis: Option<Vec<f64>>,
}

/// `[[nodes]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeTable {
    /// Node name.
    pub id: String,
    /// Position at t = 0.
    pub at: Vec<f64>,
    /// Body the node is a material point of.
    pub body: Option<String>,
    /// Local frame its DOFs are expressed in.
    pub frame: Option<String>,
    /// Held in every DOF in every step (a ground node).
    #[serde(default)]
    pub fixed: bool,
}

/// `[[bodies]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyTable {
    /// Body name.
    pub id: String,
    /// Reference node: the body's generalised coordinates live there.
    pub reference: String,
    /// Mass lumped at the reference node.
    pub mass: Option<f64>,
    /// Inertia lumped at the reference node: a number in 2D; `[Ixx, Iyy, Izz]` or a 3×3 matrix in 3D.
    pub inertia: Option<toml::Value>,
}

/// `[[masses]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MassTable {
    /// Node carrying the mass.
    pub node: String,
    /// Mass.
    pub mass: f64,
}

/// `[[springs]]` and `[[dashpots]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElementTable {
    /// Optional name.
    pub id: Option<String>,
    /// `grounded` (one DOF of one node), `fixed_direction` (two nodes, fixed global direction),
    /// `axial` (two nodes, along their current line).
    pub kind: String,
    /// One node (grounded) or two.
    pub nodes: Vec<String>,
    /// Grounded: the DOF (`ux`, `uy`, `uz`, `rx`, `ry`, `rz`, in the node's frame).
    pub dof: Option<String>,
    /// Fixed direction: the global direction.
    pub direction: Option<Vec<f64>>,
    /// Spring stiffness.
    pub stiffness: Option<f64>,
    /// Dashpot coefficient.
    pub damping: Option<f64>,
}

/// `[[contacts]]`: a node against a surface of a rigid body: a planar face (the source
/// problems) or the boundary of a solid (parry's ball, cuboid, capsule or convex polygon /
/// polyhedron).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactPairTable {
    /// Name.
    pub id: String,
    /// The slave node.
    pub node: String,
    /// A ball (a disc in 2D) of this radius centred on the node and rigid with the node's
    /// body, which touches the face instead of the node itself (a body's rolling shape; the
    /// node then belongs to a body and the surface is a plane). Default: the node touches.
    pub node_radius: Option<f64>,
    /// The body whose surface it touches.
    pub body: String,
    /// `plane` (default), `ball`, `cuboid`, `capsule` or `convex`.
    pub shape: Option<String>,
    /// Plane: a point of the face at t = 0 (global coordinates).
    pub face_point: Option<Vec<f64>>,
    /// Plane: outward normal of the face at t = 0.
    pub face_normal: Option<Vec<f64>>,
    /// Solid: its centre at t = 0 (global coordinates; its axes are the global axes at t = 0
    /// and turn with the body).
    pub centre: Option<Vec<f64>>,
    /// Ball and capsule: radius.
    pub radius: Option<f64>,
    /// Cuboid: half extents along x, y (and z).
    pub half_extents: Option<Vec<f64>>,
    /// Capsule: half the length of its segment, which lies along y.
    pub half_height: Option<f64>,
    /// Convex: its corners relative to `centre` (a polygon in 2D: 3 to 32; a polyhedron in
    /// 3D: 4 to 32; each a corner of their convex hull, none repeated, none nearly straight).
    pub vertices: Option<Vec<Vec<f64>>>,
    /// `closed` (default: the node starts on the surface) or `open` (it starts clear of it).
    pub initially: Option<String>,
    /// Coefficient of restitution of an impact, in [0, 1] (default 1: elastic). Penalty
    /// contact gets a contact dashpot sized for it; rapier its `restitution`.
    pub restitution: Option<f64>,
    /// Coulomb friction coefficient, static and kinetic alike (default 0: frictionless).
    pub friction: Option<f64>,
    /// Static friction coefficient μ_s, given with `kinetic_friction` where the two differ.
    pub static_friction: Option<f64>,
    /// Kinetic friction coefficient μ_k ≤ μ_s, given with `static_friction`.
    pub kinetic_friction: Option<f64>,
}

/// `[[loads]]`: constant force at a material point, fixed in direction.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadTable {
    /// Node (a free node or a body's material point).
    pub node: String,
    /// Force vector (global; at amplitude 1).
    pub force: Vec<f64>,
    /// A tabular amplitude `[[t, a], ...]` scaling the force (times from the start of the
    /// first dynamic step, strictly increasing; linear between points, the end values held
    /// outside them). Default: constant.
    pub amplitude: Option<Vec<Vec<f64>>>,
}

/// `[[initial_velocities]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialVelocityTable {
    /// Node (for a body: its reference node).
    pub node: String,
    /// Translational velocity.
    pub velocity: Option<Vec<f64>>,
    /// Angular velocity of a body: a number in 2D, a vector in 3D.
    pub angular: Option<toml::Value>,
}

/// `[[steps]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepTable {
    /// `static` or `dynamic`.
    pub kind: String,
    /// Duration of a dynamic step.
    pub duration: Option<f64>,
    /// DOFs held in this step (besides fixed nodes).
    #[serde(default)]
    pub hold: Vec<HoldTable>,
    /// Prescribed displacements (static steps).
    #[serde(default)]
    pub prescribe: Vec<PrescribeTable>,
}

/// A set of held DOFs of one node.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldTable {
    /// Node.
    pub node: String,
    /// DOF names, or `["all"]`.
    pub dofs: Vec<String>,
}

/// A prescribed displacement.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrescribeTable {
    /// Node.
    pub node: String,
    /// DOF name (in the node's frame).
    pub dof: String,
    /// Value.
    pub value: f64,
}
