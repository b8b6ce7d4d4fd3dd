//! `blockpuzzle serve`: the browser app on a local address, like TensorBoard.

use anyhow::Result;
use std::io::Write;
use std::net::IpAddr;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub(super) struct ServeArgs {
    /// The port (0 picks a free one).
    #[arg(long, default_value_t = crate::serve::DEFAULT_PORT)]
    port: u16,
    /// The address to listen on. Anything but loopback lets other machines in (a warning says who).
    #[arg(long, default_value = "127.0.0.1")]
    bind: IpAddr,
    /// A folder whose task and family files the app may read (repeatable; default: the current
    /// folder). The editor saves into the first.
    #[arg(long = "dir")]
    dirs: Vec<PathBuf>,
    /// A trained policy (file, run folder or zoo name) to offer beside the solver, random actions
    /// and the zoo (repeatable).
    #[arg(long = "policy")]
    policies: Vec<PathBuf>,
    /// A folder of suite results (`eval --suite` output, or folders of them per engine) for the
    /// leaderboard (repeatable; default: results/generalization when it exists).
    #[arg(long = "results")]
    results: Vec<PathBuf>,
}

/// `blockpuzzle serve`.
pub(super) fn serve(a: ServeArgs) -> Result<()> {
    let dirs = if a.dirs.is_empty() { vec![PathBuf::from(".")] } else { a.dirs };
    let results = if a.results.is_empty() {
        let default = PathBuf::from("results/generalization");
        if default.is_dir() {
            vec![default]
        } else {
            Vec::new()
        }
    } else {
        a.results
    };
    if let Some(warning) = crate::serve::exposure_warning(a.bind) {
        eprintln!("{warning}");
    }
    let running =
        crate::serve::start(crate::serve::Options { bind: a.bind, port: a.port, dirs, policies: a.policies, results })?;
    let addr = running.addr();
    let host = if addr.ip().is_unspecified() { "127.0.0.1".to_owned() } else { addr.ip().to_string() };
    let host = if host.contains(':') { format!("[{host}]") } else { host };
    println!("BlockPuzzle on MuJoCo {}: http://{host}:{}/ (Ctrl-C stops it)", crate::sim::mj::version(), addr.port());
    let _ = std::io::stdout().flush();
    running.wait();
    Ok(())
}
