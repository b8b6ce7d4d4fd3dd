//! The vector engine: N environments stepped on K threads, one engine
//! under every caller. Two ways to drive it:
//!
//! * step by step ([`VectorEnv::reset`], [`VectorEnv::step`]): a batch of
//!   actions in, a batch of observations out, Gymnasium's next-step
//!   autoreset (the step after an episode ends resets that environment,
//!   ignores its action and reports reward 0 with `autoreset` set); Python's
//!   `VecEnv` is this;
//! * episode by episode ([`VectorEnv::each`]): every environment runs a
//!   closure at once (e.g. whole episodes with its own policy copy);
//!   evaluation, training's collection and `bench` are this.
//!
//! Environment i depends only on its own seeds and actions, so its
//! trajectory is the same whatever N and K are (tests/it/vector.rs).

use super::{BlockEnv, EnvConfig, EnvError, Info, ObsSpec, ACTION_DIM};
use rayon::prelude::*;

/// A pool of `threads` threads (at least one) on which MuJoCo models can be compiled: each gets the
/// main thread's 8 MB of stack, since the XML compiler needs more than rayon's default 2 MB. Building
/// environments ([`BlockEnv::new`](super::BlockEnv::new)) or generating tasks in parallel runs on one.
///
/// # Errors
/// A pool that cannot be started, in words.
pub(crate) fn model_threads(threads: usize) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .stack_size(8 << 20)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))
}

/// N environments and the K threads that step them.
pub struct VectorEnv {
    envs: Vec<BlockEnv>,
    /// Environments whose episode ended: the next step resets them.
    ended: Vec<bool>,
    reports: Vec<VecStep>,
    pool: rayon::ThreadPool,
    spec: ObsSpec,
}

/// What one environment reported from the last [`VectorEnv::reset`] or [`VectorEnv::step`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VecStep {
    /// The step's reward (0 on a reset).
    pub reward: f32,
    /// The colour rules ended the episode.
    pub terminated: bool,
    /// The step limit or an instability ended the episode.
    pub truncated: bool,
    /// This call reset the environment instead of stepping it.
    pub autoreset: bool,
    /// The step's or reset's info; None for an environment the call left alone.
    pub info: Option<Info>,
}

/// Settings applied to every environment a [`VectorEnv::reset`] resets, before it resets.
#[derive(Debug, Clone, Default)]
pub struct ResetOptions {
    /// Curriculum level.
    pub level: Option<usize>,
    /// Challenge distribution on or off.
    pub challenge: Option<bool>,
    /// A named distribution of the task.
    pub distribution: Option<String>,
    /// Parameters of the task's `[physics]` table pinned to values (name, value) for the episodes
    /// that follow ([`BlockEnv::pin_physics`]; an empty list draws them all again).
    pub physics: Option<Vec<(String, f64)>>,
}

/// An environment's error, with its index.
#[derive(Debug, thiserror::Error)]
#[error("environment {index}: {source}")]
pub struct VecError {
    /// Which environment.
    pub index: usize,
    /// What went wrong.
    #[source]
    pub source: EnvError,
}

impl VectorEnv {
    /// `num_envs` environments of `config` on `threads` threads (at most one per environment).
    ///
    /// # Errors
    /// A count out of [`crate::support::limits::NUM_ENVS`] or [`crate::support::limits::THREADS`],
    /// or the environment's own errors.
    pub fn new(config: &EnvConfig, num_envs: usize, threads: usize) -> Result<Self, EnvError> {
        crate::support::limits::NUM_ENVS.check_usize(num_envs).map_err(EnvError::Config)?;
        let envs = (0..num_envs).map(|_| BlockEnv::new(config.clone())).collect::<Result<_, _>>()?;
        Self::from_envs(envs, threads)
    }

    /// The engine over environments built elsewhere (e.g. one per training
    /// worker, each possibly at its own level).
    ///
    /// # Errors
    /// No environments, environments of different observation layouts, or a
    /// thread count out of [`crate::support::limits::THREADS`] or that cannot start.
    pub fn from_envs(envs: Vec<BlockEnv>, threads: usize) -> Result<Self, EnvError> {
        crate::support::limits::THREADS.check_usize(threads).map_err(EnvError::Config)?;
        let spec = envs.first().ok_or_else(|| EnvError::Config("a vector of no environments".into()))?.obs_spec();
        if let Some(i) = envs.iter().position(|e| e.obs_spec() != spec) {
            return Err(EnvError::Config(format!("environment {i}'s observation differs from environment 0's")));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.min(envs.len()))
            .build()
            .map_err(|e| EnvError::Config(format!("cannot start {threads} threads: {e}")))?;
        let n = envs.len();
        Ok(Self { envs, ended: vec![false; n], reports: vec![VecStep::default(); n], pool, spec })
    }

    /// Number of environments.
    pub fn num_envs(&self) -> usize {
        self.envs.len()
    }

    /// Threads stepping them.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// What each environment's observation holds; a batch is `num_envs × spec.dim()`.
    pub fn obs_spec(&self) -> ObsSpec {
        self.spec
    }

    /// The environments (e.g. for their contact matrices).
    pub fn envs(&self) -> &[BlockEnv] {
        &self.envs
    }

    /// The environments, to change their settings between calls.
    pub fn envs_mut(&mut self) -> &mut [BlockEnv] {
        &mut self.envs
    }

    /// The reports of the last [`VectorEnv::reset`] or [`VectorEnv::step`].
    pub fn reports(&self) -> &[VecStep] {
        &self.reports
    }

    /// Runs `f(i, env)` for every environment on the threads; the results in environment order.
    pub fn each<T: Send>(&mut self, f: impl Fn(usize, &mut BlockEnv) -> T + Sync) -> Vec<T> {
        let envs = &mut self.envs;
        self.pool.install(|| envs.par_iter_mut().enumerate().map(|(i, env)| f(i, env)).collect())
    }

    /// [`VectorEnv::each`] with a state per environment (e.g. its policy
    /// copy), `states[i]` given to environment i's call.
    ///
    /// # Panics
    /// If `states` does not have one entry per environment.
    pub fn each_with<S: Send, T: Send>(
        &mut self,
        states: &mut [S],
        f: impl Fn(usize, &mut BlockEnv, &mut S) -> T + Sync,
    ) -> Vec<T> {
        assert_eq!(states.len(), self.envs.len(), "one state per environment");
        let envs = &mut self.envs;
        self.pool.install(|| {
            envs.par_iter_mut().zip(states.par_iter_mut()).enumerate().map(|(i, (env, s))| f(i, env, s)).collect()
        })
    }

    /// Resets the environments whose `mask` entry is true (all when None)
    /// with their `seeds` entry (None: the environment's own generator goes
    /// on), after applying `options`; writes their first observations into
    /// their rows of `obs` (`num_envs × obs_spec().dim()`) and returns the
    /// reports (the others' are empty).
    ///
    /// # Errors
    /// Seeds, mask or buffer of the wrong size ([`EnvError::Config`] as
    /// environment 0's), or the first environment that failed.
    pub fn reset(
        &mut self,
        seeds: &[Option<u64>],
        mask: Option<&[bool]>,
        options: &ResetOptions,
        obs: &mut [f32],
    ) -> Result<&[VecStep], VecError> {
        let n = self.envs.len();
        if seeds.len() != n || mask.is_some_and(|m| m.len() != n) {
            return Err(setup(format!("seeds and mask must have num_envs = {n} entries")));
        }
        self.check_obs(obs)?;
        self.par_rows(obs, |i, env, report, ended, row| {
            if mask.is_some_and(|m| !m[i]) {
                *report = VecStep::default();
                return Ok(());
            }
            if let Some(l) = options.level {
                env.set_level(l)?;
            }
            if let Some(c) = options.challenge {
                env.set_challenge(c)?;
            }
            if let Some(name) = &options.distribution {
                env.set_distribution(Some(name))?;
            }
            if let Some(fixed) = &options.physics {
                env.pin_physics(fixed)?;
            }
            reset_one(env, seeds[i], row, ended, report)
        })?;
        Ok(&self.reports)
    }

    /// Steps every environment with its row of `actions` (`num_envs × 4`),
    /// resetting instead those whose episode ended at the previous step;
    /// writes the observations into `obs` and returns the reports.
    ///
    /// # Errors
    /// Actions or buffer of the wrong size, or a non-finite action (checked
    /// before any environment moves, so all stay as they were), or the first
    /// environment that failed.
    pub fn step(&mut self, actions: &[f32], obs: &mut [f32]) -> Result<&[VecStep], VecError> {
        let n = self.envs.len();
        if actions.len() != n * ACTION_DIM {
            return Err(setup(format!("actions must be {n} × {ACTION_DIM} values, not {}", actions.len())));
        }
        if let Some(k) = actions.iter().position(|a| !a.is_finite()) {
            let reason = format!("component {} is {}", k % ACTION_DIM, actions[k]);
            return Err(VecError { index: k / ACTION_DIM, source: EnvError::BadAction { reason } });
        }
        self.check_obs(obs)?;
        self.par_rows(obs, |i, env, report, ended, row| {
            if *ended {
                return reset_one(env, None, row, ended, report);
            }
            let s = env.step(&actions[i * ACTION_DIM..(i + 1) * ACTION_DIM])?;
            row.copy_from_slice(&s.obs);
            *ended = s.terminated || s.truncated;
            *report = VecStep {
                reward: s.reward,
                terminated: s.terminated,
                truncated: s.truncated,
                autoreset: false,
                info: Some(s.info),
            };
            Ok(())
        })?;
        Ok(&self.reports)
    }

    fn check_obs(&self, obs: &[f32]) -> Result<(), VecError> {
        let (n, d) = (self.envs.len(), self.spec.dim());
        if obs.len() != n * d {
            return Err(setup(format!("the observation buffer must be {n} × {d} values, not {}", obs.len())));
        }
        Ok(())
    }

    /// Runs `f` on every environment with its report, ended flag and observation row.
    fn par_rows(
        &mut self,
        obs: &mut [f32],
        f: impl Fn(usize, &mut BlockEnv, &mut VecStep, &mut bool, &mut [f32]) -> Result<(), EnvError> + Sync,
    ) -> Result<(), VecError> {
        let (envs, reports, ended, pool) = (&mut self.envs, &mut self.reports, &mut self.ended, &self.pool);
        let d = self.spec.dim();
        let results: Vec<Result<(), EnvError>> = pool.install(|| {
            envs.par_iter_mut()
                .zip(reports.par_iter_mut())
                .zip(ended.par_iter_mut())
                .zip(obs.par_chunks_mut(d))
                .enumerate()
                .map(|(i, (((env, report), ended), row))| f(i, env, report, ended, row))
                .collect()
        });
        results.into_iter().enumerate().try_for_each(|(index, r)| r.map_err(|source| VecError { index, source }))
    }
}

/// A set-up error of the whole call (reported as environment 0's).
fn setup(message: String) -> VecError {
    VecError { index: 0, source: EnvError::Config(message) }
}

/// Resets `env` (with `seed`, or its own generator going on), writing its
/// first observation into `row` and its report.
fn reset_one(
    env: &mut BlockEnv,
    seed: Option<u64>,
    row: &mut [f32],
    ended: &mut bool,
    report: &mut VecStep,
) -> Result<(), EnvError> {
    let (obs, info) = env.reset(seed)?;
    row.copy_from_slice(&obs);
    *ended = false;
    *report = VecStep { autoreset: true, info: Some(info), ..VecStep::default() };
    Ok(())
}
