fn main() {
    blockpuzzle::blas::ensure_fast_kernels();
    if let Err(e) = blockpuzzle::cli::main() {
        eprintln!("error: {}", blockpuzzle::cli::error_text(&e));
        std::process::exit(1);
    }
}
