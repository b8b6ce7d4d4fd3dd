//! Trained policies and their evaluation, by the command line's own code: a
//! zoo entry acts through the core's plain-Rust forward pass (bit for bit the
//! CLI's), and `evaluate_saved` runs the CLI's suite evaluator, so the same
//! policy on the same engine gives the same numbers from Python and the CLI.

use blockpuzzle::policy::actor::AnyPolicy;
use blockpuzzle::benchmark::provenance::{Build, Harness};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;

fn zoo_err(e: blockpuzzle::benchmark::zoo::ZooError) -> PyErr {
    match &e {
        blockpuzzle::benchmark::zoo::ZooError::Io { source, .. } => crate::read_err(source, e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// A zoo entry's deterministic actor (`.json` or `.safetensors` path), acting with the CLI's arithmetic.
#[pyclass(frozen, module = "blockpuzzle._native")]
pub(crate) struct ZooActor {
    policy: AnyPolicy,
    sha256: String,
}

#[pymethods]
impl ZooActor {
    #[new]
    fn new(path: std::path::PathBuf) -> PyResult<Self> {
        let (meta, saved) = blockpuzzle::benchmark::zoo::load(&path).map_err(zoo_err)?;
        let sha256 = saved.policy_id(&meta.name).sha256.unwrap_or_default();
        Ok(Self { policy: saved.policy, sha256 })
    }

    /// `sha256:` of what acts and the task it was trained on (results' `provenance.policy.sha256`).
    #[getter]
    fn sha256(&self) -> &str {
        &self.sha256
    }

    /// Actions for a batch of flat observations (`(n, obs_dim)` float32; a set network's
    /// observation is robot | object rows | mask, any number of rows): `(n, 4)` float32.
    fn act<'py>(&self, py: Python<'py>, obs: PyReadonlyArray2<'py, f32>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let (n, dim) = (obs.shape()[0], obs.shape()[1]);
        let policy = match self.policy.net().set {
            Some(layout) => {
                let row = layout.object + 1;
                let rows = dim.checked_sub(layout.robot).filter(|r| r % row == 0).ok_or_else(|| {
                    PyValueError::new_err(format!(
                        "the set policy reads {} robot features and rows of {} object features and a mask entry; \
                         observations of {dim} values do not split so",
                        layout.robot, layout.object
                    ))
                })?;
                self.policy.with_slots(rows / row)
            }
            None if dim != self.policy.obs_dim() => {
                return Err(PyValueError::new_err(format!(
                    "the policy reads observations of {} values, these have {dim}",
                    self.policy.obs_dim()
                )))
            }
            None => self.policy.clone(),
        };
        let x = obs.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))?.to_vec();
        let actions: Vec<Vec<f32>> = py.allow_threads(|| x.chunks_exact(dim.max(1)).map(|o| policy.act(o)).collect());
        let flat: Vec<f32> =
            actions.into_iter().flat_map(|a| (0..4).map(move |k| a.get(k).copied().unwrap_or(0.0))).collect();
        PyArray1::from_vec(py, flat).reshape([n, 4])
    }
}

/// A saved policy (a zoo entry's file) on a suite by the CLI's evaluator, named `name` in the
/// result: the result as JSON text, `harness` "python". `episodes` shortens every row to its first
/// episodes (recorded in the result); `on_row(split, row, done, total)` is called after each row,
/// with the row as the result holds it (a dict).
#[pyfunction]
#[pyo3(signature = (path, name, suite, threads=None, episodes=None, on_row=None))]
pub(crate) fn evaluate_saved(
    py: Python<'_>,
    path: std::path::PathBuf,
    name: &str,
    suite: &str,
    threads: Option<usize>,
    episodes: Option<usize>,
    on_row: Option<PyObject>,
) -> PyResult<String> {
    // The one resolver, as the CLI's `eval --suite` uses it.
    let saved = match blockpuzzle::benchmark::load::resolve(&path) {
        Ok(blockpuzzle::benchmark::load::Named::Saved(_, saved)) => saved,
        Ok(_) => return Err(PyValueError::new_err(format!("{}: not a trained policy", path.display()))),
        Err(blockpuzzle::benchmark::load::LoadError::Zoo(z)) => return Err(zoo_err(z)),
        Err(e) => return Err(PyValueError::new_err(blockpuzzle::support::error::chain(&e))),
    };
    let mut suite = blockpuzzle::benchmark::suite::load(suite).map_err(crate::suite_err)?;
    if let Some(n) = episodes {
        suite = suite.first_episodes(n).map_err(crate::suite_err)?;
    }
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let subject = blockpuzzle::benchmark::evaluate::Subject::Saved(Path::new(name), &saved);
    // Ctrl-C (a KeyboardInterrupt) or the callback's own error stops the evaluation after the row
    // and is raised as it is.
    let mut failed: Option<PyErr> = None;
    let mut report = |split: &str, row: &blockpuzzle::benchmark::evaluate::RowResult, done: usize, total: usize| {
        Python::with_gil(|py| {
            let called = py.check_signals().and_then(|()| {
                let Some(f) = on_row.as_ref() else { return Ok(()) };
                let text = serde_json::to_string(row).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
                let row = py.import("json")?.call_method1("loads", (text,))?;
                f.call1(py, (split, row, done, total)).map(|_| ())
            });
            called.map_err(|e| {
                failed = Some(e);
                "stopped by the on_row callback".into()
            })
        })
    };
    let result = py.allow_threads(|| {
        blockpuzzle::benchmark::evaluate::evaluate_suite(subject, &suite, threads, Harness::Python, &mut report)
    });
    if let Some(e) = failed {
        return Err(e);
    }
    let result = result.map_err(|e| PyRuntimeError::new_err(blockpuzzle::support::error::chain(&e)))?;
    serde_json::to_string(&result).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// What this build is: `blockpuzzle` (version), `commit` (None unless built from a checkout) and
/// `mujoco` (the engine's version): the `provenance` of the results it makes.
#[pyfunction]
pub(crate) fn build_info(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let b = Build::current();
    let d = PyDict::new(py);
    d.set_item("blockpuzzle", b.blockpuzzle)?;
    d.set_item("commit", b.commit)?;
    d.set_item("mujoco", b.mujoco)?;
    Ok(d)
}

/// The solver's actions for a batch of flat `entities` observations (`(n, dim)` float32: robot |
/// entity rows | mask, any number of block rows): `(n, 4)` float32. The solver is a function of one
/// observation ([`blockpuzzle::policy::ScriptedPolicy::decide`]), so the rows are independent and
/// their order does not matter.
#[pyfunction]
pub(crate) fn solver_act<'py>(py: Python<'py>, obs: PyReadonlyArray2<'py, f32>) -> PyResult<Bound<'py, PyArray2<f32>>> {
    use blockpuzzle::env::{ObsMode, ObsSpec};
    let (n, dim) = (obs.shape()[0], obs.shape()[1]);
    let probe = ObsSpec::new(ObsMode::Entities, 0);
    let (robot, row, fixtures) = (probe.robot_dim(), probe.object_dim() + 1, ObsMode::Entities.fixtures().len());
    let blocks = dim
        .checked_sub(robot)
        .filter(|r| r % row == 0)
        .and_then(|r| (r / row).checked_sub(fixtures))
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "the solver reads the `entities` observation ({robot} robot features, then rows of {} features \
                 and a mask entry each, the gripper's, table's and floor's rows included); observations of {dim} \
                 values do not split so: make the environment with obs_mode=\"entities\"",
                row - 1
            ))
        })?;
    let solver = blockpuzzle::policy::ScriptedPolicy::solver(blocks);
    let x = obs.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))?.to_vec();
    let flat: Vec<f32> = py.allow_threads(|| x.chunks_exact(dim.max(1)).flat_map(|o| solver.decide(o).0).collect());
    PyArray1::from_vec(py, flat).reshape([n, 4])
}

/// The solver's version (`blockpuzzle::policy::SOLVER_VERSION`).
#[pyfunction]
pub(crate) fn solver_version() -> u32 {
    blockpuzzle::policy::SOLVER_VERSION
}
