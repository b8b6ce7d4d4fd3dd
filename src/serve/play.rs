//! The render queue and episodes streamed as they are made.
//!
//! One thread renders (MuJoCo's renderer in one headless OpenGL context), taking jobs first come
//! first served from a bounded queue: a second tab waits its turn or is told the queue is full, and
//! never starves the first. A job plays one episode with the one episode loop and sends each frame
//! as soon as it is rendered, one JSON line at a time (`start`, then `frame` per step, then `end`);
//! when the page goes away mid-episode the sends fail, the job stops rendering and the thread takes
//! the next one.

use crate::benchmark::load::resolve;
use crate::env::{BlockEnv, EnvConfig};
use crate::episode::rollout::{play_episode, Event};
use crate::policy::Policy;
use crate::render::{Renderer, View};
use crate::sim::mj::Data;
use crate::task::Task;
use base64::Engine as _;
use serde_json::json;
use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::Arc;

/// Episodes that may wait for the renderer beside the one it plays.
pub const QUEUE: usize = 4;
/// Frames rendered ahead of what the page has read.
pub const AHEAD: usize = 4;
/// The frame's side in pixels unless asked (what the page shows).
pub const DEFAULT_SIDE: usize = 320;
/// The largest frame side the page may ask for.
pub const MAX_SIDE: usize = 640;
/// The render thread's stack. Mesa's software rasteriser compiles its shaders with LLVM on the
/// thread that draws, which overflowed a thread's default 2 MiB (the main thread, where the
/// command line renders, has 8 MiB).
pub const STACK_BYTES: usize = 64 << 20;

/// What to play.
#[derive(Debug, Clone)]
pub struct Job {
    /// The task, compiled.
    pub task: Task,
    /// The policy: `scripted`, `random`, `obs-hash`, a zoo name or a file the app may read.
    pub policy: PathBuf,
    /// The name the page shows for it.
    pub policy_label: String,
    /// The episode's seed.
    pub seed: u64,
    /// The curriculum level (None: the highest).
    pub level: Option<usize>,
    /// A named distribution.
    pub distribution: Option<String>,
    /// Frame side, pixels.
    pub side: usize,
    /// Only the reset state, as one PNG (a thumbnail): no episode.
    pub still: bool,
}

/// What a job sends back.
#[derive(Debug)]
pub enum Msg {
    /// One JSON line of the stream.
    Line(String),
    /// The thumbnail.
    Png(Vec<u8>),
    /// The job could not start (a bad task, level or policy): the page's message.
    Failed(String),
}

/// The queue's sending end, shared by the workers.
#[derive(Clone)]
pub struct Queue {
    tx: SyncSender<(Job, SyncSender<Msg>)>,
}

/// Why a job was not queued.
#[derive(Debug, PartialEq, Eq)]
pub enum Refused {
    /// The queue holds [`QUEUE`] jobs already.
    Full,
    /// The render thread has stopped.
    Stopped,
}

impl Queue {
    /// Starts the render thread and returns its queue.
    pub fn start() -> Queue {
        let (tx, rx) = sync_channel::<(Job, SyncSender<Msg>)>(QUEUE);
        std::thread::Builder::new()
            .name("render".into())
            .stack_size(STACK_BYTES)
            .spawn(move || {
                for (job, out) in rx {
                    let failed = out.clone();
                    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(&job, &out)));
                    match run {
                        Ok(Ok(())) => {}
                        Ok(Err(message)) => {
                            eprintln!("serve: {}: {message}", job.task.id());
                            let _ = failed.try_send(Msg::Failed(message));
                        }
                        Err(_) => {
                            eprintln!("serve: rendering {} panicked; the queue goes on", job.task.id());
                            let _ = failed.try_send(Msg::Failed("the renderer failed on this episode".into()));
                        }
                    }
                }
            })
            .expect("a thread can be started at startup");
        Queue { tx }
    }

    /// Queues `job`; its messages arrive on the returned receiver.
    ///
    /// # Errors
    /// [`Refused`]: a full queue or a stopped renderer.
    pub fn submit(&self, job: Job) -> Result<Receiver<Msg>, Refused> {
        let (out, rx) = sync_channel(AHEAD);
        match self.tx.try_send((job, out)) {
            Ok(()) => Ok(rx),
            Err(TrySendError::Full(_)) => Err(Refused::Full),
            Err(TrySendError::Disconnected(_)) => Err(Refused::Stopped),
        }
    }
}

/// `env`'s current state drawn by `renderer` (through `data`, a state of the same model that the
/// renderer may write its scene into), as a PNG.
fn snapshot(env: &BlockEnv, renderer: &mut Renderer, data: &mut Data) -> Result<Vec<u8>, String> {
    data.qpos_mut().copy_from_slice(env.data().qpos());
    data.forward().map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    renderer
        .render(data, None)
        .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageOutputFormat::Png)
        .map_err(|e| format!("encoding a frame: {e}"))?;
    Ok(bytes)
}

/// The environment and policy of `job`, the policy's observation fitted as `rollout` fits it.
fn setup(job: &Job) -> Result<(BlockEnv, Box<dyn Policy>), String> {
    let named = resolve(&job.policy).map_err(|e| format!("policy {}: {e}", job.policy_label))?;
    let mut config = EnvConfig::new(job.task.clone());
    named.fit(&mut config).map_err(|e| format!("policy {}: {e}", job.policy_label))?;
    let mut env = BlockEnv::new(config).map_err(|e| e.to_string())?;
    env.set_distribution(job.distribution.as_deref()).map_err(|e| e.to_string())?;
    let level = job.level.unwrap_or(env.max_level());
    env.set_level(level).map_err(|e| e.to_string())?;
    let policy = named
        .into_player(&env, job.seed)
        .map_err(|e| format!("policy {} cannot play {}: {e}", job.policy_label, job.task.id()))?;
    Ok((env, policy))
}

/// Plays `job`, sending its stream on `out`. An error before the first line is the job's failure;
/// a page gone away ends rendering quietly.
fn run(job: &Job, out: &SyncSender<Msg>) -> Result<(), String> {
    let (mut env, mut policy) = setup(job)?;
    let view = View {
        width: job.side,
        height: job.side,
        caption: false,
        // Closer than the command line's default: the table fills the page's square frame.
        lookat: [1.3, 0.75, 0.45],
        distance: 1.5,
        azimuth: 150.0,
        elevation: -30.0,
    };
    view.check()?;
    let model = env.scene().model.clone();
    let mut renderer = Renderer::new(&model, &view).map_err(|e| e.to_string())?;
    let mut data = Data::new(Arc::clone(&model)).map_err(|e| e.to_string())?;
    if job.still {
        env.reset(Some(job.seed)).map_err(|e| e.to_string())?;
        renderer.colour_env(&env).map_err(|e| e.to_string())?;
        let _ = out.send(Msg::Png(snapshot(&env, &mut renderer, &mut data)?));
        return Ok(());
    }
    let mut gone = false;
    let mut failed: Option<String> = None;
    let mut names: Vec<String> = Vec::new();
    let (mut total, mut steps, mut decided) = (0.0f32, 0usize, None::<(usize, &'static str, Vec<[String; 2]>)>);
    let send = |line: serde_json::Value, gone: &mut bool| {
        if !*gone && out.send(Msg::Line(line.to_string())).is_err() {
            *gone = true;
        }
    };
    let frame = |env: &BlockEnv, renderer: &mut Renderer, data: &mut Data| -> Result<String, String> {
        let bytes = snapshot(env, renderer, data)?;
        Ok(format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes)))
    };
    let played = play_episode(&mut env, policy.as_mut(), job.seed, |event| {
        if gone || failed.is_some() {
            return;
        }
        match event {
            Event::Reset { env, .. } => {
                if let Err(e) = renderer.colour_env(env) {
                    failed = Some(e.to_string());
                    return;
                }
                let absent = env.absent_objects();
                names = env.objects().iter().map(|o| o.name.clone()).collect();
                let objects: Vec<_> = env
                    .objects()
                    .iter()
                    .zip(&absent)
                    .map(|(o, a)| json!({"name": o.name, "colour": o.colour.name(), "absent": a}))
                    .collect();
                let image = match frame(env, &mut renderer, &mut data) {
                    Ok(i) => i,
                    Err(e) => return failed = Some(e),
                };
                send(
                    json!({
                        "type": "start", "task": env.id(), "policy": job.policy_label, "seed": job.seed,
                        "level": env.level(), "distribution": env.distribution_name(),
                        "max_steps": env.config().task.spec.max_episode_steps, "objects": objects,
                        "engine": crate::sim::mj::version(), "image": image,
                    }),
                    &mut gone,
                );
            }
            Event::Step { env, step, .. } => {
                steps += 1;
                total += step.reward;
                let pairs: Vec<[String; 2]> = step
                    .info
                    .touching
                    .iter()
                    .map(|&(a, b)| {
                        [names.get(a).cloned().unwrap_or_default(), names.get(b).cloned().unwrap_or_default()]
                    })
                    .collect();
                if decided.is_none() && (step.info.is_success || step.info.is_failure) {
                    let what = if step.info.is_failure { "failure" } else { "success" };
                    decided = Some((steps, what, pairs.clone()));
                }
                let image = match frame(env, &mut renderer, &mut data) {
                    Ok(i) => i,
                    Err(e) => return failed = Some(e),
                };
                send(
                    json!({"type": "frame", "step": steps, "reward": step.reward, "touching": pairs, "image": image}),
                    &mut gone,
                );
            }
        }
    });
    if gone {
        eprintln!("serve: the page left during {} (seed {}); rendering stopped", job.task.id(), job.seed);
        return Ok(());
    }
    if let Some(e) = failed {
        return Err(e);
    }
    played.map_err(|e| e.to_string())?;
    let (outcome, at, contacts) = match decided {
        Some((at, what, pairs)) => (what, Some(at), pairs),
        None => ("neither", None, Vec::new()),
    };
    send(
        json!({"type": "end", "outcome": outcome, "decided_at": at, "contacts": contacts, "steps": steps, "return": total}),
        &mut gone,
    );
    Ok(())
}
