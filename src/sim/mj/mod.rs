//! A safe wrapper over the raw `mujoco-sys` bindings: owning [`Model`] and
//! [`Data`] types, the virtual file system, name lookups, typed state views
//! and the contact list. Only what blockpuzzle needs is wrapped.

mod data;
mod engine;
mod error;
mod model;
#[cfg(feature = "render")]
pub mod render;
mod vfs;

pub use data::{Contact, Data, Warning};
pub use engine::header_version;
pub use error::MjError;
pub use model::{Model, NEQDATA};
pub use vfs::Vfs;

use mujoco_sys as sys;
use std::ffi::CStr;
use std::sync::Once;

/// Kinds of model objects that can be looked up by name (`mjtObj`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjType {
    Body,
    XBody,
    Joint,
    Geom,
    Site,
    Material,
    Equality,
}

impl ObjType {
    fn raw(self) -> i32 {
        use sys::mjtObj as O;
        (match self {
            ObjType::Body => O::mjOBJ_BODY,
            ObjType::XBody => O::mjOBJ_XBODY,
            ObjType::Joint => O::mjOBJ_JOINT,
            ObjType::Geom => O::mjOBJ_GEOM,
            ObjType::Site => O::mjOBJ_SITE,
            ObjType::Material => O::mjOBJ_MATERIAL,
            ObjType::Equality => O::mjOBJ_EQUALITY,
        }) as i32
    }

    /// Lower-case name used in messages.
    pub fn label(self) -> &'static str {
        match self {
            ObjType::Body | ObjType::XBody => "body",
            ObjType::Joint => "joint",
            ObjType::Geom => "geom",
            ObjType::Site => "site",
            ObjType::Material => "material",
            ObjType::Equality => "equality",
        }
    }
}

/// `mjEQ_WELD` as the integer stored in `eq_type`.
pub const EQ_WELD: i32 = sys::mjtEq::mjEQ_WELD as i32;

/// The MuJoCo library version string, e.g. "2.2.2" ("3.11.0" with the `mujoco3` feature).
pub fn version() -> String {
    // SAFETY: mj_versionString returns a pointer to a static NUL-terminated string.
    unsafe { CStr::from_ptr(sys::mj_versionString()) }.to_string_lossy().into_owned()
}

unsafe extern "C" fn quiet_warning(msg: *const std::os::raw::c_char) {
    if msg.is_null() {
        return;
    }
    // SAFETY: MuJoCo passes a NUL-terminated message.
    let text = unsafe { CStr::from_ptr(msg) }.to_string_lossy();
    if std::env::var_os("BLOCKPUZZLE_MUJOCO_WARNINGS").is_some() {
        eprintln!("MuJoCo warning: {text}");
    }
}

/// The result of a guarded MuJoCo call (`mujoco-sys/guard.c`): a fatal
/// MuJoCo error, which the guard turned into a return, as [`MjError::Fatal`].
pub(crate) fn guarded(status: i32) -> Result<(), MjError> {
    if status == 0 {
        return Ok(());
    }
    // SAFETY: bp_last_error returns this thread's NUL-terminated message buffer.
    let text = unsafe { CStr::from_ptr(sys::bp_last_error()) }.to_string_lossy().into_owned();
    Err(MjError::Fatal { message: text })
}

/// Routes MuJoCo's messages away from its default handlers, which print to
/// stdout and append to `MUJOCO_LOG.TXT` in the working folder. Warnings are
/// still counted in [`Data::warning_count`]; set `BLOCKPUZZLE_MUJOCO_WARNINGS=1`
/// to print them to stderr. A fatal error inside a guarded call (every
/// simulation call of [`Data`]) makes that call return [`MjError::Fatal`] with
/// MuJoCo's message, so a host process (Python) survives it; anywhere else it
/// is printed to stderr and ends the process (exit code 2). Idempotent.
pub fn install_handlers() {
    static ONCE: Once = Once::new();
    ONCE.call_once(set_handlers);
}

/// Points MuJoCo's warning and error handlers at ours.
pub(crate) fn set_handlers() {
    // SAFETY: mju_user_warning / mju_user_error are global function pointers
    // that MuJoCo reads when it warns or fails; they are written with
    // functions of the right type, at start-up (Once) and after each model
    // load (serialised by the loader's lock), which is when MuJoCo's compiler
    // may have replaced them.
    unsafe {
        sys::mju_user_warning = Some(quiet_warning);
        sys::mju_user_error = Some(sys::bp_error_handler);
    }
}
