//! Where MuJoCo 2.2.2 (Debian's, the default) and MuJoCo 3.11 (the `mujoco3`
//! feature) differ in their C API, and the check that the library loaded at
//! run time is the one the headers were made from. Everything else in
//! `src/sim/mj/` compiles unchanged against both.

use super::MjError;
use mujoco_sys as sys;
use std::ffi::CStr;

/// The engine these bindings were generated for ("2.2.2" or "3.11.0").
pub fn header_version() -> String {
    version_text(sys::mjVERSION_HEADER as i64)
}

/// MuJoCo's integer versions as text: 2.x counts 222 for 2.2.2, 3.x counts
/// 3011000 for 3.11.0.
fn version_text(v: i64) -> String {
    if v >= 1_000_000 {
        format!("{}.{}.{}", v / 1_000_000, v / 1000 % 1000, v % 1000)
    } else {
        format!("{}.{}.{}", v / 100, v / 10 % 10, v % 10)
    }
}

/// Fails when the MuJoCo library loaded at run time is not the version the
/// headers (and hence every struct layout) were taken from.
pub(crate) fn check_version() -> Result<(), MjError> {
    // SAFETY: mj_version takes no arguments and returns an int.
    let library = unsafe { sys::mj_version() } as i64;
    compare(sys::mjVERSION_HEADER as i64, library)
}

fn compare(header: i64, library: i64) -> Result<(), MjError> {
    if library == header {
        return Ok(());
    }
    Err(MjError::Version { header: version_text(header), library: version_text(library) })
}

/// The two geoms of a contact: `geom1`/`geom2` in 2.2.2, `geom[2]` in 3.x
/// (where the old fields are deprecated).
pub(crate) fn contact_geoms(c: &sys::mjContact) -> [i32; 2] {
    #[cfg(not(feature = "mujoco3"))]
    return [c.geom1, c.geom2];
    #[cfg(feature = "mujoco3")]
    return c.geom;
}

/// Adds a file to a virtual file system: 2.2.2 allocates an empty file
/// (`mj_makeEmptyFileVFS`, names up to `mjMAXVFSNAME`) that is then filled,
/// 3.x copies a buffer (`mj_addBufferVFS`).
pub(crate) fn vfs_add(vfs: &mut sys::mjVFS, name: &CStr, contents: &[u8]) -> Result<(), &'static str> {
    let size = i32::try_from(contents.len()).map_err(|_| "file larger than 2 GiB")?;
    #[cfg(not(feature = "mujoco3"))]
    {
        if name.to_bytes().len() >= sys::mjMAXVFSNAME as usize {
            return Err("name too long");
        }
        // SAFETY: `vfs` is a live, initialised mjVFS and `name` a NUL-terminated
        // string that outlives the call; MuJoCo copies the name.
        match unsafe { sys::mj_makeEmptyFileVFS(vfs, name.as_ptr(), size) } {
            0 => {}
            1 => return Err("the VFS is full"),
            _ => return Err("a file of that name exists"),
        }
        let dst = vfs.filedata[(vfs.nfile - 1) as usize] as *mut u8;
        if !contents.is_empty() {
            // SAFETY: mj_makeEmptyFileVFS just allocated `size` bytes at
            // filedata[nfile-1] for this file; `contents` has exactly `size`
            // bytes and the two buffers cannot overlap.
            unsafe { std::ptr::copy_nonoverlapping(contents.as_ptr(), dst, contents.len()) };
        }
        Ok(())
    }
    #[cfg(feature = "mujoco3")]
    {
        // SAFETY: `vfs` is a live, initialised mjVFS, `name` NUL-terminated and
        // `contents` readable for `size` bytes; MuJoCo copies both.
        match unsafe { sys::mj_addBufferVFS(vfs, name.as_ptr(), contents.as_ptr().cast(), size) } {
            0 => Ok(()),
            2 => Err("a file of that name exists"),
            _ => Err("MuJoCo could not add the file"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_read_as_text() {
        assert_eq!(version_text(222), "2.2.2");
        assert_eq!(version_text(3_011_000), "3.11.0");
        assert_eq!(version_text(3_002_007), "3.2.7");
    }

    #[test]
    fn a_mismatch_names_both_versions() {
        let e = compare(3_011_000, 222).unwrap_err().to_string();
        assert!(e.contains("3.11.0 headers") && e.contains("library is 2.2.2"), "{e}");
        assert!(compare(222, 222).is_ok());
    }

    #[test]
    fn library_matches_headers() {
        check_version().unwrap();
        #[cfg(feature = "mujoco3")]
        assert_eq!(header_version(), "3.11.0");
        #[cfg(not(feature = "mujoco3"))]
        assert_eq!(header_version(), "2.2.2");
    }
}
