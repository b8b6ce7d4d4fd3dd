//! `blockpuzzle-train`, the training build's whole command line: `blockpuzzle` starts it in its
//! place for the commands that need the training stack (libtorch), and it runs every other command
//! too (src/cli/halves.rs).

fn main() {
    blockpuzzle::cli::default_sigpipe();
    if let Err(e) = blockpuzzle::cli::check_front() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    // libtorch's OpenBLAS kernels, for the commands that use or report them: a second start costs
    // every other command as much again.
    if blockpuzzle::cli::wants_fast_kernels(&args) {
        blockpuzzle::learn::blas::ensure_fast_kernels();
    }
    std::process::exit(blockpuzzle::cli::run(args));
}
