//! The one way this crate writes a file: into a temporary file beside it,
//! flushed to disk, renamed over the target, and the folder's entry flushed
//! too. A reader sees the old file or the new one, never a part; after a
//! crash or power loss the file is one of the two. A failed write leaves no
//! temporary file behind.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The temporary file for `path`: `.STEM.tmp-PID.EXT` in the same folder
/// (the rename stays on one file system, two processes never share one, and
/// libraries that pick a format by extension still see it).
pub fn temp_path(path: &Path) -> PathBuf {
    let stem = path.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let pid = std::process::id();
    match path.extension() {
        Some(ext) => path.with_file_name(format!(".{stem}.tmp-{pid}.{}", ext.to_string_lossy())),
        None => path.with_file_name(format!(".{stem}.tmp-{pid}")),
    }
}

/// Moves the finished temporary file `tmp` onto `path` durably: flushes
/// `tmp`'s data, renames it, and flushes the folder's entry.
///
/// # Errors
/// The first I/O error (`tmp` is then removed).
pub fn commit(tmp: &Path, path: &Path) -> std::io::Result<()> {
    let result = (|| {
        File::open(tmp)?.sync_all()?;
        std::fs::rename(tmp, path)?;
        sync_dir(path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(tmp);
    }
    result
}

/// Flushes the entry of `path` in its folder (where the platform allows it).
fn sync_dir(path: &Path) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match File::open(dir) {
        Ok(d) => d.sync_all().or(Ok(())),
        Err(_) => Ok(()),
    }
}

/// Writes `path` atomically with `write`, which fills a buffered writer.
///
/// # Errors
/// The first I/O error; `path` is then unchanged.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = BufWriter::new(File::create(&tmp)?);
        write(&mut f)?;
        f.flush()?;
        Ok(())
    })();
    match result {
        Ok(()) => commit(&tmp, path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Writes `bytes` to `path` atomically.
///
/// # Errors
/// I/O errors, naming the path.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    use anyhow::Context;
    write_atomic(path, |f| f.write_all(bytes)).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes `value` to `path` atomically as pretty JSON.
///
/// # Errors
/// Encoding or I/O errors, naming the path.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    write_file(path, &serde_json::to_vec_pretty(value)?)
}

/// Writes `path` atomically through a library that writes to a path of its
/// own choosing (images, plots, CSV): `write` gets the temporary path.
///
/// # Errors
/// `write`'s error or an I/O error, naming `path`; `path` is then unchanged.
pub fn write_atomic_via(path: &Path, write: impl FnOnce(&Path) -> anyhow::Result<()>) -> anyhow::Result<()> {
    use anyhow::Context;
    let tmp = temp_path(path);
    // Whether the folder takes a file at all, in the OS's words, before the
    // library tries and reports it in its own.
    File::create(&tmp).with_context(|| format!("cannot write {}", path.display()))?;
    let result = write(&tmp).and_then(|()| Ok(commit(&tmp, path)?));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("cannot write {}", path.display()))
}

/// A folder this process made (with the parents it lacked), removed again
/// with everything in it when the guard is dropped, unless [`CreatedDir::keep`]
/// was called: a command that fails leaves the file system as it found it.
/// A folder that already existed is never removed.
#[derive(Debug)]
pub struct CreatedDir {
    /// The topmost folder this guard created, while it is armed.
    top: Option<PathBuf>,
}

impl CreatedDir {
    /// Creates `path` and its missing parents.
    ///
    /// # Errors
    /// The I/O error of creating a folder (whatever was created is removed).
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let top = path.ancestors().take_while(|p| !p.as_os_str().is_empty() && !p.exists()).last();
        let guard = Self { top: top.map(Path::to_path_buf) };
        std::fs::create_dir_all(path)?;
        Ok(guard)
    }

    /// Keeps the folder: the work that needed it succeeded.
    pub fn keep(mut self) {
        self.top = None;
    }
}

impl Drop for CreatedDir {
    fn drop(&mut self) {
        if let Some(top) = self.top.take() {
            let _ = std::fs::remove_dir_all(top);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomic(&path, |f| f.write_all(b"one")).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        let err = write_atomic(&path, |f| {
            f.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"one", "a failed write keeps the old file");
        let err = write_atomic_via(&path, |tmp| {
            std::fs::write(tmp, b"x")?;
            anyhow::bail!("encoder failed")
        });
        assert!(format!("{:#}", err.unwrap_err()).contains("a.txt"));
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")], "no temporary file is left");
    }

    #[test]
    fn a_created_folder_goes_unless_kept_and_an_existing_one_stays() {
        let dir = tempfile::tempdir().unwrap();
        let deep = dir.path().join("a/b/c");
        let guard = CreatedDir::create(&deep).unwrap();
        std::fs::write(deep.join("f"), b"x").unwrap();
        drop(guard);
        assert!(!dir.path().join("a").exists(), "the topmost created folder is removed");
        CreatedDir::create(&deep).unwrap().keep();
        assert!(deep.is_dir());
        drop(CreatedDir::create(&deep).unwrap());
        assert!(deep.is_dir(), "a folder that existed stays");
    }
}
