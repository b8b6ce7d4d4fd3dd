//! `VecEnv`: the core's vector engine ([`blockpuzzle::env::vector::VectorEnv`]: N
//! environments on K Rust threads, next-step autoreset, environment i the
//! same whatever N and K are) for Python, with the GIL released while it
//! steps, writing into numpy arrays the caller allocated once.

use crate::to_py;
use blockpuzzle::env::{EnvConfig, Info, ObsMode};
use blockpuzzle::env::vector::{ResetOptions, VecError, VectorEnv};
use blockpuzzle::sim::rules::ContactState;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyReadwriteArray1, PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::sync::{Mutex, PoisonError};

/// N environments of one task, stepped in Rust threads. It may be made on
/// one Python thread and used or closed on another: the engine sits behind
/// a mutex (uncontended: every call that steps it holds the object
/// exclusively and reaches it without locking).
#[pyclass(module = "blockpuzzle._native")]
pub struct VecEnv {
    /// None once closed.
    engine: Mutex<Option<VectorEnv>>,
    obs_dim: usize,
    objects: usize,
}

/// An environment's error as the Python exception its kind maps to, naming the environment.
fn vec_to_py(e: VecError) -> PyErr {
    let msg = e.to_string();
    let kind = to_py(e.source);
    Python::with_gil(|py| {
        let class = kind.get_type(py);
        if class.is(&py.get_type::<PyValueError>()) {
            PyValueError::new_err(msg)
        } else {
            PyRuntimeError::new_err(msg)
        }
    })
}

impl VecEnv {
    /// The engine, held exclusively; an error once closed. The mutex cannot
    /// be poisoned in practice (the only lock, in `num_envs`, reads a length).
    fn engine(&mut self) -> PyResult<&mut VectorEnv> {
        self.engine
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .as_mut()
            .ok_or_else(|| PyRuntimeError::new_err("the vector environment is closed"))
    }

    /// The infos of the last call as a dict of arrays, one entry per environment.
    fn infos<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let n = self.objects;
        let engine = self.engine()?;
        let reports = engine.reports();
        let d = PyDict::new(py);
        let infos: Vec<Option<&Info>> = reports.iter().map(|r| r.info.as_ref()).collect();
        let get = |f: fn(&Info) -> bool| infos.iter().map(|i| i.is_some_and(f)).collect::<Vec<bool>>();
        d.set_item("is_success", PyArray1::from_vec(py, get(|i| i.is_success)))?;
        d.set_item("is_failure", PyArray1::from_vec(py, get(|i| i.is_failure)))?;
        d.set_item("challenge", PyArray1::from_vec(py, get(|i| i.challenge)))?;
        d.set_item("unstable", PyArray1::from_vec(py, get(|i| i.unstable)))?;
        let count = |f: fn(&Info) -> usize| infos.iter().map(|i| i.map_or(0, f) as i64).collect::<Vec<i64>>();
        d.set_item("level", PyArray1::from_vec(py, count(|i| i.level)))?;
        d.set_item("elapsed_steps", PyArray1::from_vec(py, count(|i| i.elapsed_steps)))?;
        // The contact matrix of each environment the call reached (zeros for the others).
        let mut cells = vec![0i8; reports.len() * n * n];
        for ((env, info), out) in engine.envs().iter().zip(&infos).zip(cells.chunks_mut((n * n).max(1))) {
            if info.is_none() {
                continue;
            }
            let m = env.contact_matrix();
            for (k, c) in out.iter_mut().enumerate() {
                *c = match m.get(k / n, k % n) {
                    ContactState::NeverTouched => 0,
                    ContactState::TouchedBefore => 1,
                    ContactState::TouchingNow => 2,
                };
            }
        }
        d.set_item("contact_matrix", PyArray1::from_vec(py, cells).reshape([reports.len(), n, n])?)?;
        // A task with a `[physics]` table: each parameter's value per environment (NaN where the
        // call did not reach it).
        if engine.envs().first().is_some_and(|e| e.physics().is_some()) {
            let physics = PyDict::new(py);
            for (k, p) in blockpuzzle::task::physics::PARAMS.iter().enumerate() {
                let values: Vec<f64> = infos
                    .iter()
                    .map(|i| i.and_then(|i| i.physics).map_or(f64::NAN, |d| d.values()[k].1))
                    .collect();
                physics.set_item(p.name, PyArray1::from_vec(py, values))?;
            }
            d.set_item("physics", physics)?;
        }
        // The single environment's other keys, as Gymnasium's vector info holds values that are not
        // numbers: one-dimensional object arrays (None for the environments the call did not reach).
        let objects = |values: Vec<PyObject>| -> PyResult<Bound<'py, PyAny>> {
            let a = py.import("numpy")?.call_method1("empty", (values.len(), "object"))?;
            for (k, v) in values.into_iter().enumerate() {
                a.set_item(k, v)?;
            }
            Ok(a)
        };
        let distribution: Vec<PyObject> = infos
            .iter()
            .map(|i| match i.and_then(|i| i.distribution.as_deref()) {
                Some(name) => pyo3::types::PyString::new(py, name).into_any().unbind(),
                None => py.None(),
            })
            .collect();
        d.set_item("distribution", objects(distribution)?)?;
        let touching = infos
            .iter()
            .map(|i| match i {
                Some(i) => Ok(PyList::new(py, i.touching.iter().map(|&(a, b)| (a, b)))?.into_any().unbind()),
                None => Ok(py.None()),
            })
            .collect::<PyResult<Vec<_>>>()?;
        d.set_item("touching", objects(touching)?)?;
        let present: Vec<bool> = infos.iter().map(Option::is_some).collect();
        for key in [
            "is_success",
            "is_failure",
            "challenge",
            "unstable",
            "level",
            "elapsed_steps",
            "contact_matrix",
            "distribution",
            "touching",
        ] {
            d.set_item(format!("_{key}"), PyArray1::from_vec(py, present.clone()))?;
        }
        d.set_item("autoreset", PyArray1::from_vec(py, reports.iter().map(|r| r.autoreset).collect::<Vec<_>>()))?;
        Ok(d)
    }
}

#[pymethods]
impl VecEnv {
    /// `VecEnv(task, num_envs, threads, obs_mode="flat")`: `task` an id or
    /// task file path; `obs_mode` "flat" or "objects" (robot | object rows | mask).
    #[new]
    #[pyo3(signature = (task, num_envs, threads = 1, obs_mode = "flat"))]
    fn new(task: &str, num_envs: usize, threads: usize, obs_mode: &str) -> PyResult<Self> {
        let threads_bound = blockpuzzle::support::limits::Bound { name: "threads", ..blockpuzzle::support::limits::THREADS };
        let bounds = [(blockpuzzle::support::limits::NUM_ENVS, num_envs), (threads_bound, threads)];
        for (bound, v) in bounds {
            bound.check_usize(v).map_err(PyValueError::new_err)?;
        }
        let obs_mode: ObsMode = obs_mode.parse().map_err(PyValueError::new_err)?;
        let task = crate::task(task)?;
        let engine =
            VectorEnv::new(&EnvConfig { obs_mode, ..EnvConfig::new(task) }, num_envs, threads).map_err(to_py)?;
        let (obs_dim, objects) = (engine.obs_spec().dim(), engine.envs()[0].objects().len());
        Ok(Self { engine: Mutex::new(Some(engine)), obs_dim, objects })
    }

    /// Observation size of one environment.
    #[getter]
    fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.engine.lock().unwrap_or_else(PoisonError::into_inner).as_ref().map_or(0, VectorEnv::num_envs)
    }

    /// Resets the environments whose `mask` entry is true (all when `mask`
    /// is None) with their `seeds` entry (None: the environment's own
    /// generator goes on), after applying `level`, `challenge` and
    /// `distribution` to them; writes their observations into `obs`
    /// (`num_envs × obs_dim` float32). Returns the infos.
    #[pyo3(signature = (obs, seeds, mask = None, level = None, challenge = None, distribution = None, physics = None))]
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
        physics: Option<Vec<(String, f64)>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let engine = self.engine()?;
        let out = obs.as_slice_mut().map_err(|e| PyValueError::new_err(format!("obs buffer: {e}")))?;
        // Pins hold for the episodes these environments play until the next reset (autoresets too).
        let options = ResetOptions { level, challenge, distribution, physics: Some(physics.unwrap_or_default()) };
        py.allow_threads(|| engine.reset(&seeds, mask.as_deref(), &options, out).map(|_| ())).map_err(vec_to_py)?;
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
        let engine = self.engine()?;
        let n = engine.num_envs();
        let shape = actions.shape().to_vec();
        let act_dim = blockpuzzle::env::ACTION_DIM;
        if shape != [n, act_dim] {
            return Err(PyValueError::new_err(format!(
                "invalid action: actions must have shape ({n}, {act_dim}), not {shape:?}"
            )));
        }
        let actions = actions.as_slice().map_err(|e| PyValueError::new_err(format!("invalid action: {e}")))?;
        let bad = |what: &str| PyValueError::new_err(format!("{what} buffer does not fit {n} environments"));
        let out = obs.as_slice_mut().map_err(|_| bad("obs"))?;
        let rew = rewards.as_slice_mut().map_err(|_| bad("reward"))?;
        let term = terminated.as_slice_mut().map_err(|_| bad("terminated"))?;
        let trunc = truncated.as_slice_mut().map_err(|_| bad("truncated"))?;
        if rew.len() != n || term.len() != n || trunc.len() != n {
            return Err(bad("an output"));
        }
        let reports = py.allow_threads(|| engine.step(actions, out)).map_err(vec_to_py)?;
        for (i, r) in reports.iter().enumerate() {
            (rew[i], term[i], trunc[i]) = (r.reward, r.terminated, r.truncated);
        }
        self.infos(py)
    }

    /// Frees every environment; later calls raise RuntimeError.
    fn close(&mut self) {
        *self.engine.get_mut().unwrap_or_else(PoisonError::into_inner) = None;
    }
}
