//! Paths from the page, resolved against the folders the app was started with (an allow-list):
//! a path is relative to one of them, has no `..`, and, once its links are followed, still lies
//! under that folder. Anything else is refused, naming why; nothing is joined blindly.

use std::path::{Component, Path, PathBuf};
use thiserror::Error;

/// The longest path the page may name, in bytes.
pub const MAX_PATH_BYTES: usize = 512;
/// How deep under a folder the listing looks.
pub const MAX_DEPTH: usize = 4;
/// At most this many files are listed per folder.
pub const MAX_LISTED: usize = 2000;

/// A refused or missing path.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum FileError {
    /// Not a relative path inside the folder.
    #[error("{path:?} is not a path inside the app's folders: {why}")]
    Outside {
        /// The path as asked.
        path: String,
        /// Why.
        why: &'static str,
    },
    /// No folder of that number.
    #[error("the app was started with {count} folders; there is no folder {index}")]
    NoFolder {
        /// Asked.
        index: usize,
        /// Folders.
        count: usize,
    },
    /// No such file.
    #[error("{path:?}: no such file in folder {index}")]
    Missing {
        /// The path.
        path: String,
        /// The folder.
        index: usize,
    },
    /// A name to save under that is not a plain `NAME.toml`.
    #[error(
        "{name:?} is not a file name to save under: give a plain name ending in .toml (letters, digits, '-', '_', \
         '.'; no folders), such as my-task.toml"
    )]
    BadName {
        /// The name.
        name: String,
    },
}

/// The folders the app may read (their canonical paths).
#[derive(Debug, Clone)]
pub struct Roots {
    roots: Vec<PathBuf>,
}

impl Roots {
    /// The folders, each resolved to its canonical path.
    ///
    /// # Errors
    /// A path that does not exist or is not a folder.
    pub fn new(dirs: &[PathBuf]) -> Result<Roots, super::ServeError> {
        let mut roots = Vec::new();
        for d in dirs {
            let folder = |why: String| super::ServeError::Folder { path: d.clone(), why };
            let canon = d.canonicalize().map_err(|e| folder(format!("cannot open it ({e})")))?;
            if !canon.is_dir() {
                return Err(folder("it is not a folder".to_owned()));
            }
            roots.push(canon);
        }
        Ok(Roots { roots })
    }

    /// The folders.
    pub fn folders(&self) -> &[PathBuf] {
        &self.roots
    }

    /// The file `path` (relative) in folder `index`: refused when the path is absolute, has a `..`,
    /// or leads (through a link) out of the folder; missing when it is no regular file.
    ///
    /// # Errors
    /// [`FileError`].
    pub fn resolve(&self, index: usize, path: &str) -> Result<PathBuf, FileError> {
        let root = self.roots.get(index).ok_or(FileError::NoFolder { index, count: self.roots.len() })?;
        let outside = |why| FileError::Outside { path: path.chars().take(MAX_PATH_BYTES).collect(), why };
        if path.is_empty() || path.len() > MAX_PATH_BYTES {
            return Err(outside("empty, or longer than 512 bytes"));
        }
        if path.contains('\0') || path.contains('\\') {
            return Err(outside("it holds a NUL or a backslash"));
        }
        let rel = Path::new(path);
        for c in rel.components() {
            match c {
                Component::Normal(_) | Component::CurDir => {}
                Component::ParentDir => return Err(outside("it climbs out with `..`")),
                Component::RootDir | Component::Prefix(_) => return Err(outside("it is absolute")),
            }
        }
        let joined = root.join(rel);
        let canon = joined.canonicalize().map_err(|_| FileError::Missing { path: path.to_owned(), index })?;
        if !canon.starts_with(root) {
            return Err(outside("a link in it leads out of the folder"));
        }
        if !canon.is_file() {
            return Err(FileError::Missing { path: path.to_owned(), index });
        }
        Ok(canon)
    }

    /// Where the editor saves `name`: a plain `NAME.toml` in the first folder.
    ///
    /// # Errors
    /// [`FileError::BadName`] for anything but a plain name ending in `.toml`.
    pub fn save_path(&self, name: &str) -> Result<PathBuf, FileError> {
        let bad = || FileError::BadName { name: name.chars().take(MAX_PATH_BYTES).collect() };
        let stem = name.strip_suffix(".toml").ok_or_else(bad)?;
        let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
        if stem.is_empty() || name.len() > 128 || !stem.chars().all(plain) || stem.starts_with('.') {
            return Err(bad());
        }
        let root = self.roots.first().ok_or_else(bad)?;
        Ok(root.join(name))
    }

    /// The files ending in `.{ext}` under every folder (at most [`MAX_DEPTH`] deep, hidden folders,
    /// `target` and links left out): `(folder index, relative path)`, sorted.
    pub fn list(&self, ext: &str) -> Vec<(usize, String)> {
        let mut out = Vec::new();
        for (i, root) in self.roots.iter().enumerate() {
            let mut found = Vec::new();
            walk(root, root, ext, 0, &mut found);
            found.sort();
            out.extend(found.into_iter().take(MAX_LISTED).map(|p| (i, p)));
        }
        out
    }
}

fn walk(root: &Path, dir: &Path, ext: &str, depth: usize, out: &mut Vec<String>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        if out.len() >= MAX_LISTED {
            return;
        }
        let name = e.file_name().to_string_lossy().into_owned();
        let Ok(kind) = e.file_type() else { continue };
        if name.starts_with('.') || kind.is_symlink() {
            continue;
        }
        let p = e.path();
        if kind.is_dir() && depth < MAX_DEPTH && name != "target" && name != "runs" {
            walk(root, &p, ext, depth + 1, out);
        } else if kind.is_file() && p.extension().is_some_and(|x| x == ext) {
            if let Ok(rel) = p.strip_prefix(root) {
                out.push(rel.to_string_lossy().into_owned());
            }
        }
    }
}
