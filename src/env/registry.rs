//! The registry of versioned environment ids: each is a task file shipped in
//! `tasks/` and embedded in the binary, compiled by the same code as a
//! user's task file. Wherever an id is accepted, a task file path is too.

use super::{BlockEnv, EnvConfig, EnvError};
use crate::task::{Task, TaskSource};
use std::path::Path;

/// A registered environment: its id and its task file.
#[derive(Debug, Clone, Copy)]
pub struct Registration {
    /// Versioned id, e.g. "BlocksTouch-v0".
    pub id: &'static str,
    /// The task file's text (`tasks/ID.toml`).
    pub toml: &'static str,
}

macro_rules! builtin {
    ($id:literal) => {
        Registration { id: $id, toml: include_str!(concat!("../../tasks/", $id, ".toml")) }
    };
}

/// Every registered environment, in listing order.
pub const REGISTRY: &[Registration] = &[
    builtin!("BlocksTouch-v0"),
    builtin!("BlocksChoose-v0"),
    builtin!("GripperTouch-v0"),
    builtin!("BlocksChooseShuffled-v0"),
    builtin!("ReachAvoid-v0"),
    builtin!("ToppleTower-v0"),
    builtin!("BlocksStack-v0"),
    builtin!("BlocksChooseN-v0"),
    builtin!("BlocksAvoid-v0"),
    builtin!("BlocksGather-v0"),
];

/// The registered ids.
pub fn ids() -> Vec<&'static str> {
    REGISTRY.iter().map(|r| r.id).collect()
}

/// Whether `arg` names a task file rather than an id: it is no registered id, and it ends in
/// `.toml` or `.json`, has a path separator, or exists (a folder or pipe of that name is then
/// refused as what it is, not called an unknown id).
pub fn is_path(arg: &str) -> bool {
    if REGISTRY.iter().any(|r| r.id == arg) {
        return false;
    }
    arg.ends_with(".toml")
        || arg.ends_with(".json")
        || arg.contains('/')
        || arg.contains('\\')
        || Path::new(arg).exists()
}

/// The task registered under `id`, or read from the task file at `id` when
/// it is a path.
///
/// # Errors
/// [`EnvError::UnknownId`] naming the known ids, or [`EnvError::Task`] for a
/// file that does not make a task.
pub fn task(id: &str) -> Result<Task, EnvError> {
    if let Some(r) = REGISTRY.iter().find(|r| r.id == id) {
        let origin = format!("tasks/{id}.toml (built in)");
        return Ok(Task::parse(r.toml, &origin, None)?);
    }
    if is_path(id) {
        return Ok(Task::from_file(Path::new(id))?);
    }
    Err(EnvError::UnknownId { id: id.to_owned(), known: ids().iter().map(|s| s.to_string()).collect() })
}

/// The task of a recorded source: the file or built-in of that id when it
/// still has the same content, otherwise the recorded copy (so runs,
/// policies and dumps outlive a moved or edited task file).
///
/// # Errors
/// A recorded copy that no longer compiles, or whose text is not the task
/// its hash names (an edited record is refused, whatever is on disk now).
pub fn recorded(source: &TaskSource) -> Result<Task, EnvError> {
    // The record itself must be whole: its text the task its hash names.
    let copy = source.compile()?;
    let current = match &source.path {
        Some(p) => Task::from_file(p).ok(),
        None => task(&source.id).ok(),
    };
    match current {
        Some(t) if t.source.hash == source.hash => Ok(t),
        _ => Ok(copy),
    }
}

/// The configuration of the environment `id` (a registered id or a task file path).
///
/// # Errors
/// As [`task`].
pub fn config(id: &str) -> Result<EnvConfig, EnvError> {
    Ok(EnvConfig::new(task(id)?))
}

/// Builds the environment `id` (a registered id or a task file path).
///
/// # Errors
/// As [`task`], or whatever building the scene reports.
pub fn make(id: &str) -> Result<BlockEnv, EnvError> {
    BlockEnv::new(config(id)?)
}
