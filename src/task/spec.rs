//! The task file format (TOML, version 1): what a task file may say, with
//! every default written once. `tasks/*.toml` are the built-in tasks, and
//! `docs/task-format.md` walks through the format.

use crate::sim::rules::Colour;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use toml::Spanned;

/// The task file format version this build reads.
pub const FORMAT_VERSION: u32 = 1;

/// A number, or an expression over `level`, `max_level`, `pi` and the
/// curriculum parameters (see [`super::expr`]), written as a string.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Value {
    /// A plain number.
    Num(f64),
    /// An expression such as `"min(0.08 + 0.025 * level, 0.20)"`.
    Expr(String),
}

impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Num(v)
    }
}

/// A whole task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// Format version: 1.
    pub version: u32,
    /// Versioned id, e.g. `"ReachAvoid-v0"`.
    pub id: String,
    /// One line on what the task asks.
    #[serde(default)]
    pub summary: String,
    /// Steps before `truncated`.
    #[serde(default = "default_max_episode_steps")]
    pub max_episode_steps: usize,
    /// Groups of objects whose roles (colour and start) are permuted every
    /// episode; the objects of a group must have the same shape.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shuffle: Vec<Vec<String>>,
    /// The robot: gripper colour, gripper action, start height.
    #[serde(default)]
    pub robot: RobotSpec,
    /// The table's colour.
    #[serde(default)]
    pub table: SurfaceSpec,
    /// The floor as a rule object (absent: the floor takes no part in the rules).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<SurfaceSpec>,
    /// Levels and their parameters.
    #[serde(default)]
    pub curriculum: CurriculumSpec,
    /// Constraints every sampled layout meets.
    #[serde(default)]
    pub placement: PlacementSpec,
    /// The objects, in scene and observation order.
    pub objects: Vec<Spanned<ObjectSpec>>,
    /// Named evaluation distributions (e.g. `challenge`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub distributions: BTreeMap<String, DistributionSpec>,
    /// Dynamics drawn per episode from its seed (absent: nominal physics, as every built-in task).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<super::physics::PhysicsSpec>,
}

fn default_max_episode_steps() -> usize {
    50
}

/// The Fetch robot's part in the task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Colour of the gripper (link and fingers).
    #[serde(default = "grey")]
    pub gripper: Colour,
    /// Whether the fourth action component opens and closes the fingers (as in
    /// FetchPickAndPlace); otherwise the fingers are held closed.
    #[serde(default)]
    pub gripper_action: bool,
    /// Height of the gripper above the Fetch default at reset, in metres.
    #[serde(default = "default_extra_height")]
    pub extra_height: f64,
}

fn grey() -> Colour {
    Colour::Grey
}
fn default_extra_height() -> f64 {
    0.2
}

impl Default for RobotSpec {
    fn default() -> Self {
        Self { gripper: Colour::Grey, gripper_action: false, extra_height: default_extra_height() }
    }
}

/// A colourable surface (the table, the floor).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSpec {
    /// Its colour.
    #[serde(default = "grey")]
    pub colour: Colour,
}

impl Default for SurfaceSpec {
    fn default() -> Self {
        Self { colour: Colour::Grey }
    }
}

/// The curriculum: levels 0..=max_level, parameters as functions of the level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurriculumSpec {
    /// Highest level (0: no curriculum).
    #[serde(default)]
    pub max_level: usize,
    /// Test success rate at which the trainer moves up a level.
    #[serde(default = "default_threshold")]
    pub success_threshold: f64,
    /// Named parameters, each a number or an expression of `level` (and of
    /// other parameters).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, Spanned<Value>>,
}

fn default_threshold() -> f64 {
    0.7
}

impl Default for CurriculumSpec {
    fn default() -> Self {
        Self { max_level: 0, success_threshold: default_threshold(), params: BTreeMap::new() }
    }
}

/// Constraints of every layout; a layout that breaks one is redrawn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacementSpec {
    /// Smallest distance between the centres of two objects resting on the table (m).
    #[serde(default = "default_separation")]
    pub min_separation: f64,
    /// Every object's footprint stays this far inside the table edge (m),
    /// beyond its own half extent.
    #[serde(default)]
    pub table_margin: f64,
    /// Draws of the geometric sampler before it gives up.
    #[serde(default = "default_attempts")]
    pub max_attempts: usize,
    /// Layouts the physics checks (overlap, settling, rules at reset) may
    /// reject before reset gives up.
    #[serde(default = "default_reset_attempts")]
    pub max_reset_attempts: usize,
    /// Seconds of physics run at reset with the gripper held still, so that
    /// stacks settle (0: none, the blocks start where they are placed).
    #[serde(default)]
    pub settle_seconds: f64,
    /// Largest distance an object may move while settling before the layout
    /// is rejected as unstable (m).
    #[serde(default = "default_settle_tolerance")]
    pub settle_tolerance: f64,
}

fn default_separation() -> f64 {
    0.075
}
fn default_attempts() -> usize {
    100_000
}
fn default_reset_attempts() -> usize {
    100
}
fn default_settle_tolerance() -> f64 {
    0.01
}

impl Default for PlacementSpec {
    fn default() -> Self {
        Self {
            min_separation: default_separation(),
            table_margin: 0.0,
            max_attempts: default_attempts(),
            max_reset_attempts: default_reset_attempts(),
            settle_seconds: 0.0,
            settle_tolerance: default_settle_tolerance(),
        }
    }
}

/// The shape of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A box with `half_extents`.
    Box,
}

/// One object of the scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Unique name (not `gripper`, `table` or `floor`).
    pub name: String,
    /// Its colour.
    pub colour: Colour,
    /// Its shape.
    #[serde(default = "default_kind")]
    pub kind: Kind,
    /// Half extents (x, y, z) in metres.
    #[serde(default = "default_half_extents", deserialize_with = "super::exact::array")]
    pub half_extents: [f64; 3],
    /// Mass in kg.
    #[serde(default = "default_mass")]
    pub mass: f64,
    /// MuJoCo friction (sliding, torsional, rolling); absent: MuJoCo's default.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub friction: Option<[f64; 3]>,
    /// Where it starts.
    #[serde(default)]
    pub start: StartSpec,
    /// How many copies: `[min, max]`, drawn uniformly per episode (absent:
    /// exactly one). The entry stands for `max` objects named `NAME.0` …
    /// `NAME.(max-1)`, of which the first `n` drawn take part in the episode;
    /// the others are absent (no physics with the scene, no rules, not drawn,
    /// zero rows in the observation).
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub count: Option<[usize; 2]>,
}

fn default_kind() -> Kind {
    Kind::Box
}
fn default_half_extents() -> [f64; 3] {
    [0.025; 3]
}
fn default_mass() -> f64 {
    2.0
}

/// Where an object starts. Objects are placed in file order, so an object
/// can be placed relative to those before it.
///
/// The (x, y) position is `anchor + R(frame) · (polar + rectangle + offset)`:
/// `anchor` is `around` (the gripper, the table centre, an object, or the
/// centroid of several), or `on`'s position; the frame turns the offsets so
/// that +x points from the anchor `towards` something (no turn without it);
/// `polar` is a distance drawn from `distance` (uniform by area, or uniform
/// in the distance) in a direction drawn from `angle`; `rectangle` is uniform
/// in [-a, a] × [-b, b]. `at` gives the (x, y) directly instead.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// Absolute (x, y) in the world, used as written: the table and
    /// separation constraints do not apply.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub at: Option<[Value; 2]>,
    /// The anchor: "gripper" (default), "table", an object, or a list of them (their centroid).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub around: Option<Anchor>,
    /// Rest on top of this object: its (x, y) is the anchor and the height is
    /// its top plus this object's half height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on: Option<String>,
    /// Turn the frame so that +x points from the anchor towards this ("gripper", "table" or an object).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub towards: Option<String>,
    /// Distance range [lo, hi] from the anchor.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub distance: Option<[Value; 2]>,
    /// How the distance is drawn.
    #[serde(default)]
    pub density: Density,
    /// Direction range [lo, hi] in radians, in the frame (default: all around).
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub angle: Option<[Value; 2]>,
    /// Half sides [a, b] of a uniform rectangle in the frame.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub rectangle: Option<[Value; 2]>,
    /// A fixed offset [dx, dy] in the frame.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "super::exact::option")]
    pub offset: Option<[Value; 2]>,
    /// Height of the centre above the table top (default: resting on the table, or on `on`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<Value>,
    /// Yaw in radians relative to the frame: a value, or a range [lo, hi] drawn uniformly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw: Option<Yaw>,
}

/// The anchor of a placement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Anchor {
    /// "gripper", "table" or an object's name.
    One(String),
    /// The centroid of these.
    Centroid(Vec<String>),
}

/// How a distance in [lo, hi] is drawn.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Density {
    /// Uniform by area in the annulus (a uniform point of the disc when lo = 0).
    Area,
    /// Uniform in the distance itself (denser near the anchor).
    #[default]
    Distance,
}

/// A yaw: fixed or drawn from a range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Yaw {
    /// Fixed.
    Fixed(Value),
    /// Uniform in [lo, hi].
    Range(#[serde(deserialize_with = "super::exact::array")] [Value; 2]),
}

/// A named distribution: the curriculum at one level with some parameters
/// and starts replaced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DistributionSpec {
    /// Level whose parameters apply (default: the maximum).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub level: Option<usize>,
    /// Parameters replaced.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, Spanned<Value>>,
    /// Starts replaced, by object name (an entry with a count: all its
    /// copies, or one copy by its name `NAME.K`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub starts: BTreeMap<String, StartSpec>,
    /// Count ranges replaced, by the name of an entry with a count (within
    /// that entry's `[0, max]`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty", deserialize_with = "super::exact::map")]
    pub counts: BTreeMap<String, [usize; 2]>,
}

impl TaskSpec {
    /// A task made in code: 5 cm cubes named `block0`, `block1`, … of these
    /// colours, fixed at these (x, y) on the table; grey gripper and table.
    ///
    /// # Errors
    /// A different number of colours and positions.
    pub fn fixed(id: &str, colours: &[Colour], positions: &[[f64; 2]]) -> Result<TaskSpec, super::TaskError> {
        let objects = colours
            .iter()
            .enumerate()
            .map(|(i, &colour)| {
                Spanned::new(
                    0..0,
                    ObjectSpec {
                        name: format!("block{i}"),
                        colour,
                        kind: Kind::Box,
                        half_extents: default_half_extents(),
                        mass: default_mass(),
                        friction: None,
                        start: StartSpec::default(),
                        count: None,
                    },
                )
            })
            .collect();
        let spec = TaskSpec {
            version: FORMAT_VERSION,
            id: id.to_owned(),
            summary: String::new(),
            max_episode_steps: default_max_episode_steps(),
            shuffle: Vec::new(),
            robot: RobotSpec::default(),
            table: SurfaceSpec::default(),
            floor: None,
            curriculum: CurriculumSpec::default(),
            placement: PlacementSpec::default(),
            objects,
            distributions: BTreeMap::new(),
            physics: None,
        };
        spec.with_fixed_layout(positions)
    }

    /// The same task with every object fixed at the given (x, y) (tests,
    /// demonstrations); the distributions and the shuffle are dropped.
    ///
    /// # Errors
    /// A number of positions other than the number of objects.
    pub fn with_fixed_layout(mut self, positions: &[[f64; 2]]) -> Result<TaskSpec, super::TaskError> {
        if let Some(o) = self.objects.iter().find(|o| o.get_ref().count.is_some()) {
            return Err(super::TaskError {
                origin: self.id.clone(),
                line: None,
                message: format!(
                    "object {:?} has a count: a fixed layout needs a fixed set of objects (drop the count)",
                    o.get_ref().name
                ),
            });
        }
        if positions.len() != self.objects.len() {
            return Err(super::TaskError {
                origin: self.id.clone(),
                line: None,
                message: format!("a fixed layout of {} positions for {} objects", positions.len(), self.objects.len()),
            });
        }
        for (o, p) in self.objects.iter_mut().zip(positions) {
            o.get_mut().start = StartSpec { at: Some([Value::Num(p[0]), Value::Num(p[1])]), ..StartSpec::default() };
        }
        self.distributions.clear();
        self.shuffle.clear();
        Ok(self)
    }
}
