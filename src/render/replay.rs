//! Frames of a recorded episode: the stored `qpos` of every state is put
//! back into the environment's model and rendered, so the frames show
//! exactly the recorded trajectory.

use super::{output, Renderer, View};
use crate::env::{registry, BlockEnv, EnvConfig};
use crate::episode::rollout::EpisodeRecord;
use crate::sim::rules::Colour;
use anyhow::{bail, Result};
use image::RgbImage;
use std::path::Path;
use std::time::Instant;

/// The frames of `ep` (the reset state, then one per step) and the seconds
/// spent rendering them.
///
/// # Errors
/// Unknown environment id, a state of the wrong size, rendering errors.
pub fn episode_frames(ep: &EpisodeRecord, view: &View) -> Result<(Vec<RgbImage>, f64)> {
    let task = match &ep.task {
        Some(source) => registry::recorded(source)?,
        None => registry::task(&ep.env_id)?,
    };
    let mut env = BlockEnv::new(EnvConfig::new(task))?;
    // The record must be of this task: its id and its rule objects (in the
    // episode's order, which a task that shuffles roles deals anew).
    if ep.env_id != env.id() {
        bail!("the episode names task {:?} but records the task {:?}; the dump was edited", ep.env_id, env.id());
    }
    let mut names: Vec<&str> = env.objects().iter().map(|o| o.name.as_str()).collect();
    let recorded: Vec<&str> = ep.objects.iter().map(|o| o.name.as_str()).collect();
    let mut sorted = recorded.clone();
    names.sort_unstable();
    sorted.sort_unstable();
    if names != sorted {
        bail!(
            "the episode's objects {recorded:?} are not its task's rule objects {names:?}; the dump was edited \
             (record it again with `blockpuzzle rollout`)"
        );
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
            bail!(
                "the episode records object {} as {}, but its task deals it {} at seed {}; the dump was edited \
                 (record it again with `blockpuzzle rollout`)",
                o.name,
                state(o.colour, o.absent),
                state(d.colour, absent),
                ep.seed
            );
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
            bail!("step {k} of the episode stores {} positions, {} has {nq}", state.qpos.len(), ep.env_id);
        }
        // A joint position beyond 10 km or 10⁴ rad is no state of the scene.
        if let Some(i) = state.qpos.iter().position(|v| v.is_nan() || v.abs() > 1e4) {
            bail!(
                "step {k} of the episode stores joint position {i} as {:e}, no state of the scene; the dump was \
                 edited or damaged",
                state.qpos[i]
            );
        }
        let data = env.data_mut();
        data.qpos_mut().copy_from_slice(&state.qpos);
        data.forward()?;
        let reached = if k == n { outcome } else { "" };
        let caption = (format!("{}\nstep\n{reached}", ep.env_id), format!("\n{k}/{n}\n"));
        frames.push(renderer.render(env.data_mut(), Some((&caption.0, &caption.1))));
    }
    Ok((frames, started.elapsed().as_secs_f64()))
}

/// Where frames go: an animated GIF, a filmstrip PNG, or a folder of PNGs.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// `.gif`: animated, looping, at the given frames per second.
    Gif { fps: u32 },
    /// A PNG of this many evenly spaced frames side by side.
    Filmstrip(usize),
    /// A folder of `frame_00000.png`, ...
    Folder,
}

impl Output {
    /// The output kind for `out` and the `--filmstrip` option.
    ///
    /// # Errors
    /// A filmstrip not written to `.png`, a `.png` without `--filmstrip`, a
    /// GIF at 0 frames per second, or a file name of another kind (an
    /// extension other than `.gif` or `.png` on a path that is not a folder).
    pub fn for_path(out: &Path, filmstrip: Option<usize>, fps: u32) -> Result<Self> {
        let ext = out.extension().map(|e| e.to_string_lossy().to_lowercase());
        match (ext.as_deref(), filmstrip) {
            (Some("png"), Some(n)) if n > 0 => Ok(crate::support::io::check_output(out).map(|_| Self::Filmstrip(n))?),
            (_, Some(_)) => bail!("--filmstrip N writes a PNG: give --out FILE.png with N ≥ 1"),
            (Some("gif"), None) if fps == 0 => bail!("--fps must be at least 1 (frames per second of the GIF)"),
            (Some("gif"), None) => Ok(crate::support::io::check_output(out).map(|_| Self::Gif { fps })?),
            (Some("png"), None) => {
                bail!("{} is a PNG file: add --filmstrip N, or give a folder for one PNG per frame", out.display())
            }
            (Some(other), None) if !out.is_dir() => bail!(
                "--out {}: .{other} is not written here; give FILE.gif (animation), FILE.png with --filmstrip N, \
                 or a folder without an extension (one PNG per frame)",
                out.display()
            ),
            _ if out.symlink_metadata().is_ok_and(|m| !m.is_dir()) && !out.is_dir() => bail!(
                "--out {}: it exists and is not a folder; one PNG per frame goes into a folder: give a folder path, \
                 FILE.gif (animation) or FILE.png with --filmstrip N",
                out.display()
            ),
            _ => Ok(Self::Folder),
        }
    }

    /// Writes `frames` to `out`.
    ///
    /// # Errors
    /// I/O and encoding errors.
    pub fn write(&self, out: &Path, frames: &[RgbImage]) -> Result<()> {
        match self {
            Self::Gif { fps } => output::gif(out, frames, *fps),
            Self::Filmstrip(n) => output::filmstrip(out, frames, *n),
            Self::Folder => output::png_folder(out, frames),
        }
    }
}

/// Renders episode `index` of the dump at `traj` to `out`; returns (frames, frames per second).
///
/// # Errors
/// Unreadable dump, missing episode, rendering or writing errors.
pub fn render_dump(traj: &Path, index: usize, view: &View, out: &Path, kind: &Output) -> Result<(usize, f64)> {
    let episodes = crate::episode::rollout::read_dump(traj)?;
    let Some(ep) = episodes.get(index) else {
        bail!("{} holds {} episodes; --episode {index} does not exist", traj.display(), episodes.len());
    };
    let (frames, seconds) = episode_frames(ep, view)?;
    kind.write(out, &frames)?;
    Ok((frames.len(), frames.len() as f64 / seconds.max(1e-9)))
}
