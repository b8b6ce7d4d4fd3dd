//! A safe wrapper over the raw `mujoco-sys` bindings: owning [`Model`] and
//! [`Data`] types, the virtual file system, name lookups, typed state views
//! and the contact list. Only what blockpuzzle needs is wrapped.

mod data;
mod error;
mod model;
mod vfs;

pub use data::{Contact, Data, Warning};
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
        use sys::mjtObj_ as O;
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
pub const EQ_WELD: i32 = sys::mjtEq_::mjEQ_WELD as i32;

/// The MuJoCo library version string, e.g. "2.2.2".
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

unsafe extern "C" fn fatal_error(msg: *const std::os::raw::c_char) {
    let text = if msg.is_null() {
        "(no message)".into()
    } else {
        // SAFETY: MuJoCo passes a NUL-terminated message.
        unsafe { CStr::from_ptr(msg) }.to_string_lossy()
    };
    // MuJoCo cannot continue after an error and a panic must not unwind
    // through its C frames, so end the process as MuJoCo itself would.
    eprintln!("MuJoCo fatal error: {text}");
    std::process::exit(2);
}

/// Routes MuJoCo's messages away from its default handlers, which print to
/// stdout and append to `MUJOCO_LOG.TXT` in the working folder. Warnings are
/// still counted in [`Data::warning_count`]; set `BLOCKPUZZLE_MUJOCO_WARNINGS=1`
/// to print them to stderr. Fatal errors are printed to stderr and end the
/// process (exit code 2). Idempotent.
pub fn install_handlers() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // SAFETY: mju_user_warning / mju_user_error are global function
        // pointers that MuJoCo reads when it warns or fails; they are written
        // once, before any simulation in this process uses them (Once), with
        // functions of the right type.
        unsafe {
            sys::mju_user_warning = Some(quiet_warning);
            sys::mju_user_error = Some(fatal_error);
        }
    });
}
