//! `blockpuzzle._native`: the BlockPuzzle environments for Python (PyO3).
//! The Gymnasium classes around them are in `blockpuzzle/*.py`; this module
//! holds one environment (`Env`), Rust errors as Python exceptions, and
//! observations, images and contact matrices as numpy arrays.

use blockpuzzle::env::{registry, BlockEnv, EnvConfig, EnvError, Info, ObsMode};
use blockpuzzle::render::{Renderer, View};
use blockpuzzle::sim::rules::ContactState;
use blockpuzzle::sim::scene::SceneError;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::{PyFileNotFoundError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::sync::{Mutex, PoisonError};

mod policy;
mod render_error;
mod vector;

/// A Rust error as the Python exception a Gymnasium user expects, with the same message.
pub(crate) fn to_py(e: EnvError) -> PyErr {
    let msg = e.to_string();
    match e {
        EnvError::Scene(SceneError::MissingAssets { .. } | SceneError::NoAssets) => PyFileNotFoundError::new_err(msg),
        EnvError::Mujoco(_) | EnvError::Scene(_) | EnvError::NotReset | EnvError::EpisodeOver => {
            PyRuntimeError::new_err(msg)
        }
        EnvError::UnknownId { .. }
        | EnvError::Task(_)
        | EnvError::BadAction { .. }
        | EnvError::LevelOutOfRange { .. }
        | EnvError::NoChallenge { .. }
        | EnvError::NoDistribution { .. }
        | EnvError::Physics(_) => PyValueError::new_err(msg),
        _ => PyRuntimeError::new_err(msg),
    }
}

/// One BlockPuzzle environment: a registered id or a task file. Any Python
/// thread may use it (one at a time, as Python objects are); its renderer, an
/// OpenGL context, stays on the thread that first rendered.
#[pyclass(module = "blockpuzzle._native")]
struct Env {
    /// The simulation (the mutex makes the class `Sync`, as PyO3 asks; access
    /// goes through `&mut self`, which needs no lock).
    env: Mutex<Option<BlockEnv>>,
    view: View,
    renderer: Mutex<Option<OnThread<Renderer>>>,
}

impl Env {
    fn env(&mut self) -> PyResult<&mut BlockEnv> {
        self.env
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .as_mut()
            .ok_or_else(|| PyRuntimeError::new_err("the environment is closed"))
    }
}

/// A value that may be used and dropped only on the thread that made it (an
/// OpenGL context is current there). Elsewhere [`OnThread::get`] is an error
/// and dropping it leaks it rather than run its destructor on a foreign thread.
struct OnThread<T> {
    owner: std::thread::ThreadId,
    value: std::mem::ManuallyDrop<T>,
}

// SAFETY: the value is reached only through `get`, which checks that the
// calling thread is the one that made it, and dropped only on that thread
// (`Drop` leaks it elsewhere), so no other thread ever touches it.
unsafe impl<T> Send for OnThread<T> {}

impl<T> OnThread<T> {
    fn new(value: T) -> Self {
        Self { owner: std::thread::current().id(), value: std::mem::ManuallyDrop::new(value) }
    }

    fn get(&mut self, what: &str) -> PyResult<&mut T> {
        if std::thread::current().id() == self.owner {
            Ok(&mut self.value)
        } else {
            Err(PyRuntimeError::new_err(format!(
                "{what} works on the thread that first called it (its OpenGL context lives there); call it from \
                 that thread, or make one environment per thread"
            )))
        }
    }
}

impl<T> Drop for OnThread<T> {
    fn drop(&mut self) {
        if std::thread::current().id() == self.owner {
            // SAFETY: dropped once, here, on the thread that made it.
            unsafe { std::mem::ManuallyDrop::drop(&mut self.value) }
        }
    }
}

/// An episode's drawn dynamics as a dict, name to value (a count of steps, latency, an int).
pub(crate) fn physics_dict<'py>(
    py: Python<'py>,
    drawn: &blockpuzzle::task::physics::PhysicsDraw,
) -> PyResult<Bound<'py, PyDict>> {
    use blockpuzzle::task::physics::{Draw, PARAMS};
    let d = PyDict::new(py);
    for ((name, v), p) in drawn.values().into_iter().zip(PARAMS) {
        match p.draw {
            Draw::Steps => d.set_item(name, v as u64)?,
            Draw::Scale | Draw::Level => d.set_item(name, v)?,
        }
    }
    Ok(d)
}

/// `info` as a dict: success and failure of this step, level, distribution,
/// the touching pairs (object indices) and the contact matrix (0 never
/// touched, 1 touched before, 2 touching now).
fn info_dict<'py>(py: Python<'py>, info: &Info, env: &BlockEnv) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("is_success", info.is_success)?;
    d.set_item("is_failure", info.is_failure)?;
    d.set_item("level", info.level)?;
    d.set_item("challenge", info.challenge)?;
    d.set_item("distribution", info.distribution.clone())?;
    d.set_item("touching", PyList::new(py, info.touching.iter().map(|&(a, b)| (a, b)))?)?;
    d.set_item("elapsed_steps", info.elapsed_steps)?;
    d.set_item("unstable", info.unstable)?;
    if let Some(drawn) = &info.physics {
        d.set_item("physics", physics_dict(py, drawn)?)?;
    }
    let n = env.objects().len();
    let m = env.contact_matrix();
    let mut cells = Vec::with_capacity(n * n);
    for a in 0..n {
        for b in 0..n {
            cells.push(match m.get(a, b) {
                ContactState::NeverTouched => 0i8,
                ContactState::TouchedBefore => 1,
                ContactState::TouchingNow => 2,
            });
        }
    }
    d.set_item("contact_matrix", PyArray1::from_vec(py, cells).reshape([n, n])?)?;
    Ok(d)
}

#[pymethods]
impl Env {
    /// `Env(task, width=480, height=480, obs_mode="flat")`: `task` is a
    /// registered id (e.g. "BlocksTouch-v0") or the path of a task file; width
    /// and height are the size of `render()`'s images; `obs_mode` "flat" or
    /// "objects" (robot | object rows | mask).
    #[new]
    #[pyo3(signature = (task, width = 480, height = 480, obs_mode = "flat"))]
    fn new(task: &str, width: usize, height: usize, obs_mode: &str) -> PyResult<Self> {
        if width == 0 || height == 0 || width > 4096 || height > 4096 {
            return Err(PyValueError::new_err(format!(
                "render size {width} × {height}: each side must be in 1..=4096"
            )));
        }
        let obs_mode: ObsMode = obs_mode.parse().map_err(PyValueError::new_err)?;
        let task = crate::task(task)?;
        let env = BlockEnv::new(EnvConfig { obs_mode, ..EnvConfig::new(task) }).map_err(to_py)?;
        Ok(Self {
            env: Mutex::new(Some(env)),
            view: View { width, height, ..View::default() },
            renderer: Mutex::new(None),
        })
    }

    /// The task's id.
    #[getter]
    fn id(&mut self) -> PyResult<String> {
        Ok(self.env()?.id().to_owned())
    }

    /// Observation size.
    #[getter]
    fn obs_dim(&mut self) -> PyResult<usize> {
        Ok(self.env()?.observation_space().dim())
    }

    /// The observation's layout: a dict of `mode` ("flat", "objects" or "entities"), `mask`,
    /// `robot_dim`, `object_dim` (features per row), `max_objects` (block slots), `rows` (every
    /// row: the blocks', then in the `entities` mode the gripper's, table's and floor's),
    /// `rows_key` (the `Dict` key of the rows, None for flat), `dim` and `names` (one per component).
    fn obs_layout<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let spec = self.env()?.obs_spec();
        let d = PyDict::new(py);
        d.set_item("mode", spec.mode.name())?;
        d.set_item("mask", spec.mode.has_mask())?;
        d.set_item("robot_dim", spec.robot_dim())?;
        d.set_item("object_dim", spec.object_dim())?;
        d.set_item("max_objects", spec.max_objects)?;
        d.set_item("rows", spec.rows())?;
        d.set_item("rows_key", spec.mode.rows_key())?;
        d.set_item("dim", spec.dim())?;
        d.set_item("names", spec.names())?;
        Ok(d)
    }

    /// Action size (4: gripper displacement and finger command).
    #[getter]
    fn act_dim(&mut self) -> PyResult<usize> {
        Ok(self.env()?.action_space().dim())
    }

    /// The observation space's bounds, (low, high).
    fn observation_bounds<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let space = self.env()?.observation_space();
        PyTuple::new(py, [PyArray1::from_vec(py, space.low), PyArray1::from_vec(py, space.high)])
    }

    /// The highest curriculum level.
    #[getter]
    fn max_level(&mut self) -> PyResult<usize> {
        Ok(self.env()?.max_level())
    }

    /// The episode length limit.
    #[getter]
    fn max_episode_steps(&mut self) -> PyResult<usize> {
        Ok(self.env()?.config().task.spec.max_episode_steps)
    }

    /// The objects of the rules, in contact-matrix order, as (name, colour) pairs.
    fn objects(&mut self) -> PyResult<Vec<(String, String)>> {
        Ok(self.env()?.objects().iter().map(|o| (o.name.clone(), o.colour.name().to_owned())).collect())
    }

    /// The names of the task's evaluation distributions (e.g. "challenge").
    fn distributions(&mut self) -> PyResult<Vec<String>> {
        Ok(self.env()?.config().task.spec.distributions.keys().cloned().collect())
    }

    /// `reset(seed=None, level=None, challenge=None, distribution=None, physics=None)` ->
    /// (observation, info). A seed makes the episode reproducible; without
    /// one the environment's own generator continues. `level` sets the
    /// curriculum level, `challenge` / `distribution` an evaluation distribution
    /// (kept for later resets until changed); `physics` pins parameters of the
    /// task's `[physics]` table (name to value) for this episode.
    #[pyo3(signature = (seed = None, level = None, challenge = None, distribution = None, physics = None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<u64>,
        level: Option<usize>,
        challenge: Option<bool>,
        distribution: Option<String>,
        physics: Option<Vec<(String, f64)>>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, Bound<'py, PyDict>)> {
        let env = self.env()?;
        env.pin_physics(&physics.unwrap_or_default()).map_err(to_py)?;
        if let Some(l) = level {
            env.set_level(l).map_err(to_py)?;
        }
        if let Some(c) = challenge {
            env.set_challenge(c).map_err(to_py)?;
        }
        if let Some(name) = distribution {
            env.set_distribution(Some(&name)).map_err(to_py)?;
        }
        let (obs, info) = env.reset(seed).map_err(to_py)?;
        let info = info_dict(py, &info, env)?;
        Ok((PyArray1::from_vec(py, obs), info))
    }

    /// `step(action)` -> (observation, reward, terminated, truncated, info);
    /// `action` is a contiguous float32 array of `act_dim` values in [-1, 1].
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        action: PyReadonlyArray1<'py, f32>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, f32, bool, bool, Bound<'py, PyDict>)> {
        let action = action.as_slice().map_err(|e| PyValueError::new_err(format!("invalid action: {e}")))?;
        let env = self.env()?;
        let step = env.step(action).map_err(to_py)?;
        let info = info_dict(py, &step.info, env)?;
        Ok((PyArray1::from_vec(py, step.obs), step.reward, step.terminated, step.truncated, info))
    }

    /// The current state as an RGB image, (height, width, 3) uint8, from the
    /// Fetch viewer's camera (headless: EGL with Mesa's software rasteriser).
    fn render<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let view = self.view.clone();
        let env = self
            .env
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .as_mut()
            .ok_or_else(|| PyRuntimeError::new_err("the environment is closed"))?;
        let slot = self.renderer.get_mut().unwrap_or_else(PoisonError::into_inner);
        if slot.is_none() {
            let model = env.data().model().clone();
            let r = Renderer::new(&model, &view).map_err(render_error::render_err)?;
            *slot = Some(OnThread::new(r));
        }
        let Some(renderer) = slot.as_mut() else {
            return Err(PyRuntimeError::new_err("the renderer could not be made"));
        };
        let renderer = renderer.get("render()")?;
        // Colours move between episodes when the task shuffles roles.
        renderer.colour_env(env).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let image = renderer.render(env.data_mut(), None);
        let (w, h) = (image.width() as usize, image.height() as usize);
        Ok(PyArray1::from_vec(py, image.into_raw()).reshape([h, w, 3])?.into_any())
    }

    /// Benchmark helper: `steps` steps with uniform random actions (resetting
    /// when an episode ends) run entirely in Rust, no Python in the loop: the command line's
    /// benchmark loop (`benchmark::throughput::random_steps`). Returns the seconds taken, to set
    /// the binding's per-step cost against.
    #[pyo3(signature = (steps, seed = 0))]
    fn bench_steps(&mut self, py: Python<'_>, steps: usize, seed: u64) -> PyResult<f64> {
        let env = self.env()?;
        py.allow_threads(|| {
            let start = |env: &mut BlockEnv, seed: Option<u64>| Ok(env.reset(seed)?.0);
            let obs = start(env, Some(seed))?;
            let mut policy = blockpuzzle::policy::RandomPolicy::new(seed);
            let started = std::time::Instant::now();
            blockpuzzle::benchmark::throughput::random_steps(env, &start, &mut policy, obs, steps)?;
            Ok(started.elapsed().as_secs_f64())
        })
        .map_err(to_py)
    }

    /// Frees the simulation and the renderer; later calls raise RuntimeError.
    fn close(&mut self) {
        *self.renderer.get_mut().unwrap_or_else(PoisonError::into_inner) = None;
        *self.env.get_mut().unwrap_or_else(PoisonError::into_inner) = None;
    }
}

/// Self-test of MuJoCo's fatal-error path inside this interpreter: steps a
/// model whose stack overflows once its ball lands, which raises
/// RuntimeError with MuJoCo's message (MuJoCo alone would end the process).
#[pyfunction]
fn _mujoco_fatal_error_selftest() -> PyResult<()> {
    use blockpuzzle::sim::mj::{Data, Model};
    // A stack too small for the first contact (MuJoCo 3 counts it in bytes).
    let xml = r#"<mujoco><option timestep="0.002"/><size memory="4K"/><worldbody>
        <geom type="plane" size="1 1 0.1"/><body pos="0 0 0.5"><joint type="free"/>
        <geom type="sphere" size="0.05" mass="1"/></body></worldbody></mujoco>"#;
    let err = |e: blockpuzzle::sim::mj::MjError| PyRuntimeError::new_err(e.to_string());
    let model = Model::from_xml_string(xml, std::path::Path::new("selftest.xml")).map_err(err)?;
    let mut data = Data::new(std::sync::Arc::new(model)).map_err(err)?;
    for _ in 0..1000 {
        data.step().map_err(err)?;
    }
    Ok(())
}

/// The digest of three seeded episodes that pins the dynamics (tests/golden.json;
/// `blockpuzzle::episode::rollout::episode_digest`), computed by this build.
#[pyfunction]
fn _golden_digest(env: &str, scripted: bool, level: usize, challenge: bool, seed: u64) -> PyResult<String> {
    blockpuzzle::episode::rollout::episode_digest(env, scripted, level, challenge, seed).map_err(|e| match e {
        blockpuzzle::episode::rollout::RolloutError::Env(e) => to_py(e),
        e => PyRuntimeError::new_err(e.to_string()),
    })
}

/// The step limit of a registered id or task file (its `max_episode_steps`), read
/// without building the scene: what Gymnasium's registry records as the spec's.
#[pyfunction]
fn max_episode_steps(task: &str) -> PyResult<usize> {
    Ok(crate::task(task)?.spec.max_episode_steps)
}

/// The content hash (`sha256:…`) of a registered id's or task file's task: what suites, results
/// and demos record as its `task_sha256`.
#[pyfunction]
fn task_sha256(task: &str) -> PyResult<String> {
    Ok(crate::task(task)?.source.hash)
}

/// The registered environment ids.
#[pyfunction]
fn env_ids() -> Vec<&'static str> {
    registry::ids()
}

/// The MuJoCo version the environments run on (the `mujoco` package's, 3.11.0).
#[pyfunction]
fn mujoco_version() -> String {
    blockpuzzle::sim::mj::version()
}

/// Reads the Fetch assets from `root` (gymnasium-robotics' `envs/assets`)
/// from now on, unless `$BLOCKPUZZLE_MODELS_DIR` is set; checks every file's
/// sha256 first (FileNotFoundError / ValueError naming the file).
#[pyfunction]
fn _use_fetch_assets(root: std::path::PathBuf) -> PyResult<()> {
    blockpuzzle::sim::scene::use_fetch_assets(&root).map_err(|e| match e {
        SceneError::MissingAssets { .. } => PyFileNotFoundError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    })
}

/// The folder the next scene loads from: the Fetch assets registered at
/// import, or `$BLOCKPUZZLE_MODELS_DIR`.
#[pyfunction]
fn assets_dir() -> PyResult<std::path::PathBuf> {
    blockpuzzle::sim::scene::assets().map(|a| a.base).map_err(|e| to_py(EnvError::Scene(e)))
}

/// An input file that cannot be read, as Python names it: a path that does
/// not exist is FileNotFoundError, one that may not be read PermissionError,
/// anything else about the file (a folder, too large, not text) ValueError.
/// Task files, suites and zoo entries all follow this one convention.
pub(crate) fn read_err(source: &std::io::Error, msg: String) -> PyErr {
    match source.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
        std::io::ErrorKind::PermissionDenied => pyo3::exceptions::PyPermissionError::new_err(msg),
        _ => PyValueError::new_err(msg),
    }
}

/// A suite that cannot be read ([`read_err`]) or checked (ValueError).
pub(crate) fn suite_err(e: blockpuzzle::benchmark::suite::SuiteError) -> PyErr {
    match &e {
        blockpuzzle::benchmark::suite::SuiteError::Read { source, .. } => {
            let msg = format!("{e}: {source}");
            read_err(source, msg)
        }
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// The task of a registered id or a task file; a file that does not exist is
/// FileNotFoundError ([`read_err`]), a bad one ValueError.
pub(crate) fn task(id: &str) -> PyResult<blockpuzzle::task::Task> {
    if registry::is_path(id) {
        if let Err(source) = std::fs::metadata(id) {
            return Err(read_err(&source, format!("cannot read the task file {id}: {source}")));
        }
    }
    registry::task(id).map_err(to_py)
}

/// An evaluation suite (a built-in name or a suite file), checked, shortened to its first
/// `episodes` per row where given: a dict of `name`, `summary`, `sha256`, `id` (what results
/// record of it) and `splits`, a list of (split name, rows),
/// each row a dict of `task` (id or file path), `task_id`, `task_sha256` (the compiled task's
/// content hash), `distribution` (None: the
/// curriculum's), `level` (None: the last), `seed` and `episodes`.
#[pyfunction]
#[pyo3(signature = (name, episodes=None))]
fn suite<'py>(py: Python<'py>, name: &str, episodes: Option<usize>) -> PyResult<Bound<'py, PyDict>> {
    let mut s = blockpuzzle::benchmark::suite::load(name).map_err(suite_err)?;
    if let Some(n) = episodes {
        s = s.first_episodes(n).map_err(suite_err)?;
    }
    let d = PyDict::new(py);
    d.set_item("name", &s.name)?;
    d.set_item("summary", &s.summary)?;
    d.set_item("sha256", &s.sha256)?;
    // What results record of it (the CLI's `SuiteId`, a shortened run's mark included).
    let id = serde_json::to_string(&s.id()).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    d.set_item("id", py.import("json")?.call_method1("loads", (id,))?)?;
    let splits = PyList::empty(py);
    for split in &s.splits {
        let rows = PyList::empty(py);
        for r in &split.rows {
            let row = PyDict::new(py);
            row.set_item("task", &r.source)?;
            row.set_item("generated", r.generated)?;
            row.set_item("toml", &r.task.source.toml)?;
            row.set_item("task_id", r.task.id())?;
            row.set_item("task_sha256", &r.task.source.hash)?;
            row.set_item("distribution", r.distribution.as_deref())?;
            row.set_item("level", r.level)?;
            row.set_item("seed", r.seed)?;
            row.set_item("episodes", r.episodes)?;
            rows.append(row)?;
        }
        splits.append((split.name.as_str(), rows))?;
    }
    d.set_item("splits", splits)?;
    Ok(d)
}

/// Task files drawn from the family file `family` for generator seeds `seed .. seed + count`, each
/// kept where the solver can play it (`blockpuzzle task generate`), written to the folder `out`
/// (ID.toml per task and generated.json); returns generated.json's record as JSON text. The GIL is
/// released while the candidates are checked.
#[pyfunction]
#[pyo3(signature = (family, out, seed=0, count=10, threads=None))]
fn generate_tasks(py: Python<'_>, family: &str, out: &str, seed: u64, count: usize, threads: Option<usize>) -> PyResult<String> {
    use blockpuzzle::support::limits::{GENERATE_COUNT, THREADS};
    GENERATE_COUNT.check_usize(count).map_err(PyValueError::new_err)?;
    blockpuzzle::support::limits::seed_range(seed, count as u64).map_err(PyValueError::new_err)?;
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    THREADS.check_usize(threads).map_err(PyValueError::new_err)?;
    let shipped = blockpuzzle::task::family::BUILTIN_FAMILIES.iter().any(|(n, _)| *n == family);
    if !shipped {
        if let Err(source) = std::fs::metadata(family) {
            return Err(read_err(&source, format!("cannot read the family file {family}: {source}")));
        }
    }
    let fam = blockpuzzle::task::family::Family::load(family, None).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let out = std::path::PathBuf::from(out);
    // Every output checked before any candidate is played, as `task generate` does.
    blockpuzzle::episode::generate::check_outputs(&out, &fam, seed, count).map_err(|e| PyValueError::new_err(blockpuzzle::support::error::chain(&e)))?;
    let manifest = py.allow_threads(|| -> Result<serde_json::Value, String> {
        let results = blockpuzzle::episode::generate::generate(&fam, seed, count, threads).map_err(|e| e.to_string())?;
        let build = blockpuzzle::benchmark::provenance::Build::current();
        blockpuzzle::episode::generate::write_folder(&out, &fam, family, seed, &results, &build).map_err(|e| blockpuzzle::support::error::chain(&e))
    });
    manifest.map(|m| m.to_string()).map_err(PyValueError::new_err)
}

/// The solver's episodes on a suite split, written to `out` as a demos file (`blockpuzzle demos`'s
/// code, harness "python"); returns the number of episodes, steps and successes as JSON.
#[pyfunction]
#[pyo3(signature = (suite, out, split="train", episodes=None, threads=None))]
fn record_demos(
    py: Python<'_>,
    suite: &str,
    out: &str,
    split: &str,
    episodes: Option<usize>,
    threads: Option<usize>,
) -> PyResult<String> {
    use blockpuzzle::support::limits::{EVAL_EPISODES, THREADS};
    if let Some(n) = episodes {
        EVAL_EPISODES.check_usize(n).map_err(PyValueError::new_err)?;
    }
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    THREADS.check_usize(threads).map_err(PyValueError::new_err)?;
    let s = blockpuzzle::benchmark::suite::load(suite).map_err(suite_err)?;
    let out = std::path::PathBuf::from(out);
    let done = py.allow_threads(|| -> Result<serde_json::Value, blockpuzzle::benchmark::demos::DemosError> {
        let harness = blockpuzzle::benchmark::provenance::Harness::Python;
        let d = blockpuzzle::benchmark::demos::record_to(&out, &s, split, episodes, threads, harness)?;
        Ok(serde_json::json!({"episodes": d.episodes.len(), "steps": d.steps(), "successes": d.successes(), "rows": d.layout.rows}))
    });
    done.map(|v| v.to_string()).map_err(|e| PyValueError::new_err(blockpuzzle::support::error::chain(&e)))
}

/// Reads a demos file with the core's reader (`Demos::read`, what `train --demos` reads) and returns
/// its episode and step counts as JSON; a file it refuses is a ValueError naming why. The tests run
/// one corpus of good and edited files through it and through `datasets.load_demos`, which must agree.
#[pyfunction]
fn read_demos(py: Python<'_>, path: &str) -> PyResult<String> {
    let path = std::path::PathBuf::from(path);
    let read = py.allow_threads(|| blockpuzzle::benchmark::demos::Demos::read(&path));
    let d = read.map_err(|e| PyValueError::new_err(blockpuzzle::support::error::chain(&e)))?;
    Ok(serde_json::json!({"episodes": d.episodes.len(), "steps": d.steps()}).to_string())
}

/// The commands only the Rust command line's training build has (`cli::TRAINING_COMMANDS`).
#[pyfunction]
fn training_commands() -> Vec<&'static str> {
    blockpuzzle::cli::TRAINING_COMMANDS.to_vec()
}

/// The facts Rust defines once and Python reads from here rather than writing them again (issue
/// 75): where an object row's colour one-hot begins and an `entities` row's width (entries of zoo
/// formats 1-6 do not record them), the colours in one-hot order, the outcome names in the order
/// they are tested, the zoo formats this build reads and the one it writes, and the engines numbers
/// are made on, and each built-in task's content hash. `python/tests/test_facts.py` fails on one of
/// them written by hand in the package.
#[pyfunction]
fn facts(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    // The core's one document (benchmark::facts), which python/blockpuzzle/facts.json also holds. It
    // is made once a process (it compiles every built-in task for its hash; the package reads it
    // three times at import); each call returns a fresh dict, so no caller can edit another's.
    static TEXT: std::sync::OnceLock<Result<String, String>> = std::sync::OnceLock::new();
    let text = TEXT.get_or_init(|| blockpuzzle::benchmark::facts::facts_file().map_err(|e| e.to_string()));
    let text = text.as_deref().map_err(|e| PyValueError::new_err(e.to_owned()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The observation modes, by name (`obs_mode`): the core's closed set, in its order.
#[pyfunction]
fn obs_modes() -> Vec<&'static str> {
    blockpuzzle::env::ObsMode::ALL.iter().map(|m| m.name()).collect()
}

/// The command line's commands that need no libtorch, run in this process: `args` from the
/// program name on; returns the exit status (the `blockpuzzle` command of the package).
#[pyfunction]
fn cli(py: Python<'_>, args: Vec<String>) -> i32 {
    py.allow_threads(|| blockpuzzle::cli::run(args.into_iter().map(Into::into).collect()))
}

/// The Wilson score interval at 95% of `successes` out of `n` (the CLI's, for `evaluate`).
#[pyfunction]
fn wilson95(successes: usize, n: usize) -> (f64, f64) {
    blockpuzzle::episode::outcome::wilson95(successes, n)
}

/// The CLI's outcome of one episode (src/episode/outcome.rs `Outcome::classify`): the rules' flags, the
/// episode's contact matrix over the rule objects (gripper, table, the block slots, then the floor if
/// it is one), each rule object's colour index (0-3 red, blue, green, grey; -1 for an absent slot),
/// and each block slot's height at the start and the end.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn outcome(
    success: bool,
    failure: bool,
    unstable: bool,
    touched: Vec<Vec<bool>>,
    colours: Vec<i64>,
    z_start: Vec<f64>,
    z_end: Vec<f64>,
) -> PyResult<&'static str> {
    use blockpuzzle::episode::outcome::{Outcome, Summary};
    use blockpuzzle::sim::rules::Colour;
    let n = colours.len();
    if touched.len() != n || touched.iter().any(|r| r.len() != n) || z_start.len() != z_end.len() {
        return Err(PyValueError::new_err(format!(
            "outcome: a {n} x {n} contact matrix for {n} rule objects and as many start as end heights"
        )));
    }
    let colours: Vec<Option<Colour>> =
        colours.iter().map(|&c| usize::try_from(c).ok().and_then(|c| Colour::ALL.get(c).copied())).collect();
    // Gripper and table first, then the block slots.
    let blocks: Vec<bool> = (0..n).map(|i| (2..2 + z_start.len()).contains(&i)).collect();
    let heights: Vec<(Option<f64>, Option<f64>)> = z_start.iter().zip(&z_end).map(|(a, b)| (Some(*a), Some(*b))).collect();
    Ok(Outcome::classify(&Summary {
        success,
        failure,
        unstable,
        colours: &colours,
        blocks: &blocks,
        gripper: Some(0),
        touched: &|a, b| touched[a][b] || touched[b][a],
        heights: &heights,
    })
    .name())
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(outcome, m)?)?;
    m.add_class::<Env>()?;
    m.add_class::<vector::VecEnv>()?;
    m.add_class::<policy::ZooActor>()?;
    m.add_function(wrap_pyfunction!(policy::evaluate_saved, m)?)?;
    m.add_function(wrap_pyfunction!(policy::build_info, m)?)?;
    m.add_function(wrap_pyfunction!(policy::solver_act, m)?)?;
    m.add_function(wrap_pyfunction!(policy::solver_version, m)?)?;
    m.add_function(wrap_pyfunction!(env_ids, m)?)?;
    m.add_function(wrap_pyfunction!(max_episode_steps, m)?)?;
    m.add_function(wrap_pyfunction!(task_sha256, m)?)?;
    m.add_function(wrap_pyfunction!(mujoco_version, m)?)?;
    m.add_function(wrap_pyfunction!(suite, m)?)?;
    m.add_function(wrap_pyfunction!(wilson95, m)?)?;
    m.add_function(wrap_pyfunction!(cli, m)?)?;
    m.add_function(wrap_pyfunction!(obs_modes, m)?)?;
    m.add_function(wrap_pyfunction!(facts, m)?)?;
    m.add_function(wrap_pyfunction!(generate_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(record_demos, m)?)?;
    m.add_function(wrap_pyfunction!(read_demos, m)?)?;
    m.add_function(wrap_pyfunction!(training_commands, m)?)?;
    m.add_function(wrap_pyfunction!(_mujoco_fatal_error_selftest, m)?)?;
    m.add_function(wrap_pyfunction!(_use_fetch_assets, m)?)?;
    m.add_function(wrap_pyfunction!(assets_dir, m)?)?;
    m.add_function(wrap_pyfunction!(_golden_digest, m)?)?;
    m.add_function(wrap_pyfunction!(render_error::_render_error_message, m)?)?;
    Ok(())
}
