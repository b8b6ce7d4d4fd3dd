//! Environment configuration and the errors of the environment API.

use crate::sim::mj::MjError;
use crate::sim::rules::Colour;
use crate::sim::scene::{BlockSpec, SceneError, SceneSpec};
use crate::task::sampler::PlacementError;
use crate::task::spec::TaskSpec;
use crate::task::{Task, TaskError};
use thiserror::Error;

/// Everything that defines an environment: the task (objects, colours,
/// layouts, curriculum, episode length) and the physics settings.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvConfig {
    /// The compiled task.
    pub task: Task,
    /// Physics substeps per action (20 as in Fetch; timestep 0.002 s).
    pub n_substeps: usize,
    /// Exclude robot collision pairs that never touch (faster, same physics).
    pub collision_filter: bool,
    /// After the substeps, recompute the state with a full `mj_forward`
    /// (gymnasium-robotics' step callback) instead of only the kinematics,
    /// velocities and contacts the observation and the rules read. Both give
    /// bit-identical trajectories (tested); the full pass is slower.
    pub full_forward: bool,
    /// How the observation is presented (flat by default; `objects`: robot,
    /// object rows and mask).
    pub obs_mode: super::ObsMode,
    /// Block slots in the observation: the task's blocks, and absent rows (zero, mask 0) up to
    /// this many where it is more (multi-task training presents every task in one layout).
    pub slots: usize,
}

impl EnvConfig {
    /// The default physics around a compiled task.
    pub fn new(task: Task) -> Self {
        Self {
            task,
            n_substeps: 20,
            collision_filter: true,
            full_forward: false,
            obs_mode: super::ObsMode::Flat,
            slots: 0,
        }
    }

    /// Compiles `spec` (a task made in code) with the default physics.
    ///
    /// # Errors
    /// [`EnvError::Task`] naming what is wrong with the spec.
    pub fn from_spec(spec: TaskSpec) -> Result<Self, EnvError> {
        Ok(Self::new(Task::from_spec(spec)?))
    }

    /// The task's id.
    pub fn id(&self) -> &str {
        self.task.id()
    }
    /// Colour of each block as written in the task, in observation order.
    pub fn blocks(&self) -> Vec<Colour> {
        self.task.colours()
    }
    /// What the observation holds: the mode and one slot per block (at least `slots`).
    pub fn obs_spec(&self) -> super::ObsSpec {
        super::ObsSpec::new(self.obs_mode, self.task.object_count().max(self.slots))
    }
    /// Colour of the gripper.
    pub fn gripper(&self) -> Colour {
        self.task.spec.robot.gripper
    }
    /// What the scene holds: the task's blocks, gripper, table and floor.
    pub fn scene_spec(&self) -> SceneSpec {
        let task = &self.task.spec;
        SceneSpec {
            blocks: self
                .task
                .objects()
                .map(|o| BlockSpec {
                    name: o.name.clone(),
                    colour: o.colour,
                    half_extents: o.half_extents,
                    mass: o.mass,
                    friction: o.friction,
                })
                .collect(),
            gripper: task.robot.gripper,
            table: task.table.colour,
            floor: task.floor.as_ref().map(|f| f.colour),
            finger_actuators: task.robot.gripper_action,
            collision_filter: self.collision_filter,
        }
    }
}

/// Errors of the environment API. Each names the problem and the fix.
#[derive(Debug, Error)]
pub enum EnvError {
    /// `make` with an id the registry does not know.
    #[error("unknown environment id {id:?}; known ids: {}; or give the path of a task file (.toml)", known.join(", "))]
    UnknownId { id: String, known: Vec<String> },
    /// A task file or spec that does not make a task.
    #[error(transparent)]
    Task(#[from] TaskError),
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
    #[error("{id} has no challenge mode (its task file defines no [distributions.challenge])")]
    NoChallenge { id: String },
    /// A distribution the task does not define.
    #[error("{id} has no distribution {name:?} (it has: {})", if known.is_empty() { "none".to_owned() } else { known.join(", ") })]
    NoDistribution { id: String, name: String, known: Vec<String> },
    /// Reset found no layout that passes the physics checks.
    #[error("{id}: no valid reset state after {attempts} layouts ({level}): {reason}; widen the sampling ranges or raise placement.max_reset_attempts")]
    ResetExhausted { id: String, attempts: usize, level: String, reason: String },
    /// The reset state already breaks a rule.
    #[error(
        "invalid scene: at reset the red object {red:?} already touches the blue object {blue:?}; move them apart"
    )]
    InitialViolation { red: String, blue: String },
    /// A state given to `set_state` that the model cannot take.
    #[error("invalid state: {reason}")]
    BadState { reason: String },
    /// An invalid setting.
    #[error("invalid environment setting: {0}")]
    Config(String),
    /// Physics options the task's `[physics]` table does not take (none, an unknown parameter, one
    /// it does not vary, a value outside its range).
    #[error("{0}")]
    Physics(String),
}
