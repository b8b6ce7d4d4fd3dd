//! The hard limits on numbers a user gives to the core (task-file fields, evaluation, rollouts,
//! suites, the files it reads) and the [`Bound`] type every limit is written with. Each bound is
//! written once, with why it exists; those of training and rendering are written beside the
//! settings they bound (`learn::train`, `learn::agents`, `learn::bench`, `benchmark::throughput`, `render`, the CLI's
//! render flags). Each is checked
//! before anything is created or allocated: by the command line's parsers
//! ([`Bound::parse`], which also turns `--episodes -3` into a message naming
//! the flag and its range) and again by the configs' own validation
//! ([`Bound::check`]), which library callers go through too.

use std::fmt;

/// An inclusive range of whole numbers for one setting, and why it ends there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bound {
    /// The setting as the user writes it (`--workers`, `max_episode_steps`).
    pub name: &'static str,
    /// Smallest allowed value.
    pub min: u64,
    /// Largest allowed value.
    pub max: u64,
    /// Why the range ends there (empty: any value of the type).
    pub why: &'static str,
}

/// `1,000,000` for 1000000.
fn grouped(v: u64) -> String {
    let s = v.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

impl fmt::Display for Bound {
    /// `1 to 1,000,000 (why)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} to {}", grouped(self.min), grouped(self.max))?;
        if !self.why.is_empty() {
            write!(f, " ({})", self.why)?;
        }
        Ok(())
    }
}

impl Bound {
    /// Whether `v` is in range; the error names the setting, the value and the range.
    ///
    /// # Errors
    /// A value outside `min..=max`.
    pub fn check(&self, v: u64) -> Result<(), String> {
        if (self.min..=self.max).contains(&v) {
            Ok(())
        } else {
            Err(format!("{} = {}: allowed are {self}", self.name, grouped(v)))
        }
    }

    /// As [`Bound::check`] for a `usize`.
    ///
    /// # Errors
    /// A value outside `min..=max`.
    pub fn check_usize(&self, v: usize) -> Result<(), String> {
        self.check(v as u64)
    }

    /// Parses a command-line value: a whole number in range. Used as clap's
    /// value parser, whose error names the flag and the value given.
    ///
    /// # Errors
    /// Not a whole number (a negative one included), or out of range.
    pub fn parse<T: TryFrom<u64>>(&self, s: &str) -> Result<T, String> {
        let v: u64 = s.trim().parse().map_err(|_| format!("give a whole number from {self}"))?;
        if !(self.min..=self.max).contains(&v) {
            return Err(format!("allowed are {self}"));
        }
        T::try_from(v).map_err(|_| format!("allowed are {self}"))
    }

    /// [`Bound::parse`] as clap's value parser (`value_parser = WORKERS.parser::<usize>()`).
    pub fn parser<T: TryFrom<u64>>(self) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
        move |s: &str| self.parse(s)
    }
}

impl Bound {
    /// The bound of `name`: `min..=max`, ending there for `why`.
    pub const fn new(name: &'static str, min: u64, max: u64, why: &'static str) -> Self {
        Bound { name, min, max, why }
    }
}

const fn bound(name: &'static str, min: u64, max: u64, why: &'static str) -> Bound {
    Bound::new(name, min, max, why)
}

/// A count with no bound of its own (a level, an index, a period).
pub const COUNT: Bound = bound("", 0, u32::MAX as u64, "");
/// A seed: any 64-bit value.
pub const SEED: Bound = bound("--seed", 0, u64::MAX, "");
/// Episodes of an evaluation (`eval`, `table`, `zoo export --evaluate`).
pub const EVAL_EPISODES: Bound =
    bound("--episodes", 1, 1_000_000, "a success rate's 95% interval is ±0.001 at a million episodes");
/// Episodes of each evaluation of `zoo export --evaluate` (0: none).
pub const EXPORT_EPISODES: Bound =
    bound("--evaluate", 0, 1_000_000, "0: no evaluation; a 95% interval is ±0.001 at a million episodes");
/// Episodes of a trajectory dump (`rollout`).
pub const ROLLOUT_EPISODES: Bound =
    bound("--episodes", 1, 100_000, "every episode adds about 50 kB to the dump: 100,000 make about 5 GB");
/// Resets per level and distribution of `task check`.
pub const CHECK_SAMPLES: Bound =
    bound("--samples", 1, 100_000, "per level and distribution; 100,000 estimate a redraw rate to ±0.3%");
/// Tasks of one `task generate`.
pub const GENERATE_COUNT: Bound =
    bound("--count", 1, 100_000, "each task is checked by the solver's episodes: 100,000 take hours");
/// Steps per thread of `bench` and `align --bench-steps`.
pub const BENCH_STEPS: Bound = bound("--steps", 1, 10_000_000, "about an hour of stepping per thread");
/// Threads of evaluations and benchmarks, each with its own environment.
pub const THREADS: Bound =
    bound("--threads", 1, 256, "each thread steps its own MuJoCo environment; more than the cores only wait");
/// Environments of one vector environment (Python's `VecEnv`).
pub const NUM_ENVS: Bound =
    bound("num_envs", 1, 4_096, "each environment holds its own MuJoCo model and data, a few MB");
/// Steps of one episode (task files).
pub const EPISODE_STEPS: Bound =
    bound("max_episode_steps", 1, 10_000, "200 times the paper's 50; evaluation and replay hold whole episodes");
/// Layout draws and whole resets tried before a reset gives up (task files).
pub const PLACEMENT_ATTEMPTS: Bound = bound("placement attempts", 1, 100_000, "a reset must end");

/// Input files are read whole, so each kind has a size bound (bytes) that a
/// real file stays far below and that keeps memory and echoed excerpts small.
/// Task files, suites, recipes: the largest built-in is about 4 KiB.
pub const TEXT_FILE_BYTES: u64 = 4 << 20;
/// Result files and zoo metadata: a suite result of 1,000 rows is about 2 MiB.
pub const RESULT_FILE_BYTES: u64 = 64 << 20;
/// Policy files and zoo tensors: a policy of 8 layers of 8,192 units (the
/// `--hidden` and `--layers` bounds' corner) as JSON text is about 6 GiB, so
/// this bounds memory, not what training can make; the zoo's largest is 2 MiB.
pub const POLICY_FILE_BYTES: u64 = 2 << 30;
/// Trajectory dumps: 10,000 episodes of 50 steps are about 1 GiB.
pub const DUMP_FILE_BYTES: u64 = 4 << 30;

/// The longest line of a message shown to a user: an excerpt of an input
/// (a parser's echo of the offending line) is cut there.
pub const MESSAGE_LINE_CHARS: usize = 2_000;

/// `text` with every line longer than [`MESSAGE_LINE_CHARS`] cut short and
/// saying how much was left out.
pub fn cut_long_lines(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(64 << 10));
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        match line.char_indices().nth(MESSAGE_LINE_CHARS) {
            Some((at, _)) => {
                out.push_str(&line[..at]);
                out.push_str(&format!("… ({} more characters)", line[at..].chars().count()));
            }
            None => out.push_str(line),
        }
    }
    out
}

/// Object sizes in a task file: half extents in metres.
pub const HALF_EXTENT_M: (f64, f64) = (0.001, 0.5);
/// Object masses in a task file, kg.
pub const MASS_KG: (f64, f64) = (0.001, 1_000.0);
/// Friction coefficients in a task file.
pub const FRICTION: (f64, f64) = (0.0, 10.0);
/// Settling time of a reset, seconds of simulated time.
pub const SETTLE_SECONDS: (f64, f64) = (0.0, 10.0);

/// Whether `v` lies in the closed range `r` (NaN never does).
pub fn within(v: f64, r: (f64, f64)) -> bool {
    v >= r.0 && v <= r.1
}

/// The seeds of `n` episodes from `first` (episode k: first + k) must not pass
/// 2⁶⁴ − 1, where they would wrap to 0, 1, … and repeat other episodes.
///
/// # Errors
/// A range that wraps, naming the largest first seed that fits.
pub fn seed_range(first: u64, n: u64) -> Result<(), String> {
    if n == 0 || first.checked_add(n - 1).is_some() {
        Ok(())
    } else {
        Err(format!(
            "--seed {first} with {n} seeds (episode or reset k uses seed + k) passes the largest seed \
             18446744073709551615; give --seed {} or less",
            u64::MAX - (n - 1)
        ))
    }
}

/// A fraction in [0, 1] given on the command line (`report --target`).
///
/// # Errors
/// Not a number, NaN, or outside [0, 1].
pub fn parse_fraction(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err("give a number from 0 to 1 (a success rate)".into()),
    }
}

/// The machine's memory in bytes (`MemTotal` of /proc/meminfo), if known.
pub fn memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// `12.3 GB` for a byte count.
pub fn gigabytes(bytes: u64) -> String {
    format!("{:.1} GB", bytes as f64 / 1e9)
}

/// Whether `hash` has the form of a content hash as this project writes them: `sha256:` and 64
/// lower-case hex digits. A record whose hash lacks it was damaged or hand-written, which a message
/// says rather than calling the content edited.
pub fn is_sha256(hash: &str) -> bool {
    hash.strip_prefix("sha256:")
        .is_some_and(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_name_the_setting_and_the_range() {
        assert_eq!(THREADS.parse::<usize>("12"), Ok(12));
        let e = THREADS.parse::<usize>("-3").unwrap_err();
        assert!(e.contains("whole number from 1 to 256"), "{e}");
        let e = THREADS.parse::<usize>("100000").unwrap_err();
        assert!(e.contains("allowed are 1 to 256") && e.contains("cores"), "{e}");
        let e = EPISODE_STEPS.check(1_000_000_000_000).unwrap_err();
        assert!(e.starts_with("max_episode_steps = 1,000,000,000,000: allowed are 1 to 10,000"), "{e}");
        assert_eq!(SEED.parse::<u64>("18446744073709551615"), Ok(u64::MAX));
        assert!(SEED.parse::<u64>("-1").unwrap_err().contains("0 to 18,446,744,073,709,551,615"));
    }

    #[test]
    fn seed_ranges_never_wrap() {
        assert!(seed_range(u64::MAX, 1).is_ok());
        assert!(seed_range(0, u64::MAX).is_ok());
        let e = seed_range(u64::MAX, 2).unwrap_err();
        assert!(e.contains("give --seed 18446744073709551614 or less"), "{e}");
    }

    #[test]
    fn fractions_are_finite_and_in_the_unit_interval() {
        assert_eq!(parse_fraction("0.95"), Ok(0.95));
        for bad in ["2", "NaN", "-0.1", "inf", "x"] {
            assert!(parse_fraction(bad).is_err(), "{bad}");
        }
    }
}
