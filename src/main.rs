fn main() {
    if let Err(e) = blockpuzzle::cli::main() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
