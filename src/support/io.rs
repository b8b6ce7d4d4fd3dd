//! The one way this crate writes and reads a file.
//!
//! **Writing.** [`Output`] decides once, from what is at the path, how it is
//! written:
//! - nothing there yet, or a regular file: into a temporary file beside it,
//!   flushed to disk, renamed over the target, and the folder's entry flushed
//!   too. A reader sees the old file or the new one, never a part; after a
//!   crash or power loss the file is one of the two; a failed write leaves no
//!   temporary file behind. A symbolic link is followed (the file it points at
//!   is replaced, the link stays), and the old file's permissions are kept;
//! - a character device or a pipe (`/dev/null`, `/dev/stdout`, a FIFO that a
//!   process reads): written in place, never renamed over, and nothing is
//!   created beside it;
//! - anything else is refused with the reason: a folder, a block device, a
//!   socket, a read-only file (renaming over it would defeat its protection), a
//!   link to nowhere, a FIFO nobody reads (the write would wait forever).
//!
//! **Reading.** [`read_text`] and [`read_bytes`] read an input whole, with a
//! size bound, so that no input file can drive memory or an echoed excerpt
//! without end, and refuse a folder, a device and a text with NUL bytes.

use std::fs::{File, Permissions};
use std::io::{BufWriter, Read, Write};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// How an output path is written (see the module).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// Replaced through a temporary file beside `path` (the file a link points at),
    /// with the permissions of the file it replaces.
    File {
        /// Where the file goes, symbolic links resolved.
        path: PathBuf,
        /// The replaced file's permissions.
        permissions: Option<Permissions>,
    },
    /// Written in place: a character device or a pipe.
    Stream,
}

/// Why an output could not be written, naming it. The messages read as they
/// did when they were built by hand: "cannot write PATH: REASON".
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The path is not ours to write ([`target`]), or the OS refused the write;
    /// `reason` says which (it is part of the message, not a separate source).
    #[error("cannot write {}: {reason}", path.display())]
    Refused {
        /// The output as given.
        path: PathBuf,
        /// Why, in the OS's words or [`target`]'s.
        reason: std::io::Error,
    },
    /// The value to write could not be encoded as JSON.
    #[error(transparent)]
    Encode(#[from] serde_json::Error),
    /// The library writing through a temporary path ([`write_atomic_via`])
    /// failed, or putting its bytes in place did.
    #[error("cannot write {}", path.display())]
    Via {
        /// The output as given.
        path: PathBuf,
        /// The library's error, or the I/O error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
}

impl WriteError {
    fn refused(path: &Path) -> impl Fn(std::io::Error) -> Self + '_ {
        move |reason| Self::Refused { path: path.to_owned(), reason }
    }
}

/// An error saying why a path is refused ("it is a folder; ..."); the caller names the path.
fn refuse(why: &str) -> std::io::Error {
    std::io::Error::other(format!("it {why}"))
}

/// How `path` would be written, or why it may not be.
///
/// # Errors
/// What is at `path` is not ours to write (see the module), each with the fix.
pub fn target(path: &Path) -> std::io::Result<Target> {
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            if !parent.is_dir() {
                return Err(refuse(&format!(
                    "cannot be created: the folder {} does not exist (create it first)",
                    parent.display()
                )));
            }
            return Ok(Target::File { path: path.to_owned(), permissions: None });
        }
        Err(e) => return Err(e),
    };
    if meta.file_type().is_symlink() {
        return match std::fs::canonicalize(path) {
            Ok(real) => match target(&real)? {
                Target::File { permissions, .. } => Ok(Target::File { path: real, permissions }),
                Target::Stream => Ok(Target::Stream),
            },
            Err(_) => {
                Err(refuse("is a symbolic link to a path that does not exist; remove the link or give another path"))
            }
        };
    }
    let t = meta.file_type();
    if t.is_file() {
        // Read-only by its mode, or not writable by this user (opening it for writing, without
        // truncating, changes nothing): renaming over it would defeat its protection.
        let denied = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .is_err_and(|e| e.kind() == std::io::ErrorKind::PermissionDenied);
        if meta.permissions().readonly() || denied {
            return Err(refuse("is read-only; make it writable (chmod u+w) or give another path"));
        }
        Ok(Target::File { path: path.to_owned(), permissions: Some(meta.permissions()) })
    } else if t.is_dir() {
        Err(refuse("is a folder; give a file path (for example a name inside it)"))
    } else if t.is_char_device() || t.is_fifo() {
        Ok(Target::Stream)
    } else if t.is_block_device() {
        Err(refuse("is a block device; blockpuzzle writes only files, character devices and pipes"))
    } else {
        Err(refuse("is a socket; blockpuzzle writes only files, character devices and pipes"))
    }
}

/// Checks before any work is done that `path` can be written as [`Output`]
/// would, and says how ([`target`]).
///
/// # Errors
/// As [`target`], naming the path.
pub fn check_output(path: &Path) -> Result<Target, WriteError> {
    target(path).map_err(WriteError::refused(path))
}

/// Opens a character device or a pipe for writing in place. A FIFO that no
/// process holds open for reading is refused at once (the open would wait
/// for one forever).
fn open_stream(path: &Path) -> std::io::Result<File> {
    let probe = std::fs::OpenOptions::new().write(true).custom_flags(libc::O_NONBLOCK).open(path);
    match probe {
        Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
            Err(refuse("is a FIFO that no process reads; start its reader first (a write would wait forever)"))
        }
        Err(e) => Err(e),
        // A reader holds it: the ordinary (blocking) open returns at once.
        Ok(probe) => {
            let file = std::fs::OpenOptions::new().write(true).open(path)?;
            drop(probe);
            Ok(file)
        }
    }
}

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
fn commit(tmp: &Path, path: &Path) -> std::io::Result<()> {
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

/// An output being written (see the module): bytes go through [`Write`], and
/// [`Output::finish`] puts them in place. Dropped unfinished (an error), it
/// leaves nothing behind: the temporary file is removed.
#[derive(Debug)]
pub struct Output {
    target: Target,
    /// The temporary file of a [`Target::File`], until it is committed.
    tmp: Option<PathBuf>,
    file: BufWriter<File>,
}

impl Output {
    /// Opens `path` for writing (so an unwritable destination fails before any work).
    ///
    /// # Errors
    /// As [`target`], or the OS's error creating the temporary file.
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let target = target(path)?;
        let (tmp, file) = match &target {
            Target::File { path: real, .. } => {
                let tmp = temp_path(real);
                let file = File::create(&tmp)?;
                (Some(tmp), file)
            }
            Target::Stream => (None, open_stream(path)?),
        };
        Ok(Self { target, tmp, file: BufWriter::new(file) })
    }

    /// Whether the output is written in place (a device or a pipe).
    pub fn is_stream(&self) -> bool {
        self.target == Target::Stream
    }

    /// Flushes and puts the output in place.
    ///
    /// # Errors
    /// The first I/O error; a replaced file is then unchanged.
    pub fn finish(mut self) -> std::io::Result<()> {
        self.file.flush()?;
        if let (Target::File { path, permissions }, Some(tmp)) = (&self.target, self.tmp.take()) {
            let kept = permissions.clone().map_or(Ok(()), |p| std::fs::set_permissions(&tmp, p));
            if let Err(e) = kept {
                let _ = std::fs::remove_file(&tmp);
                return Err(e);
            }
            commit(&tmp, path)?;
        }
        Ok(())
    }
}

impl Write for Output {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Drop for Output {
    fn drop(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Writes `path` with `write`, which fills the output (see the module).
///
/// # Errors
/// The first I/O error; `path` is then unchanged (a device or pipe may hold a part).
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut Output) -> std::io::Result<()>) -> std::io::Result<()> {
    let mut out = Output::create(path)?;
    write(&mut out)?;
    out.finish()
}

/// Writes `bytes` to `path` (see the module).
///
/// # Errors
/// I/O errors, naming the path.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic(path, |f| f.write_all(bytes)).map_err(WriteError::refused(path))
}

/// Writes `value` to `path` as pretty JSON (see the module).
///
/// # Errors
/// Encoding or I/O errors, naming the path.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<(), WriteError> {
    write_file(path, &serde_json::to_vec_pretty(value)?)
}

/// Writes `path` through a library that writes to a path of its own
/// choosing (images, plots, CSV): `write` gets a temporary path with
/// `path`'s extension, beside `path` for a file and in the system's
/// temporary folder for a device or pipe (whose bytes are then copied in).
///
/// # Errors
/// `write`'s error or an I/O error, naming `path`; `path` is then unchanged.
pub fn write_atomic_via<E>(path: &Path, write: impl FnOnce(&Path) -> Result<(), E>) -> Result<(), WriteError>
where
    E: Into<Box<dyn std::error::Error + Send + Sync + 'static>>,
{
    let name = WriteError::refused(path);
    let tmp = match target(path).map_err(&name)? {
        Target::File { path: real, .. } => temp_path(&real),
        Target::Stream => {
            let ext = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
            std::env::temp_dir().join(format!("blockpuzzle-{}-{}{ext}", std::process::id(), unique()))
        }
    };
    // Whether the folder takes a file at all, in the OS's words, before the
    // library tries and reports it in its own.
    File::create(&tmp).map_err(&name)?;
    let result: Result<(), Box<dyn std::error::Error + Send + Sync>> = write(&tmp).map_err(Into::into).and_then(|()| {
        let bytes = std::fs::read(&tmp)?;
        write_atomic(path, |f| f.write_all(&bytes)).map_err(|e| name(e).into())
    });
    let _ = std::fs::remove_file(&tmp);
    result.map_err(|source| WriteError::Via { path: path.to_owned(), source })
}

/// A number no other call in this process gets.
fn unique() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// Reads `path` whole as bytes, refusing more than `max` bytes and anything
/// that is not a regular file or a pipe; `what` names the input in messages
/// ("suite file").
///
/// # Errors
/// The OS's error, or the bound or kind refused, each naming the path.
pub fn read_bytes(path: &Path, what: &str, max: u64) -> std::io::Result<Vec<u8>> {
    read(path, what, max, false)
}

/// As [`read_bytes`], as UTF-8 text without NUL bytes. The text is checked as
/// it is read, so a binary file is refused after its first megabyte, not after
/// all of it.
///
/// # Errors
/// As [`read_bytes`], or text that is not UTF-8 or holds a NUL byte.
pub fn read_text(path: &Path, what: &str, max: u64) -> std::io::Result<String> {
    let bytes = read(path, what, max, true)?;
    String::from_utf8(bytes).map_err(|e| {
        refuse(&format!("is not UTF-8 text (byte offset {}); give the {what} itself", e.utf8_error().valid_up_to()))
    })
}

fn read(path: &Path, what: &str, max: u64, text: bool) -> std::io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    let t = meta.file_type();
    if t.is_dir() {
        return Err(refuse(&format!("is a folder; give the {what} itself")));
    }
    if !(t.is_file() || t.is_fifo() || t.is_char_device()) {
        return Err(refuse(&format!("is not a regular file; give the {what} itself")));
    }
    if t.is_file() && meta.len() > max {
        return Err(refuse(&format!("is {}; a {what} is at most {}", size(meta.len()), size(max))));
    }
    // A pipe is opened without waiting for a writer, and read until every
    // writer has closed it (none at all: it reads as empty).
    let nonblock = if t.is_fifo() { libc::O_NONBLOCK } else { 0 };
    let mut file = std::fs::OpenOptions::new().read(true).custom_flags(nonblock).open(path)?;
    let mut bytes = Vec::new();
    let mut chunk = vec![0u8; 1 << 20];
    loop {
        match file.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => {
                if text {
                    if let Some(at) = chunk[..n].iter().position(|&b| b == 0) {
                        let at = bytes.len() + at;
                        return Err(refuse(&format!(
                            "is not a text file (a NUL byte at offset {at}); give the {what} itself"
                        )));
                    }
                }
                bytes.extend_from_slice(&chunk[..n]);
                if bytes.len() as u64 > max {
                    return Err(refuse(&format!("holds more than {}; a {what} is at most that", size(max))));
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    // A pipe or device that gave nothing (a FIFO without a writer, /dev/null) is not an empty file.
    if !t.is_file() && bytes.is_empty() {
        let kind = kind(t);
        return Err(refuse(&format!(
            "is {kind} that gave no data (no process wrote to it); give the {what} as a file, or start its writer first"
        )));
    }
    Ok(bytes)
}

/// What a file of type `t` is, as messages name it: "a folder", "a pipe (FIFO)", "a file", "a
/// device" or "a socket".
pub fn kind(t: std::fs::FileType) -> &'static str {
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a pipe (FIFO)"
    } else if t.is_file() {
        "a file"
    } else if t.is_socket() {
        "a socket"
    } else {
        "a device"
    }
}

/// `1.5 MB` for 1_500_000.
fn size(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 30 => format!("{:.1} GiB", b as f64 / f64::from(1u32 << 30)),
        b if b >= 1 << 20 => format!("{:.1} MiB", b as f64 / f64::from(1u32 << 20)),
        b if b >= 1 << 10 => format!("{:.1} KiB", b as f64 / 1024.0),
        b => format!("{b} bytes"),
    }
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
        let err = write_atomic_via(&path, |tmp| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
            std::fs::write(tmp, b"x")?;
            Err("encoder failed".into())
        });
        assert_eq!(
            crate::support::error::chain(&err.unwrap_err()),
            format!("cannot write {}: encoder failed", path.display())
        );
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")], "no temporary file is left");
    }

    #[test]
    fn a_link_is_written_through_and_a_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.json");
        std::fs::write(&real, b"old").unwrap();
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_file(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays");
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        assert_eq!(std::fs::metadata(&real).unwrap().permissions().mode() & 0o777, 0o640);
        let dangling = dir.path().join("dangling.json");
        std::os::unix::fs::symlink(dir.path().join("nowhere/x"), &dangling).unwrap();
        assert!(format!("{:#}", write_file(&dangling, b"x").unwrap_err()).contains("does not exist"));
    }

    #[test]
    fn reads_are_bounded_and_text_is_text() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.toml");
        std::fs::write(&path, b"x = 1\n").unwrap();
        assert_eq!(read_text(&path, "task file", 100).unwrap(), "x = 1\n");
        let e = read_text(&path, "task file", 3).unwrap_err().to_string();
        assert!(e.contains("6 bytes; a task file is at most 3 bytes"), "{e}");
        std::fs::write(&path, [b'a', 0, b'b']).unwrap();
        assert!(read_text(&path, "task file", 100).unwrap_err().to_string().contains("NUL byte at offset 1"));
        std::fs::write(&path, [0xff, 0xfe]).unwrap();
        assert!(read_text(&path, "task file", 100).unwrap_err().to_string().contains("not UTF-8"));
        assert_eq!(read_bytes(&path, "tensor file", 100).unwrap(), [0xff, 0xfe]);
        assert!(read_text(dir.path(), "task file", 100).unwrap_err().to_string().contains("is a folder"));
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
