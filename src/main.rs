//! `blockpuzzle`, the command line. In the training build it links none of the training stack and
//! starts in milliseconds; the commands that need the stack run in `blockpuzzle-train`, which it
//! starts in its place (src/cli/halves.rs).

fn main() {
    // A closed pipe ends the program quietly, as it does `cat` and `ls` (`blockpuzzle info | head -1`),
    // rather than as a panic in the next `println!`: Rust starts programs with SIGPIPE ignored.
    // SAFETY: restoring a signal's default disposition at startup, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    #[cfg(feature = "train")]
    {
        if blockpuzzle::cli::runs_in_training_half(&args).is_some() {
            std::process::exit(blockpuzzle::cli::exec_training_half(args));
        }
        std::process::exit(blockpuzzle::cli::run_core(args));
    }
    #[cfg(not(feature = "train"))]
    std::process::exit(blockpuzzle::cli::run(args));
}
