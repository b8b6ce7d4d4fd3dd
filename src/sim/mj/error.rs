//! Errors of the MuJoCo wrapper.

use std::path::PathBuf;
use thiserror::Error;

/// Everything that can go wrong in the safe MuJoCo wrapper.
#[derive(Debug, Error)]
pub enum MjError {
    /// `mj_loadXML` refused a model; `message` is MuJoCo's own text.
    #[error("MuJoCo could not load {path}: {message}")]
    Load { path: PathBuf, message: String },
    /// The model file is not there.
    #[error("model file {path} does not exist")]
    MissingFile { path: PathBuf },
    /// A name that the model does not define.
    #[error("the model has no {kind} named {name:?}")]
    UnknownName { kind: &'static str, name: String },
    /// A name with an interior NUL byte or too long for MuJoCo.
    #[error("invalid name or path {name:?}: {reason}")]
    InvalidName { name: String, reason: &'static str },
    /// MuJoCo's virtual file system refused a file.
    #[error("MuJoCo's virtual file system refused {name:?}: {reason}")]
    Vfs { name: String, reason: &'static str },
    /// MuJoCo could not allocate an `mjData` or a model copy.
    #[error("MuJoCo could not allocate mjData or a model copy")]
    Alloc,
    /// A model's parameters were to change while others hold it too.
    #[error(
        "the model is shared by other states or scenes; give the state its own copy (Model::try_clone) to change it"
    )]
    ModelShared,
    /// Two states of different models were mixed.
    #[error("the two mjData belong to different models")]
    ModelMismatch,
    /// MuJoCo stopped on a fatal error during a simulation call (its message
    /// kept); the state must be reset before it is used again.
    #[error("MuJoCo failed: {message}; reset the environment before using it again")]
    Fatal { message: String },
    /// The MuJoCo library loaded at run time is not the version whose headers
    /// this build was made from (their structs may differ).
    #[error(
        "MuJoCo version mismatch: built against the {header} headers but the loaded library is {library}; \
             rebuild (`cargo clean -p mujoco-sys`) or fix LD_LIBRARY_PATH so that the two agree"
    )]
    Version { header: String, library: String },
    /// An index outside a model array.
    #[error("{kind} index {index} out of range (model has {count})")]
    OutOfRange { kind: &'static str, index: usize, count: usize },
}
