//! Layer 4, env: the environments, with Gymnasium's semantics.
//!
//! | module | what |
//! |---|---|
//! | `config` | [`EnvConfig`] and the environment API's errors ([`EnvError`]) |
//! | `obs` | the observation modes ([`ObsSpec`]) and how each is read off the simulation |
//! | `reset` | the reset pipeline: roles dealt, a layout drawn, the settled robot restored |
//! | `physics` | a task's `[physics]` table at work: the episode's dynamics drawn and applied, action noise and latency, observation noise |
//! | [`registry`] | the versioned environment ids, each a task file in `tasks/` |
//! | [`vector`] | the vector engine: N environments stepped on K threads |
//! | [`hindsight`] | hindsight colour relabelling of an episode's contacts |
//!
//! The environments, with Gymnasium semantics: `reset(seed)` returns the first
//! observation and an [`Info`]; `step(action)` returns a [`Step`] with the
//! reward and separate `terminated` / `truncated` flags.
//!
//! Physics follow gymnasium-robotics' Fetch: 20 substeps of 0.002 s per
//! action, mocap control of the gripper (position action × 0.05 added to the
//! gripper position, orientation held at the quaternion (1, 0, 1, 0)), fingers
//! held closed, 50 steps per episode. The rules are checked after every
//! substep, so a brief red–blue touch is never missed.

mod config;
pub mod hindsight;
mod obs;
mod physics;
pub mod registry;
mod reset;
pub mod vector;

pub use config::{EnvConfig, EnvError};
pub use obs::{
    obs_dim, Fixture, ObsMode, ObsSpec, BLOCK_OBS, COLOUR_FEATURE, ENTITY_FEATURES, OBJECT_FEATURES, ROBOT_FEATURES,
    ROBOT_OBS, TYPE_FEATURE,
};

use crate::sim::mj::{Data, ObjType, Warning};
use crate::sim::rules::{Colour, ContactMatrix, Rules, Touching, Verdict};
use crate::sim::scene::{Scene, SceneObject};
use crate::task::sampler::Placed;
use crate::task::Tally;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Dimension of the action space: Box[-1, 1]^4 (dx, dy, dz, gripper; the
/// gripper component is ignored unless the task enables the gripper action).
pub const ACTION_DIM: usize = 4;
/// Scale from an action component to a gripper displacement in metres.
pub const ACTION_SCALE: f64 = 0.05;
/// Quaternion added to the gripper's orientation each step (gymnasium-robotics'
/// `rot_ctrl`): the mocap target is the current orientation plus (1, 0, 1, 0),
/// which MuJoCo normalises, holding the gripper pointing down.
pub const GRIPPER_ROT: [f64; 4] = [1.0, 0.0, 1.0, 0.0];
/// Initial base joints (slide0, slide1, slide2) of the Fetch environments.
pub const INITIAL_SLIDES: [f64; 3] = [0.405, 0.48, 0.0];
/// Offset from the grip site to the mocap target at set-up (z gets the extra height).
pub const GRIPPER_SETUP_OFFSET: [f64; 3] = [-0.498, 0.005, -0.431];
/// Actions used to settle the robot at set-up.
pub const SETTLE_ACTIONS: usize = 10;
/// Where absent objects wait (x, y on the floor, far from the robot and the
/// table): slot k rests at `PARK_ORIGIN + (PARK_PITCH · k, 0)`, apart from
/// the others, touching only the floor, which the rules do not hear from it.
pub const PARK_ORIGIN: [f64; 2] = [-3.0, -3.0];
/// Spacing of parked objects along x (m).
pub const PARK_PITCH: f64 = 0.3;
/// Deepest interpenetration of two objects a reset state may have (m):
/// deeper, the layout is rejected as overlapping.
pub const OVERLAP_TOLERANCE: f64 = 0.002;

/// Auxiliary information of a step or reset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Info {
    /// Every blue object touched a green one during this step.
    pub is_success: bool,
    /// A red object touched a blue one during this step.
    pub is_failure: bool,
    /// Curriculum level of the episode.
    pub level: usize,
    /// Whether the episode uses the challenge distribution.
    pub challenge: bool,
    /// The evaluation distribution of the episode (`None`: the curriculum).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distribution: Option<String>,
    /// Object pairs `(a, b)`, `a < b`, that touched at any substep of this
    /// step (at reset: in the reset state). Indices into [`BlockEnv::objects`].
    pub touching: Vec<(usize, usize)>,
    /// MuJoCo reported numerical instability; the episode was truncated.
    pub unstable: bool,
    /// Steps taken in this episode.
    pub elapsed_steps: usize,
    /// The episode's dynamics, drawn at reset (a task with a `[physics]` table; absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<crate::task::physics::PhysicsDraw>,
}

/// What resets have cost so far: how often the sampler and the physics
/// checks redrew a layout (see `blockpuzzle task check`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ResetStats {
    /// Resets that produced an episode.
    pub resets: u64,
    /// Layouts the sampler drew, those it rejected included.
    pub draws: u64,
    /// Layouts that passed the sampler and went to the physics checks.
    pub layouts: u64,
    /// Layouts the physics checks rejected, by reason.
    pub rejected: Tally,
}

/// The result of one step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Observation after the step (finite: never NaN).
    pub obs: Vec<f32>,
    /// −1 per step, 0 on success, −(steps left, this one included) on failure.
    pub reward: f32,
    /// The episode ended under the rules (success or failure).
    pub terminated: bool,
    /// The episode was cut: time limit, or numerical instability.
    pub truncated: bool,
    /// Details.
    pub info: Info,
}

/// A continuous box space.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxSpace {
    /// Lower bounds.
    pub low: Vec<f32>,
    /// Upper bounds.
    pub high: Vec<f32>,
}

impl BoxSpace {
    /// Number of dimensions.
    pub fn dim(&self) -> usize {
        self.low.len()
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    NeedsReset,
    Running,
    Over,
}

/// A BlockPuzzle environment.
pub struct BlockEnv {
    config: EnvConfig,
    scene: Scene,
    data: Data,
    initial: Data,
    initial_grip: [f64; 3],
    rules: Rules,
    rng: ChaCha8Rng,
    level: usize,
    distribution: Option<usize>,
    /// Rule objects of the current episode (colours move when the task shuffles roles).
    objects: Vec<SceneObject>,
    /// Block colours of the current episode, in observation order.
    colours: Vec<Colour>,
    /// Finger actuators' qpos addresses, when the gripper action is enabled.
    finger_ctrl: Vec<usize>,
    stats: ResetStats,
    steps: usize,
    phase: Phase,
    touching: Touching,
    step_touching: Touching,
    obs: Vec<f32>,
    /// Each block's half extents (the `objects` observation holds them).
    sizes: Vec<[f64; 3]>,
    /// Which blocks take part in this episode (all, unless the task has counts).
    present: Vec<bool>,
    /// The task has counts: some episodes leave blocks out.
    varies: bool,
    /// The contacts of every substep of the last step, when recording (hindsight relabelling).
    substeps: Option<Vec<Touching>>,
    physics: std::time::Duration,
    /// The per-episode dynamics of a task with a `[physics]` table.
    dynamics: Option<physics::Dynamics>,
}

impl BlockEnv {
    /// Builds an environment and settles the robot as Fetch does.
    ///
    /// # Errors
    /// [`EnvError`] for an invalid configuration, missing assets, or a model
    /// MuJoCo refuses.
    pub fn new(config: EnvConfig) -> Result<Self, EnvError> {
        if config.n_substeps == 0 {
            return Err(EnvError::Config("n_substeps must be positive".into()));
        }
        let task = &config.task.spec;
        let scene = Scene::build(&config.scene_spec())?;
        let rules = Rules::new(scene.colours()).map_err(crate::sim::scene::SceneError::from)?;
        let mut data = Data::new(scene.model.clone())?;

        // Fetch set-up: base joints, weld at identity (done in Scene::build),
        // gripper target above the table, settle.
        for (k, &v) in INITIAL_SLIDES.iter().enumerate() {
            data.qpos_mut()[scene.slide_qpos[k]] = v;
        }
        data.forward()?;
        let grip = data.site_xpos()[scene.grip_site];
        let mut target = [0.0; 3];
        for k in 0..3 {
            target[k] = grip[k] + GRIPPER_SETUP_OFFSET[k];
        }
        target[2] += task.robot.extra_height;
        data.mocap_pos_mut()[scene.mocap] = target;
        data.mocap_quat_mut()[scene.mocap] = GRIPPER_ROT;
        for _ in 0..SETTLE_ACTIONS * config.n_substeps {
            data.step()?;
        }
        data.forward()?;
        let initial_grip = data.site_xpos()[scene.grip_site];
        let initial = data.try_clone()?;
        // A task whose dynamics vary steps a copy of the model that its state alone holds, set
        // from the scene's nominal one at every reset.
        let dynamics = match &task.physics {
            Some(p) => {
                let mut own = Data::new(std::sync::Arc::new(scene.model.try_clone()?))?;
                own.copy_from(&initial)?;
                data = own;
                let blocks: Vec<usize> = scene.blocks.iter().map(|b| b.body).collect();
                Some(physics::Dynamics::new(p.clone(), &scene.model, &blocks))
            }
            None => None,
        };
        let model = scene.model.clone();
        let finger_ctrl: Vec<usize> =
            model.actuator_joint().iter().map(|&j| model.jnt_qposadr()[j as usize] as usize).collect();

        let n = scene.objects.len();
        let obs = vec![0.0; config.obs_spec().dim()];
        let config_sizes = config.task.objects().map(|o| o.half_extents).collect();
        let (present, varies) = (vec![true; config.task.object_count()], !config.task.count_groups().is_empty());
        Ok(Self {
            objects: scene.objects.clone(),
            colours: config.task.colours(),
            config,
            scene,
            data,
            initial,
            initial_grip,
            rules,
            rng: ChaCha8Rng::from_entropy(),
            level: 0,
            distribution: None,
            finger_ctrl,
            stats: ResetStats::default(),
            steps: 0,
            phase: Phase::NeedsReset,
            touching: Touching::new(n),
            step_touching: Touching::new(n),
            obs,
            sizes: config_sizes,
            present,
            varies,
            substeps: None,
            physics: std::time::Duration::ZERO,
            dynamics,
        })
    }

    /// Registry id (or custom name).
    pub fn id(&self) -> &str {
        self.config.id()
    }
    /// The configuration.
    pub fn config(&self) -> &EnvConfig {
        &self.config
    }
    /// Box[-1, 1]^4.
    pub fn action_space(&self) -> BoxSpace {
        BoxSpace { low: vec![-1.0; ACTION_DIM], high: vec![1.0; ACTION_DIM] }
    }
    /// What the observation holds ([`ObsSpec`]).
    pub fn obs_spec(&self) -> ObsSpec {
        self.config.obs_spec()
    }
    /// Presents the observation as `mode` from now on (the current one is
    /// rewritten): how a trained policy's environment takes the policy's layout.
    pub fn set_obs_mode(&mut self, mode: ObsMode) {
        if self.config.obs_mode != mode {
            self.config.obs_mode = mode;
            self.write_obs();
        }
    }
    /// Writes the current observation into `self.obs`.
    fn write_obs(&mut self) {
        self.draw_obs_noise();
        let mut obs = std::mem::take(&mut self.obs);
        self.observe(self.config.obs_mode, &mut obs);
        self.obs = obs;
    }
    /// The current state's observation as `mode` presents it, whatever mode the environment
    /// presents (a policy that reads another layout than the one recorded: the solver).
    pub fn observation_as(&self, mode: ObsMode) -> Vec<f32> {
        let mut out = Vec::new();
        self.observe(mode, &mut out);
        out
    }
    /// Writes the current state's observation in `mode` into `out`.
    fn observe(&self, mode: ObsMode, out: &mut Vec<f32>) {
        let (spec, dt) = (ObsSpec { mode, ..self.config.obs_spec() }, self.dt());
        let colour = |o: usize| self.objects[o].colour;
        let fixtures = obs::FixtureColours {
            gripper: colour(crate::sim::scene::GRIPPER_OBJECT),
            table: colour(crate::sim::scene::TABLE_OBJECT),
            floor: self.scene.floor_object.map(colour),
        };
        let ctx = obs::ObsContext {
            spec: &spec,
            colours: &self.colours,
            sizes: &self.sizes,
            present: &self.present,
            fixtures,
            noise: self.dynamics.as_ref().map_or(&[], |d| &d.obs_offsets),
        };
        obs::write(&ctx, &self.scene, &self.data, dt, out);
    }
    /// The observation as one box of [`ObsSpec::dim`] values: unbounded,
    /// the mask (where the mode has one) in [0, 1].
    pub fn observation_space(&self) -> BoxSpace {
        let spec = self.obs_spec();
        let (n, features) = (spec.dim(), spec.robot_dim() + spec.object_dim() * spec.rows());
        let low = (0..n).map(|i| if i < features { f32::NEG_INFINITY } else { 0.0 }).collect();
        let high = (0..n).map(|i| if i < features { f32::INFINITY } else { 1.0 }).collect();
        BoxSpace { low, high }
    }
    /// Rule objects of the current episode: gripper, table, blocks (then the
    /// floor, when the task makes it one).
    pub fn objects(&self) -> &[SceneObject] {
        &self.objects
    }
    /// Which blocks take part in the current episode, in observation order
    /// (all of them unless the task has counts; an absent block is parked
    /// off the scene, out of the rules, and zero in the observation).
    pub fn present(&self) -> &[bool] {
        &self.present
    }
    /// Whether each rule object (as [`BlockEnv::objects`]) is absent this episode.
    pub fn absent_objects(&self) -> Vec<bool> {
        (0..self.objects.len()).map(|o| self.is_absent(o)).collect()
    }
    /// Whether rule object `o` is a block left out of this episode.
    fn is_absent(&self, o: usize) -> bool {
        o.checked_sub(crate::sim::scene::FIRST_BLOCK_OBJECT).and_then(|k| self.present.get(k)).is_some_and(|&p| !p)
    }
    /// Block colours of the current episode, in observation order (they
    /// differ from the task's between episodes only when it shuffles roles).
    pub fn block_colours(&self) -> &[Colour] {
        &self.colours
    }
    /// The compiled scene (model and ids).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Current simulation state.
    pub fn data(&self) -> &Data {
        &self.data
    }
    /// Mutable simulation state, for experts (tests inject instabilities with it).
    /// Changes take effect at the next step.
    pub fn data_mut(&mut self) -> &mut Data {
        &mut self.data
    }
    /// The authors' contact-state matrix of the current episode.
    pub fn contact_matrix(&self) -> &ContactMatrix {
        self.rules.matrix()
    }
    /// The rules' verdict so far.
    pub fn verdict(&self) -> Option<Verdict> {
        self.rules.verdict()
    }
    /// Grip site position after set-up (the centre of the curriculum discs).
    pub fn initial_gripper_position(&self) -> [f64; 3] {
        self.initial_grip
    }
    /// Current grip site position.
    pub fn gripper_position(&self) -> [f64; 3] {
        self.data.site_xpos()[self.scene.grip_site]
    }
    /// Current block centres, in block order.
    pub fn block_positions(&self) -> Vec<[f64; 3]> {
        self.scene.blocks.iter().map(|b| self.data.site_xpos()[b.site]).collect()
    }
    /// Current block orientations (w, x, y, z).
    pub fn block_quats(&self) -> Vec<[f64; 4]> {
        self.scene.blocks.iter().map(|b| self.data.xquat()[b.body]).collect()
    }
    /// Wall time spent inside `mj_step` since construction (for benchmarks:
    /// everything else in `step` is environment overhead).
    pub fn physics_seconds(&self) -> f64 {
        self.physics.as_secs_f64()
    }
    /// What the resets since construction cost (sampler and physics rejections).
    pub fn reset_stats(&self) -> &ResetStats {
        &self.stats
    }
    /// Steps taken in the current episode.
    pub fn elapsed_steps(&self) -> usize {
        self.steps
    }

    /// Highest curriculum level.
    pub fn max_level(&self) -> usize {
        self.config.task.max_level()
    }
    /// Current curriculum level.
    pub fn level(&self) -> usize {
        self.level
    }
    /// Sets the curriculum level used from the next reset on.
    ///
    /// # Errors
    /// [`EnvError::LevelOutOfRange`] beyond [`BlockEnv::max_level`].
    pub fn set_level(&mut self, level: usize) -> Result<(), EnvError> {
        if level > self.max_level() {
            return Err(EnvError::LevelOutOfRange { id: self.id().to_owned(), level, max: self.max_level() });
        }
        self.level = level;
        Ok(())
    }
    /// Whether episodes use the challenge distribution.
    pub fn challenge(&self) -> bool {
        self.distribution_name() == Some("challenge")
    }
    /// Switches the challenge distribution on or off from the next reset on.
    ///
    /// # Errors
    /// [`EnvError::NoChallenge`] for environments without a challenge mode.
    pub fn set_challenge(&mut self, on: bool) -> Result<(), EnvError> {
        if on && self.config.task.distribution("challenge").is_none() {
            return Err(EnvError::NoChallenge { id: self.id().to_owned() });
        }
        self.set_distribution(on.then_some("challenge"))
    }
    /// The evaluation distribution in use (`None`: the curriculum).
    pub fn distribution_name(&self) -> Option<&str> {
        self.distribution.map(|d| self.config.task.distributions[d].name.as_str())
    }
    /// Uses the named evaluation distribution (or, with `None`, the
    /// curriculum) from the next reset on.
    ///
    /// # Errors
    /// [`EnvError::NoDistribution`] naming the task's distributions.
    pub fn set_distribution(&mut self, name: Option<&str>) -> Result<(), EnvError> {
        self.distribution = match name {
            None => None,
            Some(n) => Some(self.config.task.distribution(n).ok_or_else(|| EnvError::NoDistribution {
                id: self.id().to_owned(),
                name: n.to_owned(),
                known: self.config.task.distribution_names().iter().map(|s| s.to_string()).collect(),
            })?),
        };
        Ok(())
    }

    /// Starts an episode from the state `qpos`, `qvel` (MuJoCo's full vectors,
    /// `nq` and `nv` long) instead of a sampled layout, as Gymnasium's
    /// `MujocoEnv.set_state` does: everything else is as after construction
    /// (mocap target, controls), the constraint solver starts cold
    /// (`qacc_warmstart` zero, as after `mj_resetData`, which
    /// gymnasium-robotics' Fetch reset calls), the rules start from the
    /// contacts of that state (no layout checks: any state is accepted), and
    /// the colours stay those of the last episode. Returns the observation.
    ///
    /// # Errors
    /// [`EnvError::BadState`] for a wrong length or a non-finite value.
    pub fn set_state(&mut self, qpos: &[f64], qvel: &[f64]) -> Result<Vec<f32>, EnvError> {
        let model = self.data.model();
        for (what, v, n) in [("qpos", qpos, model.nq()), ("qvel", qvel, model.nv())] {
            if v.len() != n {
                return Err(EnvError::BadState { reason: format!("{what} has {} values, the model {n}", v.len()) });
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(EnvError::BadState { reason: format!("{what}[{i}] is {}", v[i]) });
            }
        }
        self.phase = Phase::NeedsReset;
        self.data.copy_from(&self.initial)?;
        self.data.qpos_mut().copy_from_slice(qpos);
        self.data.qvel_mut().copy_from_slice(qvel);
        self.data.qacc_warmstart_mut().fill(0.0);
        self.data.forward()?;
        self.rules.reset();
        self.scan_contacts();
        self.steps = 0;
        self.phase = Phase::Running;
        self.write_obs();
        Ok(self.obs.clone())
    }

    /// Applies one action for `n_substeps` physics substeps.
    ///
    /// Components are clipped to [-1, 1]; the fourth opens (> 0) or closes
    /// (< 0) the fingers when the task enables the gripper action, and is
    /// ignored otherwise (fingers held closed).
    ///
    /// # Errors
    /// [`EnvError::BadAction`] for a wrong length or a non-finite value,
    /// [`EnvError::NotReset`] / [`EnvError::EpisodeOver`] when no episode runs.
    pub fn step(&mut self, action: &[f32]) -> Result<Step, EnvError> {
        if action.len() != ACTION_DIM {
            return Err(EnvError::BadAction {
                reason: format!("expected {ACTION_DIM} components, got {}", action.len()),
            });
        }
        if let Some(i) = action.iter().position(|a| !a.is_finite()) {
            return Err(EnvError::BadAction { reason: format!("component {i} is {}", action[i]) });
        }
        match self.phase {
            Phase::NeedsReset => return Err(EnvError::NotReset),
            Phase::Over => return Err(EnvError::EpisodeOver),
            Phase::Running => {}
        }

        let bad_before = self.bad_number_warnings();
        let applied = self.acting(action);
        self.apply_action(&applied);
        self.step_touching.clear();
        if let Some(record) = &mut self.substeps {
            record.clear();
        }
        for _ in 0..self.config.n_substeps {
            let t = std::time::Instant::now();
            let stepped = self.data.step();
            self.physics += t.elapsed();
            if let Err(e) = stepped {
                // MuJoCo's state is unspecified now: only a reset continues.
                self.phase = Phase::NeedsReset;
                return Err(e.into());
            }
            self.observe_substep();
        }
        // Blocked gripper: fingers back to closed, then recompute the state.
        if self.finger_ctrl.is_empty() {
            for &a in &self.scene.finger_qpos {
                self.data.qpos_mut()[a] = 0.0;
            }
        }
        let updated = if self.config.full_forward {
            self.data.forward()
        } else {
            // Everything the next mj_step needs it recomputes itself from
            // qpos/qvel, so only what the observation and rules read is due.
            self.data.kinematics(true)
        };
        if let Err(e) = updated {
            self.phase = Phase::NeedsReset;
            return Err(e.into());
        }
        self.observe_substep();
        self.steps += 1;

        let unstable = self.bad_number_warnings() > bad_before
            || !self.data.qpos().iter().chain(self.data.qvel()).all(|v| v.is_finite());
        let verdict = if unstable { None } else { self.rules.verdict() };
        let (is_success, is_failure) = (verdict == Some(Verdict::Success), verdict == Some(Verdict::Failure));
        let terminated = verdict.is_some();
        let max_steps = self.config.task.spec.max_episode_steps;
        let truncated = !terminated && (unstable || self.steps >= max_steps);
        let reward = match verdict {
            Some(Verdict::Success) => 0.0,
            Some(Verdict::Failure) => -((max_steps + 1).saturating_sub(self.steps) as f32),
            None => -1.0,
        };
        if !unstable {
            self.write_obs();
        } // else: keep the last finite observation; NaN never reaches the agent
        if terminated || truncated {
            self.phase = Phase::Over;
        }
        let info = Info { unstable, ..self.info(is_success, is_failure, self.step_touching.pairs()) };
        Ok(Step { obs: self.obs.clone(), reward, terminated, truncated, info })
    }

    /// MuJoCo's counters of bad numbers (it resets the state when it raises them).
    fn bad_number_warnings(&self) -> i64 {
        [Warning::BadQpos, Warning::BadQvel, Warning::BadQacc]
            .into_iter()
            .map(|w| i64::from(self.data.warning_count(w)))
            .sum()
    }

    fn dt(&self) -> f64 {
        self.config.n_substeps as f64 * self.scene.model.timestep()
    }

    fn info(&self, is_success: bool, is_failure: bool, touching: Vec<(usize, usize)>) -> Info {
        Info {
            is_success,
            is_failure,
            level: self.level,
            challenge: self.challenge(),
            distribution: self.distribution_name().map(str::to_owned),
            touching,
            unstable: false,
            elapsed_steps: self.steps,
            physics: self.physics(),
        }
    }

    /// gymnasium-robotics' `mocap_set_action`: the mocap jumps to the welded
    /// gripper's pose, then moves by the action.
    fn apply_action(&mut self, action: &[f32]) {
        let body = self.scene.gripper_body;
        let (pos, quat) = (self.data.xpos()[body], self.data.xquat()[body]);
        let (m, scale) = (self.scene.mocap, self.action_scale());
        let mp = &mut self.data.mocap_pos_mut()[m];
        for k in 0..3 {
            mp[k] = pos[k] + f64::from(action[k].clamp(-1.0, 1.0)) * scale;
        }
        let mq = &mut self.data.mocap_quat_mut()[m];
        for k in 0..4 {
            mq[k] = quat[k] + GRIPPER_ROT[k];
        }
        // gymnasium-robotics' ctrl_set_action for position actuators: target = finger position + action.
        let grip = f64::from(action[3].clamp(-1.0, 1.0));
        for (i, &a) in self.finger_ctrl.iter().enumerate() {
            let target = self.data.qpos()[a] + grip;
            self.data.ctrl_mut()[i] = target;
        }
    }

    fn scan_contacts(&mut self) {
        self.touching.clear();
        for c in self.data.contacts() {
            let (a, b) = (self.scene.geom_object[c.geom1()], self.scene.geom_object[c.geom2()]);
            if a >= 0 && b >= 0 {
                // Absent blocks take no part in the rules (they touch only the floor).
                if self.varies && (self.is_absent(a as usize) || self.is_absent(b as usize)) {
                    continue;
                }
                self.touching.insert(a as usize, b as usize);
            }
        }
    }

    fn observe_substep(&mut self) {
        self.scan_contacts();
        self.step_touching.union_with(&self.touching);
        self.rules.observe(&self.touching);
        if let Some(record) = &mut self.substeps {
            record.push(self.touching.clone());
        }
    }

    /// Records, from the next step on, the contacts the rules saw at every
    /// substep of a step (`on = false` stops): what
    /// [`crate::env::hindsight::replay`] needs to judge the step under other colours.
    pub fn record_substeps(&mut self, on: bool) {
        self.substeps = on.then(Vec::new);
    }

    /// Whether [`BlockEnv::record_substeps`] is on.
    pub fn records_substeps(&self) -> bool {
        self.substeps.is_some()
    }

    /// The contacts the rules saw at each substep of the last step, in order
    /// (the physics substeps, then the state after them); empty unless
    /// [`BlockEnv::record_substeps`] is on.
    pub fn substep_contacts(&self) -> &[Touching] {
        self.substeps.as_deref().unwrap_or(&[])
    }

    /// Id of a model object by name (convenience for tools and tests).
    ///
    /// # Errors
    /// [`EnvError::Mujoco`] if the model has no such object.
    pub fn model_id(&self, kind: ObjType, name: &str) -> Result<usize, EnvError> {
        Ok(self.scene.model.id(kind, name)?)
    }
}
