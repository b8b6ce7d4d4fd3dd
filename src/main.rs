fn main() {
    // A closed pipe ends the program quietly, as it does `cat` and `ls` (`blockpuzzle info | head -1`),
    // rather than as a panic in the next `println!`: Rust starts programs with SIGPIPE ignored.
    // SAFETY: restoring a signal's default disposition at startup, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // libtorch's OpenBLAS kernels (only the training build loads them).
    #[cfg(feature = "train")]
    blockpuzzle::blas::ensure_fast_kernels();
    std::process::exit(blockpuzzle::cli::run(std::env::args_os().collect()));
}
