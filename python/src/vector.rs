//! `VecEnv`: N environments stepped by K Rust threads with the GIL released,
//! writing into numpy arrays the caller allocated once. Autoreset is
//! Gymnasium's next-step mode: the step after an episode ends resets that
//! environment (its action is ignored; reward 0, not terminated, not
//! truncated). Environment i depends only on its own seeds and actions, so
//! its trajectory is the same whatever N and K are.

use crate::to_py;
use blockpuzzle::env::{registry, BlockEnv, EnvConfig, EnvError, Info};
use blockpuzzle::rules::ContactState;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyReadwriteArray1, PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use std::sync::{Mutex, PoisonError};

/// What one environment reports from a step or reset.
#[derive(Default, Clone)]
struct Report {
    reward: f32,
    terminated: bool,
    truncated: bool,
    /// Whether this step was the autoreset of an ended episode.
    reset: bool,
    info: Option<Info>,
    contacts: Vec<i8>,
}

/// N environments of one task, stepped in Rust threads. It may be made on
/// one Python thread and used or closed on another: the environments sit
/// behind a mutex (uncontended: every call that steps them holds the object
/// exclusively and reaches them without locking).
#[pyclass(module = "blockpuzzle._native")]
pub struct VecEnv {
    envs: Mutex<Vec<BlockEnv>>,
    /// Environments whose episode ended: the next step resets them.
    ended: Vec<bool>,
    reports: Vec<Report>,
    pool: rayon::ThreadPool,
    obs_dim: usize,
    objects: usize,
    closed: bool,
}

/// The environments of a vector env that the caller holds exclusively, without
/// locking. The mutex cannot be poisoned in practice (the only lock, in
/// `num_envs`, is held to read a length), and would still hold them intact.
fn unlocked(envs: &mut Mutex<Vec<BlockEnv>>) -> &mut Vec<BlockEnv> {
    envs.get_mut().unwrap_or_else(PoisonError::into_inner)
}

fn contacts(env: &BlockEnv) -> Vec<i8> {
    let n = env.objects().len();
    let m = env.contact_matrix();
    (0..n * n)
        .map(|k| match m.get(k / n, k % n) {
            ContactState::NeverTouched => 0,
            ContactState::TouchedBefore => 1,
            ContactState::TouchingNow => 2,
        })
        .collect()
}

/// What a vector call does to environment `i`: its environment, report,
/// ended flag and observation row.
type PerEnv<'a> = dyn Fn(usize, &mut BlockEnv, &mut Report, &mut bool, &mut [f32]) -> Result<(), EnvError> + Sync + 'a;

impl VecEnv {
    /// Runs `f` on every environment in the thread pool with the GIL
    /// released; `out` is the `num_envs × obs_dim` observation buffer.
    fn par_each(&mut self, py: Python<'_>, out: &mut [f32], f: &PerEnv<'_>) -> PyResult<()> {
        let envs = unlocked(&mut self.envs);
        let (reports, ended, pool) = (&mut self.reports, &mut self.ended, &self.pool);
        let obs_dim = self.obs_dim;
        py.allow_threads(|| {
            pool.install(|| {
                envs.par_iter_mut()
                    .zip(reports.par_iter_mut())
                    .zip(ended.par_iter_mut())
                    .zip(out.par_chunks_mut(obs_dim))
                    .enumerate()
                    .try_for_each(|(i, (((env, report), ended), row))| f(i, env, report, ended, row))
            })
        })
        .map_err(to_py)
    }

    fn check_open(&self) -> PyResult<()> {
        if self.closed {
            return Err(PyRuntimeError::new_err("the vector environment is closed"));
        }
        Ok(())
    }

    /// The infos of the last call as a dict of arrays, one entry per environment.
    fn infos<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let infos: Vec<Option<&Info>> = self.reports.iter().map(|r| r.info.as_ref()).collect();
        let get = |f: fn(&Info) -> bool| infos.iter().map(|i| i.is_some_and(f)).collect::<Vec<bool>>();
        d.set_item("is_success", PyArray1::from_vec(py, get(|i| i.is_success)))?;
        d.set_item("is_failure", PyArray1::from_vec(py, get(|i| i.is_failure)))?;
        d.set_item("challenge", PyArray1::from_vec(py, get(|i| i.challenge)))?;
        d.set_item("unstable", PyArray1::from_vec(py, get(|i| i.unstable)))?;
        let count = |f: fn(&Info) -> usize| infos.iter().map(|i| i.map_or(0, f) as i64).collect::<Vec<i64>>();
        d.set_item("level", PyArray1::from_vec(py, count(|i| i.level)))?;
        d.set_item("elapsed_steps", PyArray1::from_vec(py, count(|i| i.elapsed_steps)))?;
        let n = self.objects;
        let cells: Vec<i8> = self.reports.iter().flat_map(|r| r.contacts.iter().copied()).collect();
        let num_envs = self.reports.len();
        if cells.len() == num_envs * n * n {
            d.set_item("contact_matrix", PyArray1::from_vec(py, cells).reshape([num_envs, n, n])?)?;
        }
        let present: Vec<bool> = infos.iter().map(Option::is_some).collect();
        for key in ["is_success", "is_failure", "challenge", "unstable", "level", "elapsed_steps", "contact_matrix"] {
            d.set_item(format!("_{key}"), PyArray1::from_vec(py, present.clone()))?;
        }
        d.set_item("autoreset", PyArray1::from_vec(py, self.reports.iter().map(|r| r.reset).collect::<Vec<_>>()))?;
        Ok(d)
    }
}

/// Resets `env` (with `seed`, or its own generator going on), writing its
/// first observation into `row` and its report.
fn reset_one(
    env: &mut BlockEnv,
    seed: Option<u64>,
    row: &mut [f32],
    ended: &mut bool,
    report: &mut Report,
) -> Result<(), EnvError> {
    let (obs, info) = env.reset(seed)?;
    row.copy_from_slice(&obs);
    *ended = false;
    *report = Report { reset: true, contacts: contacts(env), info: Some(info), ..Report::default() };
    Ok(())
}

#[pymethods]
impl VecEnv {
    /// `VecEnv(task, num_envs, threads)`: `task` an id or task file path.
    #[new]
    #[pyo3(signature = (task, num_envs, threads = 1))]
    fn new(task: &str, num_envs: usize, threads: usize) -> PyResult<Self> {
        let threads_bound = blockpuzzle::limits::Bound { name: "threads", ..blockpuzzle::limits::THREADS };
        let bounds = [(blockpuzzle::limits::NUM_ENVS, num_envs), (threads_bound, threads)];
        for (bound, v) in bounds {
            bound.check_usize(v).map_err(PyValueError::new_err)?;
        }
        let task = registry::task(task).map_err(to_py)?;
        let envs: Vec<BlockEnv> = (0..num_envs)
            .map(|_| BlockEnv::new(EnvConfig::new(task.clone())))
            .collect::<Result<_, _>>()
            .map_err(to_py)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.min(num_envs))
            .build()
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start {threads} threads: {e}")))?;
        let obs_dim = envs[0].observation_space().dim();
        let objects = envs[0].objects().len();
        Ok(Self {
            ended: vec![false; num_envs],
            reports: vec![Report::default(); num_envs],
            envs: Mutex::new(envs),
            pool,
            obs_dim,
            objects,
            closed: false,
        })
    }

    /// Observation size of one environment.
    #[getter]
    fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.envs.lock().unwrap_or_else(PoisonError::into_inner).len()
    }

    /// Resets the environments whose `mask` entry is true (all when `mask`
    /// is None) with their `seeds` entry (None: the environment's own
    /// generator goes on), after applying `level`, `challenge` and
    /// `distribution` to them; writes their observations into `obs`
    /// (`num_envs × obs_dim` float32). Returns the infos.
    #[pyo3(signature = (obs, seeds, mask = None, level = None, challenge = None, distribution = None))]
    #[allow(clippy::too_many_arguments)]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        mut obs: PyReadwriteArray2<'py, f32>,
        seeds: Vec<Option<u64>>,
        mask: Option<Vec<bool>>,
        level: Option<usize>,
        challenge: Option<bool>,
        distribution: Option<String>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.check_open()?;
        let n = unlocked(&mut self.envs).len();
        if seeds.len() != n || mask.as_ref().is_some_and(|m| m.len() != n) {
            return Err(PyValueError::new_err(format!("seeds and mask must have num_envs = {n} entries")));
        }
        let mask = mask.unwrap_or_else(|| vec![true; n]);
        let obs_dim = self.obs_dim;
        let out = obs.as_slice_mut().map_err(|e| PyValueError::new_err(format!("obs buffer: {e}")))?;
        if out.len() != n * obs_dim {
            return Err(PyValueError::new_err(format!("obs buffer must be {n} × {obs_dim} float32")));
        }
        self.par_each(py, out, &|i, env, report, ended, row| {
            if !mask[i] {
                *report = Report::default();
                return Ok(());
            }
            if let Some(l) = level {
                env.set_level(l)?;
            }
            if let Some(c) = challenge {
                env.set_challenge(c)?;
            }
            if let Some(name) = &distribution {
                env.set_distribution(Some(name))?;
            }
            reset_one(env, seeds[i], row, ended, report)
        })?;
        self.infos(py)
    }

    /// Steps every environment with its row of `actions` (`num_envs × 4`
    /// float32), resetting instead those whose episode ended at the previous
    /// step; writes observations, rewards, terminated and truncated flags
    /// into the given arrays. Returns the infos.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f32>,
        mut obs: PyReadwriteArray2<'py, f32>,
        mut rewards: PyReadwriteArray1<'py, f32>,
        mut terminated: PyReadwriteArray1<'py, bool>,
        mut truncated: PyReadwriteArray1<'py, bool>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.check_open()?;
        let (n, obs_dim) = (unlocked(&mut self.envs).len(), self.obs_dim);
        let shape = actions.shape().to_vec();
        let act_dim = blockpuzzle::env::ACTION_DIM;
        if shape != [n, act_dim] {
            return Err(PyValueError::new_err(format!(
                "invalid action: actions must have shape ({n}, {act_dim}), not {shape:?}"
            )));
        }
        let actions = actions.as_slice().map_err(|e| PyValueError::new_err(format!("invalid action: {e}")))?;
        // Checked before any environment moves, so that a bad row leaves all of them as they were.
        if let Some(k) = actions.iter().position(|a| !a.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "invalid action: environment {} has a non-finite component ({})",
                k / act_dim,
                actions[k]
            )));
        }
        let bad = |what: &str| PyValueError::new_err(format!("{what} buffer does not fit {n} environments"));
        let out = obs.as_slice_mut().map_err(|_| bad("obs"))?;
        let rew = rewards.as_slice_mut().map_err(|_| bad("reward"))?;
        let term = terminated.as_slice_mut().map_err(|_| bad("terminated"))?;
        let trunc = truncated.as_slice_mut().map_err(|_| bad("truncated"))?;
        if out.len() != n * obs_dim || rew.len() != n || term.len() != n || trunc.len() != n {
            return Err(bad("an output"));
        }
        self.par_each(py, out, &|i, env, report, ended, row| {
            if *ended {
                return reset_one(env, None, row, ended, report);
            }
            let s = env.step(&actions[i * act_dim..(i + 1) * act_dim])?;
            row.copy_from_slice(&s.obs);
            *ended = s.terminated || s.truncated;
            *report = Report {
                reward: s.reward,
                terminated: s.terminated,
                truncated: s.truncated,
                reset: false,
                contacts: contacts(env),
                info: Some(s.info),
            };
            Ok(())
        })?;
        for (i, r) in self.reports.iter().enumerate() {
            rew[i] = r.reward;
            term[i] = r.terminated;
            trunc[i] = r.truncated;
        }
        self.infos(py)
    }

    /// Frees every environment; later calls raise RuntimeError.
    fn close(&mut self) {
        unlocked(&mut self.envs).clear();
        self.closed = true;
    }
}
