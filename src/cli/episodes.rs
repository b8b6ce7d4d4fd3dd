//! The commands that play and show episodes: `rollout` (a trajectory dump, optionally rendered)
//! and `render` (a dump's episode, or a policy's), with the camera and movie flags they share.

use crate::env::{registry, BlockEnv};
use crate::episode::outcome::{Outcome, Outcomes};
use crate::episode::rollout::{run_episode, DumpWriter};
use crate::support::limits::Bound;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// Frame width and height in pixels.
pub const FRAME_PIXELS: Bound =
    Bound::new("--width/--height", 1, 16_384, "the renderer then checks the model's offscreen buffer");
/// GIF frames per second.
pub const FPS: Bound = Bound::new("--fps", 1, 100, "GIF frame delays are whole hundredths of a second");
/// Frames a GIF keeps at most.
pub const GIF_FRAMES: Bound = Bound::new("--max-frames", 2, 100_000, "");
/// Frames of a filmstrip.
pub const FILMSTRIP: Bound =
    Bound::new("--filmstrip", 1, 64, "a strip is one row of frames: 64 frames of 480 px are 30,720 px wide");

/// `blockpuzzle demos`.
#[derive(Debug, clap::Args)]
pub(super) struct DemosArgs {
    /// Built-in suite name or suite file (.toml) whose rows are played. The help lists the built-in names.
    #[arg(long, help = format!(
        "Built-in suite name ({}) or suite file (.toml) whose rows are played",
        crate::benchmark::suite::builtin_names()
    ))]
    suite: String,
    /// The split whose rows are played (train, test, ...).
    #[arg(long, default_value = "train")]
    split: String,
    /// Episodes per row, from the row's seed on (default: the row's own count).
    #[arg(long, value_parser = crate::support::limits::EVAL_EPISODES.parser::<usize>())]
    episodes: Option<usize>,
    /// Threads, each with its own environment (default: the machine's cores); the same episodes whatever the count.
    #[arg(long, value_parser = crate::support::limits::THREADS.parser::<usize>())]
    threads: Option<usize>,
    /// Output file (safetensors); written atomically.
    #[arg(long)]
    out: PathBuf,
}

/// `blockpuzzle demos`: the solver's episodes on a suite split, for imitation and offline RL.
pub(super) fn demos(a: DemosArgs) -> Result<()> {
    let suite = crate::benchmark::suite::load(&a.suite)?;
    let threads = a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let d = crate::benchmark::demos::record_to(
        &a.out,
        &suite,
        &a.split,
        a.episodes,
        threads,
        crate::benchmark::provenance::Harness::Cli,
    )?;
    println!(
        "{} episodes ({} steps, {} rows of {} entities) of suite {} split {}, the solver's success {:.3} -> {}",
        d.episodes.len(),
        d.steps(),
        d.observations(),
        d.layout.rows,
        suite.name,
        a.split,
        d.successes() as f64 / d.episodes.len().max(1) as f64,
        a.out.display()
    );
    Ok(())
}

#[derive(Debug, clap::Args)]
pub(super) struct RolloutArgs {
    /// Environment id (see `blockpuzzle envs`) or task file (.toml).
    #[arg(long)]
    env: String,
    /// Which policy acts: `random` (seeded by --seed), a baseline (`scripted`, `obs-hash`), or a
    /// trained policy (file, run directory or zoo name).
    #[arg(long, default_value = "scripted")]
    policy: String,
    /// Number of episodes.
    #[arg(long, default_value_t = 10, value_parser = crate::support::limits::ROLLOUT_EPISODES.parser::<usize>())]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Curriculum level (default: the maximum, i.e. the evaluation distribution).
    #[arg(long, conflicts_with_all = ["challenge", "distribution"], value_parser = crate::support::limits::COUNT.parser::<usize>())]
    level: Option<usize>,
    /// Use the challenge distribution (the same as --distribution challenge).
    #[arg(long, conflicts_with = "distribution")]
    challenge: bool,
    /// Use a named evaluation distribution of the task file ([distributions.NAME]).
    #[arg(long)]
    distribution: Option<String>,
    /// The observation the environment presents (flat, objects, entities): what `random` and
    /// `obs-hash` act on (default: flat). The solver (`scripted`) reads the `entities` one and a
    /// trained policy its own.
    #[arg(long)]
    obs_mode: Option<crate::env::ObsMode>,
    /// Output file (JSON Lines); written atomically.
    #[arg(long)]
    out: PathBuf,
    /// Also render the first episode: FILE.gif, FILE.png with --filmstrip N, or a folder.
    #[arg(long)]
    render: Option<PathBuf>,
    #[command(flatten)]
    view: ViewArgs,
    #[command(flatten)]
    movie: MovieArgs,
}

/// Frame size and camera (the Fetch viewer's by default).
#[derive(Debug, Clone, clap::Args)]
pub(super) struct ViewArgs {
    /// Frame width in pixels.
    #[arg(long, default_value_t = 480, value_parser = FRAME_PIXELS.parser::<usize>())]
    width: usize,
    /// Frame height in pixels.
    #[arg(long, default_value_t = 480, value_parser = FRAME_PIXELS.parser::<usize>())]
    height: usize,
    /// Camera distance from the point it looks at (m).
    #[arg(long, default_value_t = 2.5)]
    distance: f64,
    /// Camera azimuth (degrees).
    #[arg(long, default_value_t = 132.0)]
    azimuth: f64,
    /// Camera elevation (degrees, negative looks down).
    #[arg(long, default_value_t = -14.0, allow_negative_numbers = true)]
    elevation: f64,
    /// Leave out the caption (task, step, outcome) that each frame carries in its corner.
    #[arg(long)]
    no_caption: bool,
}

/// What a rendered episode is written as (`rollout --render`, `render`).
#[derive(Debug, Clone, clap::Args)]
pub(super) struct MovieArgs {
    /// Frames per second of a GIF.
    #[arg(long, default_value_t = 10, value_parser = FPS.parser::<u32>())]
    fps: u32,
    /// Write a filmstrip PNG of this many evenly spaced frames (--out FILE.png).
    #[arg(long, value_parser = FILMSTRIP.parser::<usize>())]
    filmstrip: Option<usize>,
    /// A GIF of at most this many evenly spaced frames, the first and last included (a smaller
    /// file that plays the episode faster at the same --fps).
    #[arg(long, value_parser = GIF_FRAMES.parser::<usize>())]
    max_frames: Option<usize>,
}

impl MovieArgs {
    /// What `out` is written as.
    fn output(&self, out: &std::path::Path) -> Result<crate::render::replay::Output> {
        Ok(crate::render::replay::Output::for_path(out, self.filmstrip, self.fps, self.max_frames)?)
    }
}

impl ViewArgs {
    /// The camera, checked (a command checks it before any work).
    pub(super) fn view(&self) -> Result<crate::render::View> {
        let view = crate::render::View {
            width: self.width,
            height: self.height,
            distance: self.distance,
            azimuth: self.azimuth,
            elevation: self.elevation,
            caption: !self.no_caption,
            ..Default::default()
        };
        view.check().map_err(anyhow::Error::msg)?;
        Ok(view)
    }
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["traj", "policy"])))]
pub(super) struct RenderArgs {
    /// Trajectory dump written by `rollout` (JSON Lines).
    #[arg(long)]
    traj: Option<PathBuf>,
    /// Which episode of the dump (0-based).
    #[arg(long, default_value_t = 0, requires = "traj", value_parser = crate::support::limits::COUNT.parser::<usize>())]
    episode: usize,
    /// Or play one episode of a trained policy (file, run directory or zoo name) and render it.
    #[arg(long)]
    policy: Option<PathBuf>,
    /// With --policy: the task (default: the one the policy was trained on).
    #[arg(long, requires = "policy")]
    env: Option<String>,
    /// With --policy: the episode's seed.
    #[arg(long, default_value_t = crate::benchmark::evaluate::TEST_SEED, requires = "policy", value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// With --policy: the challenge distribution.
    #[arg(long, requires = "policy")]
    challenge: bool,
    /// Output: FILE.gif (animation), FILE.png with --filmstrip N, or a folder (one PNG per frame).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    view: ViewArgs,
    #[command(flatten)]
    movie: MovieArgs,
}

/// `blockpuzzle rollout`.
pub(super) fn rollout(a: RolloutArgs) -> Result<()> {
    // Check the --render output before spending time on the episodes.
    let render_kind = a.render.as_deref().map(|out| a.movie.output(out)).transpose()?;
    if a.render.is_some() {
        a.view.view()?;
    }
    // A trained policy is loaded first: the environment shows its layout (its observation mode and,
    // for one of several tasks, its training tasks' block slots).
    let named = crate::benchmark::load::resolve(Path::new(&a.policy))?;
    let mut config = registry::config(&a.env)?;
    config.obs_mode = a.obs_mode.unwrap_or_default();
    if let crate::benchmark::load::Named::Saved(_, saved) = &named {
        let reads = saved.obs_mode();
        if let Some(mode) = a.obs_mode.filter(|&m| m != reads) {
            bail!("policy {} reads the `{reads}` observation, not the `{mode}` one: leave --obs-mode out", a.policy);
        }
    }
    named.fit(&mut config)?;
    let mut env = BlockEnv::new(config)?;
    if a.challenge {
        env.set_challenge(true)?;
    }
    env.set_distribution(a.distribution.as_deref().or(a.challenge.then_some("challenge")))?;
    let level = a.level.unwrap_or(env.max_level());
    env.set_level(level)?;
    crate::support::limits::seed_range(a.seed, a.episodes as u64).map_err(anyhow::Error::msg)?;
    let mut writer = DumpWriter::create(&a.out)?;
    let mut policy = named.into_player(&env, a.seed)?;
    let (mut outcomes, mut steps) = (Outcomes::default(), 0usize);
    for k in 0..a.episodes {
        let seed = a.seed + k as u64;
        let ep = run_episode(&mut env, policy.as_mut(), seed).with_context(|| format!("episode {k} (seed {seed})"))?;
        outcomes.add(Outcome::of(&ep));
        steps += ep.steps.len();
        writer.write(&ep)?;
    }
    writer.finish()?;
    if let (Some(out), Some(kind)) = (&a.render, &render_kind) {
        // The dump is whole by now: a failed rendering keeps it and says so.
        let (frames, fps) =
            crate::render::replay::render_dump(&a.out, 0, &a.view.view()?, out, kind).with_context(|| {
                format!(
                    "the episodes are saved in {}, but --render failed; render them with \
                     `blockpuzzle render --traj {}` once rendering works",
                    a.out.display(),
                    a.out.display()
                )
            })?;
        println!("rendered episode 0: {frames} frames ({fps:.1} frames/s) -> {}", out.display());
    }
    let n = a.episodes as f64;
    println!(
        "{} {} policy, level {}{}: success {:.3} ({}/{}), mean length {:.1}; not successful: {}; wrote {}",
        a.env,
        a.policy,
        level,
        env.distribution_name().map_or(String::new(), |d| format!(" ({d})")),
        outcomes.success as f64 / n,
        outcomes.success,
        a.episodes,
        steps as f64 / n,
        outcomes.summary(),
        a.out.display()
    );
    Ok(())
}

pub(super) fn render(a: RenderArgs) -> Result<()> {
    let kind = a.movie.output(&a.out)?;
    let view = a.view.view()?;
    let (frames, fps, what) = match (&a.traj, &a.policy) {
        (Some(traj), _) => {
            let (frames, fps) = crate::render::replay::render_dump(traj, a.episode, &view, &a.out, &kind)?;
            (frames, fps, format!("episode {}", a.episode))
        }
        (None, Some(path)) => {
            let saved = crate::benchmark::load::load_policy(path)?;
            let task = policy_task(a.env.as_deref(), &saved)?;
            let (obs_mode, slots) = (saved.obs_mode(), saved.slots()?);
            let mut env = BlockEnv::new(crate::env::EnvConfig { obs_mode, slots, ..crate::env::EnvConfig::new(task) })?;
            env.set_distribution(a.challenge.then_some("challenge"))?;
            let level = env.max_level();
            env.set_level(level)?;
            let mut policy = crate::benchmark::evaluate::trained_policy(path, saved, &env)?;
            let ep = run_episode(&mut env, &mut policy, a.seed)?;
            let (frames, seconds) = crate::render::replay::episode_frames(&ep, &view)?;
            kind.write(&a.out, &frames)?;
            let outcome = if ep.success {
                "success"
            } else if ep.failure {
                "failure"
            } else {
                "neither"
            };
            (frames.len(), frames.len() as f64 / seconds.max(1e-9), format!("seed {} ({outcome})", a.seed))
        }
        (None, None) => bail!("give --traj DUMP or --policy POLICY"),
    };
    println!(
        "rendered {frames} frames of {what} at {}x{} ({fps:.1} frames/s) -> {}",
        a.view.width,
        a.view.height,
        a.out.display()
    );
    Ok(())
}

/// The task to run a policy on: the one named, else the one it was trained
/// on (its recorded copy if the file moved or changed).
pub(super) fn policy_task(
    env: Option<&str>,
    saved: &crate::benchmark::saved::SavedPolicy,
) -> Result<crate::task::Task> {
    Ok(match (env, &saved.task) {
        (Some(env), _) => registry::task(env)?,
        (None, Some(source)) => registry::recorded(source)?,
        (None, None) => match registry::task(&saved.env_id) {
            Ok(task) => task,
            // A multi-task run's policy names its tasks (`SUITE-SPLIT`, or ids joined by `+`), no one task.
            Err(_) if !registry::is_path(&saved.env_id) => bail!(
                "the policy was trained on several tasks ({}) and holds no one task: pass --env ID (or evaluate a \
                 suite with eval --suite S)",
                saved.env_id
            ),
            Err(e) => return Err(e.into()),
        },
    })
}
