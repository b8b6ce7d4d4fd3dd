//! MuJoCo's virtual file system: in-memory files that `mj_loadXML` reads
//! before it looks at the disk.

use super::MjError;
use mujoco_sys as sys;
use std::ffi::CString;

/// An owned `mjVFS`. In MuJoCo 2.2.2 it is large (about 2 MB of file names),
/// so it lives on the heap; dropping it frees the file buffers MuJoCo allocated.
pub struct Vfs {
    raw: Box<sys::mjVFS>,
}

impl Vfs {
    /// An empty virtual file system.
    pub fn new() -> Self {
        // SAFETY: mjVFS is plain old data (ints, chars and pointers; 3.x: one pointer), so an
        // all-zero value is valid; mj_defaultVFS then initialises it.
        let mut raw: Box<sys::mjVFS> = unsafe { Box::new(std::mem::zeroed()) };
        // SAFETY: `raw` points to a live, writable mjVFS.
        unsafe { sys::mj_defaultVFS(raw.as_mut()) };
        Self { raw }
    }

    /// Adds a file called `name` holding `contents`.
    ///
    /// MuJoCo 2.2.2 matches VFS names against the full path it computes for
    /// a file (the top-level file's folder joined with an include or mesh
    /// name), so register files under the path they would have on disk.
    ///
    /// # Errors
    /// [`MjError::Vfs`] when the name is too long, already present, the VFS is
    /// full, or the contents are too large; [`MjError::InvalidName`] for a NUL byte.
    pub fn add(&mut self, name: &str, contents: &[u8]) -> Result<(), MjError> {
        let c_name = CString::new(name)
            .map_err(|_| MjError::InvalidName { name: name.to_owned(), reason: "contains a NUL byte" })?;
        super::engine::vfs_add(self.raw.as_mut(), &c_name, contents)
            .map_err(|reason| MjError::Vfs { name: name.to_owned(), reason })
    }

    pub(crate) fn as_ptr(&self) -> *const sys::mjVFS {
        self.raw.as_ref()
    }
}

impl Default for Vfs {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for Vfs {
    fn drop(&mut self) {
        // SAFETY: `raw` was initialised by mj_defaultVFS and its buffers were
        // allocated by MuJoCo; mj_deleteVFS frees them exactly once.
        unsafe { sys::mj_deleteVFS(self.raw.as_mut()) };
    }
}
