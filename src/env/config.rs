//! Environment configuration and the errors of the environment API.

use crate::curriculum::{Layout, PlacementError};
use crate::mj::MjError;
use crate::rules::Colour;
use crate::scene::SceneError;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Everything that defines an environment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnvConfig {
    /// Registry id (or a free-form name for custom tasks).
    pub id: String,
    /// Colour of each block, in scene and observation order.
    pub blocks: Vec<Colour>,
    /// Colour of the gripper.
    pub gripper: Colour,
    /// Colour of the table.
    pub table: Colour,
    /// Where the blocks start.
    pub layout: Layout,
    /// Steps per episode before `truncated` (50 as in Fetch).
    pub max_episode_steps: usize,
    /// Physics substeps per action (20 as in Fetch; timestep 0.002 s).
    pub n_substeps: usize,
    /// Height of the gripper above the Fetch default at reset (0.2 as in the
    /// original BlockPuzzle code; FetchPush uses 0).
    pub gripper_extra_height: f64,
    /// Exclude robot collision pairs that never touch (faster, same physics).
    pub collision_filter: bool,
    /// After the substeps, recompute the state with a full `mj_forward`
    /// (gymnasium-robotics' step callback) instead of only the kinematics,
    /// velocities and contacts the observation and the rules read. Both give
    /// bit-identical trajectories (tested); the full pass is slower.
    #[serde(default)]
    pub full_forward: bool,
}

impl EnvConfig {
    /// A custom task with default physics: grey gripper and table unless changed.
    pub fn custom(id: &str, blocks: Vec<Colour>, layout: Layout) -> Self {
        Self {
            id: id.to_owned(),
            blocks,
            gripper: Colour::Grey,
            table: Colour::Grey,
            layout,
            max_episode_steps: 50,
            n_substeps: 20,
            gripper_extra_height: 0.2,
            collision_filter: true,
            full_forward: false,
        }
    }
}

/// Errors of the environment API. Each names the problem and the fix.
#[derive(Debug, Error)]
pub enum EnvError {
    /// `make` with an id the registry does not know.
    #[error("unknown environment id {id:?}; known ids: {}", known.join(", "))]
    UnknownId { id: String, known: Vec<String> },
    /// The scene could not be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// MuJoCo failed at run time.
    #[error(transparent)]
    Mujoco(#[from] MjError),
    /// No valid block layout.
    #[error(transparent)]
    Placement(#[from] PlacementError),
    /// An action of the wrong length or with a non-finite value.
    #[error("invalid action: {reason}")]
    BadAction { reason: String },
    /// `step` before the first `reset`.
    #[error("step called before reset: call reset() first")]
    NotReset,
    /// `step` after the episode ended.
    #[error("the episode is over (terminated or truncated): call reset() before stepping again")]
    EpisodeOver,
    /// A curriculum level beyond the maximum.
    #[error("level {level} is beyond the maximum level {max} of {id}")]
    LevelOutOfRange { id: String, level: usize, max: usize },
    /// Challenge mode on an environment without one.
    #[error("{id} has no challenge mode (only BlocksChoose-v0 has one)")]
    NoChallenge { id: String },
    /// The reset state already breaks a rule.
    #[error(
        "invalid scene: at reset the red object {red:?} already touches the blue object {blue:?}; move them apart"
    )]
    InitialViolation { red: String, blue: String },
    /// An invalid setting.
    #[error("invalid environment setting: {0}")]
    Config(String),
}
