//! `blockpuzzle`, the command line. In the training build it links none of the training stack and
//! starts in milliseconds; the commands that need the stack run in `blockpuzzle-train`, which it
//! starts in its place (src/cli/halves.rs).

fn main() {
    blockpuzzle::cli::default_sigpipe();
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
