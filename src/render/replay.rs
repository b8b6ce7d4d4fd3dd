//! Frames of a recorded episode: the stored `qpos` of every state is put
//! back into the environment's model and rendered, so the frames show
//! exactly the recorded trajectory.

use super::{output, Renderer, View};
use crate::env::{registry, BlockEnv, EnvConfig};
use crate::episode::rollout::EpisodeRecord;
use crate::sim::rules::Colour;
use image::RgbImage;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a recorded episode cannot be replayed or its frames written.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The episode's task cannot be made, or refuses its distribution, level or seed.
    #[error(transparent)]
    Env(#[from] crate::env::EnvError),
    /// Rendering is not available or failed.
    #[error(transparent)]
    Render(#[from] super::RenderError),
    /// The engine refused a recorded state or the scene's materials.
    #[error(transparent)]
    Mj(#[from] crate::sim::mj::MjError),
    /// The dump cannot be read.
    #[error(transparent)]
    Dump(#[from] crate::episode::rollout::RolloutError),
    /// The frames cannot be written.
    #[error(transparent)]
    Output(#[from] output::OutputError),
    /// The output path is not ours to write.
    #[error(transparent)]
    Target(#[from] crate::support::io::WriteError),
    /// The episode names one task and records another.
    #[error("the episode names task {named:?} but records the task {recorded:?}; the dump was edited")]
    OtherTask {
        /// The id the episode names.
        named: String,
        /// The id of the task it records.
        recorded: String,
    },
    /// The episode's objects are not its task's rule objects.
    #[error(
        "the episode's objects {recorded:?} are not its task's rule objects {names:?}; the dump was edited \
         (record it again with `blockpuzzle rollout`)"
    )]
    OtherObjects {
        /// The episode's objects, in its order.
        recorded: Vec<String>,
        /// The task's, sorted.
        names: Vec<String>,
    },
    /// An object recorded in another colour (or absent) than its task deals it.
    #[error(
        "the episode records object {object} as {recorded}, but its task deals it {dealt} at seed {seed}; the dump \
         was edited (record it again with `blockpuzzle rollout`)"
    )]
    OtherDeal {
        /// The object.
        object: String,
        /// Its recorded colour, or `absent`.
        recorded: String,
        /// The dealt one.
        dealt: String,
        /// The episode's seed.
        seed: u64,
    },
    /// A state of the wrong size.
    #[error("step {step} of the episode stores {stored} positions, {env_id} has {nq}")]
    StateSize {
        /// The step (0: the reset state).
        step: usize,
        /// The positions stored.
        stored: usize,
        /// The task.
        env_id: String,
        /// The positions of its model.
        nq: usize,
    },
    /// A joint position that is no state of the scene.
    #[error(
        "step {step} of the episode stores joint position {joint} as {value:e}, no state of the scene; the dump was \
         edited or damaged"
    )]
    BadPosition {
        /// The step.
        step: usize,
        /// The joint position's index.
        joint: usize,
        /// Its value.
        value: f64,
    },
    /// `--filmstrip` without a `.png` output.
    #[error("--filmstrip N writes a PNG: give --out FILE.png with N ≥ 1")]
    FilmstripNotPng,
    /// A GIF of 0 frames per second.
    #[error("--fps must be at least 1 (frames per second of the GIF)")]
    ZeroFps,
    /// `--max-frames` for another output than a GIF.
    #[error("--max-frames N keeps N frames of a GIF: give --out FILE.gif, without --filmstrip")]
    MaxFramesNotGif,
    /// `--max-frames` below 2.
    #[error("--max-frames {asked} keeps too few frames for an animation: give at least 2 (the first and last step)")]
    MaxFramesTooFew {
        /// What was asked.
        asked: usize,
    },
    /// A `.png` output without `--filmstrip`.
    #[error("{} is a PNG file: add --filmstrip N, or give a folder for one PNG per frame", path.display())]
    PngWithoutFilmstrip {
        /// The output.
        path: PathBuf,
    },
    /// An output of another kind.
    #[error(
        "--out {}: .{ext} is not written here; give FILE.gif (animation), FILE.png with --filmstrip N, \
         or a folder without an extension (one PNG per frame)",
        path.display()
    )]
    OtherKind {
        /// The output.
        path: PathBuf,
        /// Its extension.
        ext: String,
    },
    /// A folder output that exists and is not a folder.
    #[error(
        "--out {}: it exists and is not a folder; one PNG per frame goes into a folder: give a folder path, \
         FILE.gif (animation) or FILE.png with --filmstrip N",
        path.display()
    )]
    NotAFolder {
        /// The output.
        path: PathBuf,
    },
    /// An episode the dump does not hold.
    #[error("{} holds {count} episodes; --episode {index} does not exist", path.display())]
    NoEpisode {
        /// The dump.
        path: PathBuf,
        /// Its episodes.
        count: usize,
        /// The episode asked for.
        index: usize,
    },
}

/// The frames of `ep` (the reset state, then one per step) and the seconds
/// spent rendering them.
///
/// # Errors
/// Unknown environment id, a state of the wrong size, rendering errors.
pub fn episode_frames(ep: &EpisodeRecord, view: &View) -> Result<(Vec<RgbImage>, f64), ReplayError> {
    let task = match &ep.task {
        Some(source) => registry::recorded(source)?,
        None => registry::task(&ep.env_id)?,
    };
    let mut env = BlockEnv::new(EnvConfig::new(task))?;
    // The record must be of this task: its id and its rule objects (in the
    // episode's order, which a task that shuffles roles deals anew).
    if ep.env_id != env.id() {
        return Err(ReplayError::OtherTask { named: ep.env_id.clone(), recorded: env.id().to_owned() });
    }
    let mut names: Vec<&str> = env.objects().iter().map(|o| o.name.as_str()).collect();
    let recorded: Vec<&str> = ep.objects.iter().map(|o| o.name.as_str()).collect();
    let mut sorted = recorded.clone();
    names.sort_unstable();
    sorted.sort_unstable();
    if names != sorted {
        let owned = |v: &[&str]| v.iter().map(|s| (*s).to_owned()).collect();
        return Err(ReplayError::OtherObjects { recorded: owned(&recorded), names: owned(&names) });
    }
    // Its colours and absent objects are dealt at reset from its seed (and distribution and level):
    // a record that differs (blue marked absent beside a "success") is not this episode.
    env.set_distribution(ep.distribution.as_deref().or(ep.challenge.then_some("challenge")))?;
    env.set_level(ep.level)?;
    env.reset(Some(ep.seed))?;
    let dealt = env.objects().iter().zip(env.absent_objects());
    for (o, (d, absent)) in ep.objects.iter().zip(dealt) {
        if (o.name.as_str(), o.colour, o.absent) != (d.name.as_str(), d.colour, absent) {
            let state = |c: Colour, absent: bool| if absent { "absent".to_owned() } else { c.name().to_owned() };
            return Err(ReplayError::OtherDeal {
                object: o.name.clone(),
                recorded: state(o.colour, o.absent),
                dealt: state(d.colour, absent),
                seed: ep.seed,
            });
        }
    }
    let nq = env.data().qpos().len();
    let model = env.data().model().clone();
    let mut renderer = Renderer::new(&model, view)?;
    // The episode's colours (they move between episodes when the task shuffles roles).
    let colours: Vec<Colour> = ep.objects.iter().map(|o| o.colour).collect();
    let absent: Vec<bool> = ep.objects.iter().map(|o| o.absent).collect();
    renderer.colour_objects(env.scene(), &colours, &absent)?;
    let n = ep.steps.len();
    let outcome = if ep.success {
        "success"
    } else if ep.failure {
        "failure"
    } else {
        ""
    };
    let mut frames = Vec::with_capacity(n + 1);
    let started = Instant::now();
    for k in 0..=n {
        let state = if k == 0 { &ep.initial } else { &ep.steps[k - 1].state };
        if state.qpos.len() != nq {
            return Err(ReplayError::StateSize { step: k, stored: state.qpos.len(), env_id: ep.env_id.clone(), nq });
        }
        // A joint position beyond 10 km or 10⁴ rad is no state of the scene.
        if let Some(i) = state.qpos.iter().position(|v| v.is_nan() || v.abs() > 1e4) {
            return Err(ReplayError::BadPosition { step: k, joint: i, value: state.qpos[i] });
        }
        let data = env.data_mut();
        data.qpos_mut().copy_from_slice(&state.qpos);
        data.forward()?;
        let reached = if k == n { outcome } else { "" };
        let caption = (format!("{}\nstep\n{reached}", ep.env_id), format!("\n{k}/{n}\n"));
        let caption = renderer.view().caption.then_some((caption.0.as_str(), caption.1.as_str()));
        frames.push(renderer.render(env.data_mut(), caption));
    }
    Ok((frames, started.elapsed().as_secs_f64()))
}

/// Where frames go: an animated GIF, a filmstrip PNG, or a folder of PNGs.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// `.gif`: animated, looping, at the given frames per second; with `max_frames`, at most that
    /// many evenly spaced frames, the first and last included.
    Gif {
        /// Frames per second.
        fps: u32,
        /// The most frames it keeps (all where `None`).
        max_frames: Option<usize>,
    },
    /// A PNG of this many evenly spaced frames side by side.
    Filmstrip(usize),
    /// A folder of `frame_00000.png`, ...
    Folder,
}

impl Output {
    /// The output kind for `out` and the `--filmstrip`, `--fps` and `--max-frames` options.
    ///
    /// # Errors
    /// A filmstrip not written to `.png`, a `.png` without `--filmstrip`, a
    /// GIF at 0 frames per second, `--max-frames` below 2 or for another output than a GIF, or a
    /// file name of another kind (an extension other than `.gif` or `.png` on a path that is not a
    /// folder).
    pub fn for_path(
        out: &Path,
        filmstrip: Option<usize>,
        fps: u32,
        max_frames: Option<usize>,
    ) -> Result<Self, ReplayError> {
        let ext = out.extension().map(|e| e.to_string_lossy().to_lowercase());
        if let Some(n) = max_frames {
            if ext.as_deref() != Some("gif") || filmstrip.is_some() {
                return Err(ReplayError::MaxFramesNotGif);
            }
            if n < 2 {
                return Err(ReplayError::MaxFramesTooFew { asked: n });
            }
        }
        match (ext.as_deref(), filmstrip) {
            (Some("png"), Some(n)) if n > 0 => Ok(crate::support::io::check_output(out).map(|_| Self::Filmstrip(n))?),
            (_, Some(_)) => Err(ReplayError::FilmstripNotPng),
            (Some("gif"), None) if fps == 0 => Err(ReplayError::ZeroFps),
            (Some("gif"), None) => Ok(crate::support::io::check_output(out).map(|_| Self::Gif { fps, max_frames })?),
            (Some("png"), None) => Err(ReplayError::PngWithoutFilmstrip { path: out.to_owned() }),
            (Some(other), None) if !out.is_dir() => {
                Err(ReplayError::OtherKind { path: out.to_owned(), ext: other.to_owned() })
            }
            _ if out.symlink_metadata().is_ok_and(|m| !m.is_dir()) && !out.is_dir() => {
                Err(ReplayError::NotAFolder { path: out.to_owned() })
            }
            _ => Ok(Self::Folder),
        }
    }

    /// Writes `frames` to `out`.
    ///
    /// # Errors
    /// I/O and encoding errors.
    pub fn write(&self, out: &Path, frames: &[RgbImage]) -> Result<(), output::OutputError> {
        match self {
            Self::Gif { fps, max_frames: None } => output::gif(out, frames, *fps),
            Self::Gif { fps, max_frames: Some(n) } => {
                let kept: Vec<RgbImage> =
                    output::filmstrip_indices(frames.len(), *n).into_iter().map(|k| frames[k].clone()).collect();
                output::gif(out, &kept, *fps)
            }
            Self::Filmstrip(n) => output::filmstrip(out, frames, *n),
            Self::Folder => output::png_folder(out, frames),
        }
    }
}

/// Renders episode `index` of the dump at `traj` to `out`; returns (frames, frames per second).
///
/// # Errors
/// Unreadable dump, missing episode, rendering or writing errors.
pub fn render_dump(
    traj: &Path,
    index: usize,
    view: &View,
    out: &Path,
    kind: &Output,
) -> Result<(usize, f64), ReplayError> {
    let episodes = crate::episode::rollout::read_dump(traj)?;
    let Some(ep) = episodes.get(index) else {
        return Err(ReplayError::NoEpisode { path: traj.to_owned(), count: episodes.len(), index });
    };
    let (frames, seconds) = episode_frames(ep, view)?;
    kind.write(out, &frames)?;
    Ok((frames.len(), frames.len() as f64 / seconds.max(1e-9)))
}
