//! Layer 9, serve (the `serve` feature): the browser app, `blockpuzzle serve`.
//!
//! | module | what |
//! |---|---|
//! | [`http`] | the server: the bind (loopback unless told), per-connection time bounds, bounded requests, a bounded pool of workers, the routes |
//! | [`files`] | paths from the page resolved against the folders the app was started with, never joined blindly |
//! | [`api`] | what the page reads and asks: built-in tasks, families and their draws, suites, the zoo, the leaderboard; task checks and saves |
//! | [`play`] | the render queue (bounded, first come first served) and episodes streamed frame by frame as they are made |
//! | [`assets`] | the page itself (HTML, JavaScript, CSS), compiled into the binary |
//!
//! The app is a client of the library, not a fork of it: it resolves tasks and policies with the
//! registry and `benchmark::load`, plays with the one episode loop, renders with `render`, checks
//! tasks with `episode::check`, reads results with `benchmark::results` and writes with the one
//! writer. Its own code is routing, the queue and the page. It links no libtorch (it runs in the
//! `blockpuzzle` half of the command line) and uses no layer above it.

pub mod api;
pub mod assets;
pub mod files;
pub mod http;
pub mod play;

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use thiserror::Error;

/// The port `serve` listens on unless told (TensorBoard's is 6006; this is the next).
pub const DEFAULT_PORT: u16 = 6007;

/// What `serve` was started with.
#[derive(Debug, Clone)]
pub struct Options {
    /// The address to bind (127.0.0.1 unless told).
    pub bind: IpAddr,
    /// The port (0: any free one, what tests use).
    pub port: u16,
    /// Folders whose files the app may read (task and family files, policies, results); the first
    /// is where the editor saves.
    pub dirs: Vec<PathBuf>,
    /// Trained policies (files, run folders or zoo names) the page offers beside the solver,
    /// random actions and the zoo.
    pub policies: Vec<PathBuf>,
    /// Folders of suite results (`eval --suite` output) for the leaderboard.
    pub results: Vec<PathBuf>,
}

/// Why the app could not start.
#[derive(Debug, Error)]
pub enum ServeError {
    /// The address could not be bound.
    #[error("cannot listen on {addr}: {source}; give another port with --port N (0 picks a free one)")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A folder given that is not one.
    #[error("{}: {why}; give folders that exist (--dir DIR, --results DIR)", path.display())]
    Folder {
        /// The path.
        path: PathBuf,
        /// What is wrong.
        why: String,
    },
    /// A policy given that does not load.
    #[error("--policy {}: {source}", path.display())]
    Policy {
        /// The path.
        path: PathBuf,
        /// Why.
        #[source]
        source: crate::benchmark::load::LoadError,
    },
}

/// Whether binding `ip` makes the app reachable from other machines, and the warning that says who
/// can reach it (None for a loopback address).
pub fn exposure_warning(ip: IpAddr) -> Option<String> {
    if ip.is_loopback() {
        return None;
    }
    let who = if ip.is_unspecified() {
        "every machine that can reach any of this machine's addresses".to_owned()
    } else {
        format!("every machine that can reach {ip}")
    };
    Some(format!(
        "warning: serving on {ip}, not on loopback: {who} can browse the folders this app was started with, \
         play policies and save task files into its first folder. There is no authentication; bind 127.0.0.1 \
         (the default) unless that is what you want"
    ))
}

/// Starts the app: binds, starts the workers and the render queue, and returns at once with the
/// running server (its address, for a port of 0).
///
/// # Errors
/// [`ServeError`]: a port taken, a folder or policy that is not one.
pub fn start(options: Options) -> Result<http::Running, ServeError> {
    http::start(options)
}
