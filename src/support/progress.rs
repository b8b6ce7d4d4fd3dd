//! Progress of long commands, on stderr: a bar on a terminal; elsewhere (a log file, a pipe, a
//! batch job) a plain line every [`PLAIN_EVERY`] seconds or so, so that hours of work are never
//! silent.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Seconds between plain progress lines off a terminal, unless `BLOCKPUZZLE_PROGRESS_SECONDS`
/// says otherwise (a whole number; 0: a line at every step).
pub const PLAIN_EVERY: u64 = 30;

/// A progress report of `len` steps of `what`: an indicatif bar on a terminal, plain lines
/// elsewhere. Shareable across threads (`inc` takes `&self`).
pub struct Progress {
    bar: indicatif::ProgressBar,
    what: String,
    /// Off a terminal: when the last plain line was written, and how often to write one.
    plain: Option<(Mutex<Instant>, Duration)>,
}

/// A progress report of `len` steps named `what` on stderr.
pub fn bar(len: u64, what: &str) -> Progress {
    let plain = (!std::io::stderr().is_terminal()).then(|| (Mutex::new(Instant::now()), plain_every()));
    let bar = match plain {
        Some(_) => indicatif::ProgressBar::hidden(),
        None => indicatif::ProgressBar::new(len),
    };
    bar.set_length(len);
    let template = format!("{{bar:30}} {what} {{pos}}/{{len}} [{{elapsed_precise}} < {{eta_precise}}]");
    bar.set_style(
        indicatif::ProgressStyle::with_template(&template).unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Progress { bar, what: what.to_owned(), plain }
}

/// A report that shows nothing anywhere (a quiet caller's).
pub fn hidden() -> Progress {
    Progress { bar: indicatif::ProgressBar::hidden(), what: String::new(), plain: None }
}

/// The interval between plain lines: `BLOCKPUZZLE_PROGRESS_SECONDS` where it is a whole number.
fn plain_every() -> Duration {
    let seconds = std::env::var("BLOCKPUZZLE_PROGRESS_SECONDS").ok().and_then(|s| s.trim().parse().ok());
    Duration::from_secs(seconds.unwrap_or(PLAIN_EVERY))
}

impl Progress {
    /// Whether it reports in plain lines (a report shown off a terminal).
    pub fn is_plain(&self) -> bool {
        self.plain.is_some()
    }

    /// `n` more steps done.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
        let Some((last, every)) = &self.plain else { return };
        let Ok(mut last) = last.lock() else { return };
        if last.elapsed() >= *every {
            *last = Instant::now();
            eprintln!("{}", self.line());
        }
    }

    /// One plain line: where the work stands, how long it has taken and about how long is left.
    pub fn line(&self) -> String {
        let (pos, len) = (self.bar.position(), self.bar.length().unwrap_or(0));
        let elapsed = self.bar.elapsed().as_secs_f64();
        let left = match pos {
            0 => String::new(),
            _ => format!(", about {:.0} s left", elapsed * (len.saturating_sub(pos)) as f64 / pos as f64),
        };
        let percent = if len == 0 { 100.0 } else { 100.0 * pos as f64 / len as f64 };
        format!("{}: {pos} of {len} ({percent:.0}%) in {elapsed:.0} s{left}", self.what)
    }

    /// The work is over: the bar is cleared (off a terminal nothing more is written).
    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}
