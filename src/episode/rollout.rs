//! Rolling out a policy and recording headless trajectory dumps (JSON Lines:
//! one episode per line).

use crate::env::{BlockEnv, EnvError, Step, ACTION_DIM};
use crate::policy::Policy;
use crate::sim::rules::Colour;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors of a rollout.
#[derive(Debug, Error)]
pub enum RolloutError {
    /// The environment refused something.
    #[error(transparent)]
    Env(#[from] EnvError),
    /// The output file could not be written (the OS error is the source).
    #[error("cannot write trajectory dump {path}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The dump could not be read (the OS error is the source).
    #[error("cannot read trajectory dump {path}")]
    Read { path: PathBuf, source: std::io::Error },
    /// JSON encoding failed.
    #[error("cannot encode trajectory")]
    Json(#[from] serde_json::Error),
    /// A line of a dump is not an episode record (garbage, or cut short).
    #[error("{path} line {line} is not an episode record of a trajectory dump (written by `blockpuzzle rollout`; was the file cut short?)")]
    Decode { path: PathBuf, line: usize, source: serde_json::Error },
}

/// An object of the episode and its colour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectRecord {
    /// "gripper", "table", "block0", ...
    pub name: String,
    /// Its colour.
    pub colour: Colour,
    /// Left out of this episode (a copy beyond the count drawn).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub absent: bool,
}

/// Pose of a block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockPose {
    /// Centre (x, y, z).
    pub pos: [f64; 3],
    /// Orientation (w, x, y, z).
    pub quat: [f64; 4],
}

/// State after a reset or a step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateRecord {
    /// Full generalised positions: enough to replay and render the state.
    pub qpos: Vec<f64>,
    /// Grip site position.
    pub gripper: [f64; 3],
    /// Every block's pose.
    pub blocks: Vec<BlockPose>,
}

/// One step of an episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    /// The action taken.
    pub action: [f32; 4],
    /// State after the action.
    #[serde(flatten)]
    pub state: StateRecord,
    /// Object pairs that touched during the step (indices into `objects`).
    pub touching: Vec<(usize, usize)>,
    /// Reward of the step.
    pub reward: f32,
    /// Terminated under the rules.
    pub terminated: bool,
    /// Truncated (time limit or instability).
    pub truncated: bool,
    /// Success during this step.
    pub is_success: bool,
    /// Failure during this step.
    pub is_failure: bool,
    /// Numerical instability.
    pub unstable: bool,
}

/// One recorded episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeRecord {
    /// Environment id.
    pub env_id: String,
    /// The task by content, so that the dump replays after its task file
    /// moved or changed (absent in dumps written before tasks were files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<crate::task::TaskSource>,
    /// The evaluation distribution, if not the curriculum.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distribution: Option<String>,
    /// Seed passed to `reset`.
    pub seed: u64,
    /// Curriculum level.
    pub level: usize,
    /// Challenge distribution.
    pub challenge: bool,
    /// Rule objects and colours.
    pub objects: Vec<ObjectRecord>,
    /// State after reset.
    pub initial: StateRecord,
    /// The steps.
    pub steps: Vec<StepRecord>,
    /// The episode succeeded.
    pub success: bool,
    /// The episode failed.
    pub failure: bool,
    /// Sum of rewards.
    pub episode_return: f32,
    /// The episode's dynamics (a task with a `[physics]` table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<crate::task::physics::PhysicsDraw>,
}

fn state(env: &BlockEnv) -> StateRecord {
    StateRecord {
        qpos: env.data().qpos().to_vec(),
        gripper: env.gripper_position(),
        blocks: env
            .block_positions()
            .into_iter()
            .zip(env.block_quats())
            .map(|(pos, quat)| BlockPose { pos, quat })
            .collect(),
    }
}

/// What [`play_episode`] shows its caller.
pub enum Event<'a> {
    /// After the reset: the environment and its first observation.
    Reset { env: &'a BlockEnv, obs: &'a [f32] },
    /// After a step: the environment, the observation the action was chosen on, the action, the step.
    Step { env: &'a BlockEnv, obs: &'a [f32], action: &'a [f32; ACTION_DIM], step: &'a Step },
}

/// The episode loop, the one every caller uses (rollouts and dumps,
/// evaluation, training's exploration and tests): resets `env` with `seed`,
/// resets `policy`, then steps with its actions until the episode ends,
/// showing each [`Event`] to `on_event`.
///
/// # Errors
/// Whatever the environment reports (placement, invalid scene, instability).
pub fn play_episode(
    env: &mut BlockEnv,
    policy: &mut dyn Policy,
    seed: u64,
    mut on_event: impl FnMut(Event<'_>),
) -> Result<(), EnvError> {
    let (mut obs, _) = env.reset(Some(seed))?;
    on_event(Event::Reset { env, obs: &obs });
    policy.reset();
    // A policy that reads another layout than the environment presents sees that view of each state.
    let view = policy.reads().filter(|&m| m != env.obs_spec().mode);
    loop {
        let action = match view {
            Some(mode) => policy.act(&env.observation_as(mode)),
            None => policy.act(&obs),
        };
        let step = env.step(&action)?;
        on_event(Event::Step { env, obs: &obs, action: &action, step: &step });
        if step.terminated || step.truncated {
            return Ok(());
        }
        obs = step.obs;
    }
}

/// Runs one episode of `policy` from `reset(Some(seed))` and records it.
///
/// # Errors
/// Whatever the environment reports (placement, invalid scene).
pub fn run_episode(env: &mut BlockEnv, policy: &mut dyn Policy, seed: u64) -> Result<EpisodeRecord, RolloutError> {
    record_episode(env, policy, seed, None)
}

/// [`run_episode`], keeping as well every observation the environment presented: the reset's, then
/// each step's (one more than the steps).
///
/// # Errors
/// Whatever the environment reports (placement, invalid scene).
pub fn run_episode_observed(
    env: &mut BlockEnv,
    policy: &mut dyn Policy,
    seed: u64,
) -> Result<(EpisodeRecord, Vec<Vec<f32>>), RolloutError> {
    let mut observations = Vec::new();
    let rec = record_episode(env, policy, seed, Some(&mut observations))?;
    Ok((rec, observations))
}

fn record_episode(
    env: &mut BlockEnv,
    policy: &mut dyn Policy,
    seed: u64,
    mut observations: Option<&mut Vec<Vec<f32>>>,
) -> Result<EpisodeRecord, RolloutError> {
    let mut rec = None;
    play_episode(env, policy, seed, |event| match event {
        Event::Reset { env, obs } => {
            if let Some(o) = observations.as_deref_mut() {
                o.push(obs.to_vec());
            }
            rec = Some(EpisodeRecord {
                env_id: env.id().to_owned(),
                task: Some(env.config().task.source.clone()),
                distribution: env.distribution_name().map(str::to_owned),
                seed,
                level: env.level(),
                challenge: env.challenge(),
                objects: env
                    .objects()
                    .iter()
                    .zip(env.absent_objects())
                    .map(|(o, absent)| ObjectRecord { name: o.name.clone(), colour: o.colour, absent })
                    .collect(),
                initial: state(env),
                steps: Vec::new(),
                success: false,
                failure: false,
                episode_return: 0.0,
                physics: env.physics(),
            })
        }
        Event::Step { env, action, step: s, .. } => {
            if let Some(o) = observations.as_deref_mut() {
                o.push(s.obs.clone());
            }
            let Some(rec) = rec.as_mut() else { return };
            rec.episode_return += s.reward;
            rec.success |= s.info.is_success;
            rec.failure |= s.info.is_failure;
            rec.steps.push(StepRecord {
                action: *action,
                state: state(env),
                touching: s.info.touching.clone(),
                reward: s.reward,
                terminated: s.terminated,
                truncated: s.truncated,
                is_success: s.info.is_success,
                is_failure: s.info.is_failure,
                unstable: s.info.unstable,
            });
        }
    })?;
    rec.ok_or(RolloutError::Env(EnvError::NotReset))
}

/// The digest that pins an environment's dynamics (tests/golden.json): the
/// sha256 of three seeded episodes of `id` at `level` (the challenge
/// distribution if `challenge`) from seed `seed` on, played by the scripted
/// controller or by random actions seeded with `seed`. It covers every reset
/// state, action, qpos, reward, flag and contact, and the colours drawn by a
/// shuffling task, so any change to the simulation or the task shows.
///
/// # Errors
/// [`RolloutError::Env`] for an unknown id, level or distribution.
pub fn episode_digest(
    id: &str,
    scripted: bool,
    level: usize,
    challenge: bool,
    seed: u64,
) -> Result<String, RolloutError> {
    use crate::policy::{RandomPolicy, ScriptedPolicy};
    use sha2::{Digest, Sha256};
    let mut env = crate::env::registry::make(id)?;
    env.set_level(level)?;
    env.set_challenge(challenge)?;
    let mut policy: Box<dyn Policy> = if scripted {
        Box::new(ScriptedPolicy::solver(env.obs_spec().max_objects))
    } else {
        Box::new(RandomPolicy::new(seed))
    };
    let mut h = Sha256::new();
    let f64s = |h: &mut Sha256, v: &[f64]| v.iter().for_each(|x| h.update(x.to_bits().to_le_bytes()));
    for k in 0..3 {
        let ep = run_episode(&mut env, policy.as_mut(), seed + k)?;
        f64s(&mut h, &ep.initial.qpos);
        for s in &ep.steps {
            s.action.iter().for_each(|a| h.update(a.to_bits().to_le_bytes()));
            f64s(&mut h, &s.state.qpos);
            h.update(s.reward.to_bits().to_le_bytes());
            h.update([s.terminated as u8, s.truncated as u8, s.is_success as u8, s.is_failure as u8, s.unstable as u8]);
            for &(a, b) in &s.touching {
                h.update([a as u8, b as u8]);
            }
        }
        if !env.config().task.spec.shuffle.is_empty() {
            h.update(env.block_colours().iter().map(|c| *c as u8).collect::<Vec<u8>>());
        }
    }
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// A JSON Lines file written as [`crate::support::io::Output`] writes: episodes go to
/// a temporary file next to `path`, renamed onto `path` by
/// [`DumpWriter::finish`] (a device or pipe is written in place). If the
/// writer is dropped unfinished (an error), the temporary file is removed
/// and nothing is left at `path`.
pub struct DumpWriter {
    path: PathBuf,
    out: crate::support::io::Output,
}

impl DumpWriter {
    /// Opens the output (so an unwritable destination fails before any work).
    ///
    /// # Errors
    /// [`RolloutError::Io`] if the folder does not exist, is not writable or
    /// `path` is not ours to write (a folder, a read-only file, ...).
    pub fn create(path: &Path) -> Result<Self, RolloutError> {
        let out = crate::support::io::Output::create(path)
            .map_err(|source| RolloutError::Io { path: path.to_owned(), source })?;
        Ok(Self { path: path.to_owned(), out })
    }

    /// Appends one episode as a line.
    ///
    /// # Errors
    /// [`RolloutError::Io`] / [`RolloutError::Json`].
    pub fn write(&mut self, ep: &EpisodeRecord) -> Result<(), RolloutError> {
        // Encoded first, so that a failed write is reported as one (naming the file).
        let mut line = serde_json::to_vec(ep)?;
        line.push(b'\n');
        self.out.write_all(&line).map_err(|source| RolloutError::Io { path: self.path.clone(), source })
    }

    /// Flushes and moves the file into place.
    ///
    /// # Errors
    /// [`RolloutError::Io`].
    pub fn finish(self) -> Result<(), RolloutError> {
        let path = self.path;
        self.out.finish().map_err(|source| RolloutError::Io { path, source })
    }
}

/// Reads a trajectory dump.
///
/// # Errors
/// [`RolloutError::Read`], or [`RolloutError::Decode`] naming the file and the bad line.
pub fn read_dump(path: &Path) -> Result<Vec<EpisodeRecord>, RolloutError> {
    let text = crate::support::io::read_text(path, "trajectory dump", crate::support::limits::DUMP_FILE_BYTES)
        .map_err(|source| RolloutError::Read { path: path.to_owned(), source })?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|source| RolloutError::Decode {
                path: path.to_owned(),
                line: i + 1,
                source,
            })
        })
        .collect()
}
