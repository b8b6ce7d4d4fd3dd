//! The training build's command line in two binaries. Debian's libtorch costs every process that
//! links it about half a second of CPU before `main` (its operator registry and the libraries it
//! pulls in), so `blockpuzzle` links none of the training stack and runs every command that needs
//! none itself; it hands the others ([`runs_in_training_half`]) to `blockpuzzle-train`, the whole
//! command line, found beside it and started in its place (`exec`: the same process, so an MPI
//! rank or a caller waiting on the PID sees no difference).
//!
//! Both are built by every `cargo build` and installed by `cargo install`; `cargo run` builds and
//! runs `blockpuzzle-train` alone (the crate's `default-run`), which leaves a `blockpuzzle` built
//! before it stale. The two carry their build's identity (a digest of the sources, features and
//! profile, `build.rs`), and a `blockpuzzle-train` from other sources is refused, naming the
//! command that builds both.

use std::ffi::OsString;
use std::path::PathBuf;

/// The binary that runs the training commands.
pub const TRAINING_BINARY: &str = "blockpuzzle-train";

/// The environment variable through which `blockpuzzle` tells `blockpuzzle-train` its build.
const BUILD_VARIABLE: &str = "BLOCKPUZZLE_FRONT_BUILD";

/// This build's identity (build.rs: the sources' digest, the features and the profile).
pub const BUILD_ID: &str = env!("BLOCKPUZZLE_BUILD_ID");

/// How to get two halves that belong together, for every refusal here.
const FIX: &str = "build both halves of the command line with `cargo build --release` (`make build`; `cargo run` \
                   builds only `blockpuzzle-train`), or install both with `cargo install --path .`";

/// The commands that run in `blockpuzzle-train`: those that run libtorch, and `info`, which reports
/// its libraries. The training build's other commands (`plot`, `report`, `align`) run no libtorch.
pub const TRAINING_HALF: &[&str] = &["train", "bench", "zoo export", "info"];

/// The entry of [`TRAINING_HALF`] the command line `args` (from the program name on) runs, if any:
/// `blockpuzzle` starts `blockpuzzle-train` for it.
pub fn runs_in_training_half(args: &[OsString]) -> Option<&'static str> {
    super::command_in(TRAINING_HALF, args)
}

/// Where `blockpuzzle-train` should be: beside this program.
fn training_binary() -> std::io::Result<PathBuf> {
    Ok(std::env::current_exe()?.with_file_name(TRAINING_BINARY))
}

/// Starts `blockpuzzle-train` in this process's place with the same arguments; returns only when
/// it cannot (the exit status 1, the reason and the fix on stderr).
pub fn exec_training_half(args: Vec<OsString>) -> i32 {
    use std::os::unix::process::CommandExt;
    let command = runs_in_training_half(&args).unwrap_or("info");
    let path = match training_binary() {
        Ok(path) if path.is_file() => path,
        Ok(path) => {
            eprintln!(
                "error: `{command}` runs in {TRAINING_BINARY}, the training half of this command line, and {} \
                 does not exist: {FIX}",
                path.display()
            );
            return 1;
        }
        Err(e) => {
            eprintln!("error: `{command}` runs in {TRAINING_BINARY}, which is found beside this program, whose path is unknown ({e}): {FIX}");
            return 1;
        }
    };
    let err = std::process::Command::new(&path)
        .arg0(args.first().cloned().unwrap_or_else(|| "blockpuzzle".into()))
        .args(args.iter().skip(1))
        .env(BUILD_VARIABLE, BUILD_ID)
        .exec();
    eprintln!("error: cannot start {} for `{command}` ({err}): {FIX}", path.display());
    1
}

/// In `blockpuzzle-train`, at start: when `blockpuzzle` started it, whether both come from the same
/// build. Clears the variable, so that nothing this process starts inherits it.
///
/// # Errors
/// The two builds differ: the message names the fix.
pub fn check_front() -> anyhow::Result<()> {
    let Some(front) = std::env::var_os(BUILD_VARIABLE) else { return Ok(()) };
    // Called first thing in `main`, before any thread exists that could read the environment.
    std::env::remove_var(BUILD_VARIABLE);
    if front == BUILD_ID {
        return Ok(());
    }
    let here = std::env::current_exe().map_or_else(|_| TRAINING_BINARY.into(), |p| p.display().to_string());
    anyhow::bail!(
        "{here} was built from other sources than the `blockpuzzle` beside it (build {} there, {BUILD_ID} here): {FIX}",
        front.to_string_lossy()
    )
}
