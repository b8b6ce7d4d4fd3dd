fn main() {
    // A closed pipe ends the program quietly, as it does `cat` and `ls` (`blockpuzzle info | head -1`),
    // rather than as a panic in the next `println!`: Rust starts programs with SIGPIPE ignored.
    // SAFETY: restoring a signal's default disposition at startup, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    // libtorch's OpenBLAS kernels (only the training build loads them), for the commands that use
    // or report them: a second start costs every other command as much again.
    #[cfg(feature = "train")]
    if blockpuzzle::cli::wants_fast_kernels(&args) {
        blockpuzzle::learn::blas::ensure_fast_kernels();
    }
    std::process::exit(blockpuzzle::cli::run(args));
}
