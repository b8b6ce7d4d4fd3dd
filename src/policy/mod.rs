//! Layer 5, policy: policies that read only observations.
//!
//! | module | what |
//! |---|---|
//! | this file | the [`Policy`] trait, random and obs-hash, the scripted controller and solver |
//! | `push`, `reach`, `topple`, `pick` | the solver's behaviours, each a function of one observation |
//! | [`actor`] | trained policies' plain-Rust forward pass (no libtorch) |
//!
//! Policies that need no learning: uniform random actions, and scripted
//! controllers that prove the tasks solvable: pushing blue onto green,
//! reaching green with a blue gripper (over any red wall), toppling a tower
//! with a red gripper, and picking blue up and putting it on green.
//!
//! Both read only the observation, and the scripted controller nothing else: it keeps no state
//! from step to step, and it does not read the order of the block rows (since [`SOLVER_VERSION`] 3;
//! the version each number records).
//! The scripted controller as a solver
//! ([`ScriptedPolicy::solver`], the `scripted` baseline) decides what to do
//! from the `entities` observation alone: which blocks are blue, green, red,
//! and whether the gripper or the table takes part in the rules.
//! [`ScriptedPolicy::for_env`] is told the behaviour by the task's
//! configuration instead, and reads the layout that configuration presents
//! (flat or `objects`, which show no gripper or table colour): the reference
//! the solver is tested against.

pub mod actor;
mod pick;
mod push;
mod reach;
mod topple;

use crate::env::{EnvConfig, Fixture, ObsMode, ObsSpec, ACTION_DIM, ROBOT_OBS};
use crate::sim::rules::Colour;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Something that maps observations to actions.
pub trait Policy {
    /// Called at the start of each episode.
    fn reset(&mut self) {}
    /// The action for `obs`.
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM];
    /// The observation mode it reads, where it needs one whatever the environment presents: the
    /// episode loop ([`crate::episode::rollout::play_episode`]) then gives it that view of each state.
    fn reads(&self) -> Option<ObsMode> {
        None
    }
}

/// Uniform actions in [-1, 1]^4 from its own seeded generator.
pub struct RandomPolicy {
    rng: ChaCha8Rng,
}

impl RandomPolicy {
    /// A random policy with a fixed seed.
    pub fn new(seed: u64) -> Self {
        Self { rng: ChaCha8Rng::seed_from_u64(seed) }
    }
}

impl Policy for RandomPolicy {
    fn act(&mut self, _obs: &[f32]) -> [f32; ACTION_DIM] {
        std::array::from_fn(|_| self.rng.gen_range(-1.0..=1.0))
    }
}

/// Pseudo-random actions that are a function of the observation alone: a
/// hash of the observation's bits (FNV-1a over each value's `f32` bit
/// pattern, then murmur3's finaliser once per action component) mapped to
/// [-1, 1). Stateless, so a batch, a thread or another language (Python's
/// `blockpuzzle.policies.obs_hash`, the same integer arithmetic in numpy)
/// gives bit-identical actions: the reference policy for checking one
/// evaluation harness against another.
#[derive(Debug, Clone, Copy, Default)]
pub struct ObsHashPolicy;

impl ObsHashPolicy {
    /// The action for `obs`.
    pub fn action(obs: &[f32]) -> [f32; ACTION_DIM] {
        let mut h: u32 = 0x811c_9dc5;
        for v in obs {
            h = (h ^ v.to_bits()).wrapping_mul(0x0100_0193);
        }
        std::array::from_fn(|k| {
            let mut x = h ^ (k as u32 + 1).wrapping_mul(0x9e37_79b9);
            x ^= x >> 16;
            x = x.wrapping_mul(0x85eb_ca6b);
            x ^= x >> 13;
            x = x.wrapping_mul(0xc2b2_ae35);
            x ^= x >> 16;
            // 24 bits: exact in f32, as are the scaling and the shift.
            (x >> 8) as f32 * (1.0 / 16_777_216.0) * 2.0 - 1.0
        })
    }
}

impl Policy for ObsHashPolicy {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        Self::action(obs)
    }
}

/// A block as seen in the observation.
#[derive(Debug, Clone, Copy)]
struct SeenBlock {
    pos: [f64; 3],
    colour: Colour,
    /// Its slot in the observation.
    slot: usize,
}

/// The blocks present in `obs` (laid out as `spec` says): position and
/// colour. A slot is absent when the mask says so or, in the flat layout,
/// when its row is zero (no colour).
fn read_blocks(spec: &ObsSpec, obs: &[f32]) -> Vec<SeenBlock> {
    let present = |k: usize| spec.mask(obs).map_or(true, |m| m.get(k).is_some_and(|&v| v > 0.5));
    spec.objects(obs)
        .enumerate()
        .filter(|&(k, b)| present(k) && ObsSpec::colour(b).iter().any(|&v| v > 0.5))
        .map(|(slot, b)| SeenBlock { pos: [b[0] as f64, b[1] as f64, b[2] as f64], colour: colour_of(b), slot })
        .collect()
}

/// Grip-site height that clears the blocks (block top 0.45 m, fingers reach
/// about 0.019 m below the grip site).
const SAFE_Z: f64 = 0.50;
/// Grip-site height for pushing: fingers just above the table.
const PUSH_Z: f64 = 0.425;
/// Distance behind the block's centre where a push starts.
const STANDOFF: f64 = 0.065;
/// Proportional gain from metres of error to action units.
const GAIN: f64 = 1.0 / 0.05;

/// Which scripted behaviour a task calls for, chosen from its colours and
/// whether the gripper action is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Script {
    /// Grey gripper, blocked fingers: push blue against green.
    Push,
    /// Red gripper, green blocks: push green onto blue, never touching blue.
    PushGreen,
    /// Blue gripper: move onto the green block, over any red block in the way.
    Reach,
    /// Red gripper: knock the tower under the blue block over without touching blue.
    Topple,
    /// Gripper action on: pick blue up and put it on green.
    PickPlace,
    /// Gripper action on, several blue blocks: put each on the green one, side by side.
    Gather,
}

/// Why the solver cannot play a task: what its observation shows, in words.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsolvable(pub String);

impl std::fmt::Display for Unsolvable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl Script {
    /// The behaviour the rules shown in an `entities` observation call for (`spec` says where
    /// what is): by the gripper's colour (blue: reach green; red: topple onto a green table, or
    /// elsewhere push a green block onto the one blue block), then
    /// by the blocks and the table (several blue blocks: gather them on green; a red table: pick
    /// blue up and put it on green; otherwise push blue against green).
    ///
    /// # Errors
    /// What the solver cannot do: a layout without the gripper's and table's rows; a blue gripper
    /// with blue blocks or without a green one; a red gripper with other than one blue block and no
    /// green table; a green gripper; no blue block, or no green block for it to reach.
    pub fn from_observation(spec: &ObsSpec, obs: &[f32]) -> Result<Script, Unsolvable> {
        let fixture = |f: Fixture| -> Option<Colour> {
            let row = spec.fixture_row(f)?;
            let present = spec.mask(obs).and_then(|m| m.get(row)).is_some_and(|&v| v > 0.5);
            let rows = spec.all_rows(obs);
            present.then(|| rows.clone().nth(row)).flatten().map(colour_of)
        };
        let (Some(gripper), Some(table)) = (fixture(Fixture::Gripper), fixture(Fixture::Table)) else {
            return Err(Unsolvable(format!(
                "the {} observation does not show the gripper's and the table's colours (the solver reads the `entities` one)",
                spec.mode
            )));
        };
        let blocks = read_blocks(spec, obs);
        let count = |c: Colour| blocks.iter().filter(|b| b.colour == c).count();
        let green_anywhere =
            count(Colour::Green) > 0 || table == Colour::Green || fixture(Fixture::Floor) == Some(Colour::Green);
        match gripper {
            Colour::Blue if count(Colour::Blue) > 0 => Err(Unsolvable(
                "a blue gripper and blue blocks (the solver reaches green with the gripper alone)".into(),
            )),
            Colour::Blue if count(Colour::Green) > 0 => Ok(Script::Reach),
            Colour::Blue => Err(Unsolvable("a blue gripper with no green block to reach".into())),
            Colour::Red if table == Colour::Green && count(Colour::Blue) > 0 => Ok(Script::Topple),
            Colour::Red if count(Colour::Blue) == 1 && count(Colour::Green) > 0 => Ok(Script::PushGreen),
            Colour::Red => {
                Err(Unsolvable("a red gripper with other than one blue block to bring a green block to".into()))
            }
            Colour::Green => Err(Unsolvable(
                "a green gripper (the solver brings blue to green blocks, not the gripper to blue)".into(),
            )),
            Colour::Grey if count(Colour::Blue) == 0 => Err(Unsolvable("no blue object to move".into())),
            Colour::Grey if !green_anywhere => Err(Unsolvable("no green object to reach".into())),
            Colour::Grey if count(Colour::Green) == 0 => Err(Unsolvable(
                "blue must reach a green table or floor, not a green block (the solver moves blue onto green blocks)"
                    .into(),
            )),
            Colour::Grey if count(Colour::Blue) > 1 => Ok(Script::Gather),
            Colour::Grey if table == Colour::Red => Ok(Script::PickPlace),
            Colour::Grey => Ok(Script::Push),
        }
    }

    /// Its name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Script::Push => "push",
            Script::PushGreen => "push-green",
            Script::Reach => "reach",
            Script::Topple => "topple",
            Script::PickPlace => "pick-place",
            Script::Gather => "gather",
        }
    }
}

/// The colour a one-hot row shows (its largest component).
fn colour_of(row: &[f32]) -> Colour {
    let hot = ObsSpec::colour(row);
    Colour::ALL[(0..hot.len()).max_by(|&i, &j| hot[i].total_cmp(&hot[j])).unwrap_or(3)]
}

/// The version of the solver's behaviours: bumped on any change to what it does, recorded in every
/// result, demonstrations file and dataset it makes ([`crate::benchmark::provenance::Build`]).
/// Version 1 kept a plan from step to step (the behaviour chosen at the first step, the route
/// around red, the steps spent closing, the swipe, letting go and rising); version 2 is a function
/// of one observation; version 3 chooses among blocks of one colour by where they are (the
/// nearest, [`nearest`]), never by their slot in the observation, so that its action does not
/// depend on the order of the block rows and a policy that reads them as a set can copy it;
/// version 4 pushes with every threshold of `push_line` a smooth step (lined up behind the block,
/// the corridor behind it, arriving, rising before crossing), so that its action is a continuous
/// function of the observation, which a network copies better (results/generalist.md); version 5
/// grasps through a funnel (the grip comes down as it centres on the block, and closes within 2 cm
/// of its centre, where a threshold of 8 mm left it hovering or rising again) and gathers the blue
/// blocks in a fixed order of where they are (least y first), not the nearest to the gripper
/// first, whose choice a network averaged into a way between two blocks (results/solver.md).
pub const SOLVER_VERSION: u32 = 5;

/// The scripted controller: for block tasks, get behind the blue block and
/// push it towards the green one (or push the green one onto the blue one if
/// that path is clearer of grey blocks); for a blue-gripper task, move the
/// gripper onto the green block, above the top of any red block until over
/// it; for a red-gripper tower, push the grey blocks out from under the blue
/// one; with the gripper action, pick blue up and put it on green (each
/// blue in turn, side by side, when there are several). With red blocks on
/// the table, the push goes around them, through a waypoint beside them.
///
/// It keeps no state from one step to the next: every action is a function of the observation
/// alone ([`ScriptedPolicy::decide`]). Each phase (which behaviour, which block, the way around
/// red, whether a block is held or being let go, whether the swipe is under way) is read afresh
/// from what the observation shows, so the solver labels any state the way it would act there,
/// whatever came before: an expert for DAgger whose labels are consistent (tests/it/entities.rs
/// replays recorded observations in shuffled order). Each behaviour is a function in its own file
/// (push.rs, reach.rs, topple.rs, pick.rs).
#[derive(Debug, Clone)]
pub struct ScriptedPolicy {
    /// How the behaviour is chosen.
    choice: Choice,
    /// Where the observation holds what.
    spec: ObsSpec,
    /// What the last observation it acted on called for: the behaviour, or why it cannot play
    /// (a report for callers; no action depends on it).
    last: Option<Result<Script, Unsolvable>>,
}

/// Where the behaviour comes from.
#[derive(Debug, Clone, PartialEq)]
enum Choice {
    /// The task's configuration named it, and each slot's half extents.
    Fixed(Script, Vec<[f64; 3]>),
    /// Each observation decides it ([`Script::from_observation`]), and shows the sizes.
    Observed,
}

/// What a behaviour reads at a step: the grip site, the fingers and their velocities, the blocks
/// present and each slot's size.
struct Seen<'a> {
    grip: [f64; 3],
    /// The grip site's travel in the last step (the observation's velocity × dt).
    grip_vel: [f64; 3],
    fingers: [f64; 2],
    /// The fingers' joint travel in the last step (the observation's velocity × dt).
    finger_vel: [f64; 2],
    blocks: &'a [SeenBlock],
    sizes: &'a [[f64; 3]],
}

impl Script {
    /// Its action for what `seen` shows.
    fn act(self, seen: &Seen) -> [f32; ACTION_DIM] {
        match self {
            Script::Push => push::push(seen, false),
            Script::PushGreen => push::push(seen, true),
            Script::Reach => reach::reach(seen),
            Script::Topple => topple::topple(seen),
            Script::PickPlace => pick::pick_place(seen),
            Script::Gather => pick::gather(seen),
        }
    }
}

impl ScriptedPolicy {
    /// The controller for an environment configuration, told its behaviour by the task (its
    /// gripper's colour and whether the gripper action is on), reading the observation as
    /// `config` presents it (flat or `objects` too). The `scripted` baseline is
    /// [`ScriptedPolicy::solver`], which chooses the same behaviour on every built-in task from
    /// the observation alone (tests/it/entities.rs).
    pub fn for_env(config: &EnvConfig) -> Self {
        let blues = config.task.colours().iter().filter(|&&c| c == Colour::Blue).count();
        let script = if config.task.spec.robot.gripper_action {
            if blues > 1 {
                Script::Gather
            } else {
                Script::PickPlace
            }
        } else {
            match config.gripper() {
                Colour::Blue => Script::Reach,
                Colour::Red => Script::Topple,
                _ => Script::Push,
            }
        };
        let spec = config.obs_spec();
        // As the observation holds them (f32), so that the solver, which reads them there, acts alike.
        let sizes = config.task.objects().map(|o| o.half_extents.map(|v| v as f32 as f64)).collect();
        Self { choice: Choice::Fixed(script, sizes), spec, last: Some(Ok(script)) }
    }

    /// The solver: a controller that reads nothing but the `entities` observation with `blocks`
    /// block slots and decides every action from it alone ([`ScriptedPolicy::decide`]): the
    /// behaviour the rules shown call for ([`Script::from_observation`]) and what that behaviour
    /// does in the state shown. Where it cannot play a task it stands still and
    /// [`ScriptedPolicy::unsolvable`] says why. It asks the episode loop for that layout
    /// ([`Policy::reads`]) whatever the environment presents.
    pub fn solver(blocks: usize) -> Self {
        let spec = ObsSpec::new(ObsMode::Entities, blocks);
        Self { choice: Choice::Observed, spec, last: None }
    }

    /// The behaviour in use: the one the task names, or the one the solver chose for the last
    /// observation it acted on (`None` before its first, or where it cannot play the task).
    pub fn script(&self) -> Option<Script> {
        self.last.as_ref().and_then(|r| r.as_ref().ok().copied())
    }

    /// Why the solver cannot play the task of the last observation it acted on, where it cannot.
    pub fn unsolvable(&self) -> Option<&Unsolvable> {
        self.last.as_ref().and_then(|r| r.as_ref().err())
    }

    /// The action for `obs` and the behaviour it came from (or why there is none: then the action
    /// stands still), from `obs` alone: the same observation gives the same action, bit for bit,
    /// whatever was seen before.
    pub fn decide(&self, obs: &[f32]) -> ([f32; ACTION_DIM], Result<Script, Unsolvable>) {
        if obs.len() < ROBOT_OBS {
            // Not a BlockPuzzle observation: stand still.
            return ([0.0; ACTION_DIM], Err(Unsolvable("not a BlockPuzzle observation".into())));
        }
        let (script, sizes) = match &self.choice {
            Choice::Fixed(script, sizes) => (Ok(*script), std::borrow::Cow::Borrowed(sizes)),
            Choice::Observed => {
                let size_at = OBJECT_FEATURES_LEN;
                let sizes: Vec<[f64; 3]> =
                    self.spec.objects(obs).map(|r| std::array::from_fn(|k| r[size_at + k] as f64)).collect();
                (Script::from_observation(&self.spec, obs), std::borrow::Cow::Owned(sizes))
            }
        };
        let Ok(script) = script else {
            return ([0.0; ACTION_DIM], script); // a task the solver cannot play: stand still
        };
        let blocks = read_blocks(&self.spec, obs);
        let seen = Seen {
            grip: [obs[0] as f64, obs[1] as f64, obs[2] as f64],
            grip_vel: [obs[5] as f64, obs[6] as f64, obs[7] as f64],
            fingers: [obs[3] as f64, obs[4] as f64],
            finger_vel: [obs[8] as f64, obs[9] as f64],
            blocks: &blocks,
            sizes: &sizes,
        };
        (script.act(&seen), Ok(script))
    }
}

/// Where a row's size begins (after [`crate::env::OBJECT_FEATURES`]).
const OBJECT_FEATURES_LEN: usize = crate::env::OBJECT_FEATURES.len();

fn toward(from: [f64; 3], to: [f64; 3]) -> [f32; ACTION_DIM] {
    let mut a = [0.0f32; ACTION_DIM];
    for k in 0..3 {
        a[k] = ((to[k] - from[k]) * GAIN).clamp(-1.0, 1.0) as f32;
    }
    a
}

/// 0 below `a`, 1 above `b`, and a smooth (cubic) step between: the solver's thresholds, so that its
/// action is a continuous function of the observation (since version 4).
fn smoothstep(x: f64, a: f64, b: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn xy_dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The block of `colour` nearest to `to` in the plane among those `keep` admits: a choice among
/// alike blocks by where they are, never by their slot, so that the solver's action is the same
/// whatever the order of the block rows. Blocks at one distance go to the lower x, then y, then z.
fn nearest(
    blocks: &[SeenBlock],
    colour: Colour,
    to: [f64; 3],
    keep: impl Fn(&SeenBlock) -> bool,
) -> Option<&SeenBlock> {
    let key = |b: &SeenBlock| [xy_dist(b.pos, to), b.pos[0], b.pos[1], b.pos[2]];
    blocks.iter().filter(|b| b.colour == colour && keep(b)).min_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        (0..4).map(|k| ka[k].total_cmp(&kb[k])).find(|o| o.is_ne()).unwrap_or(std::cmp::Ordering::Equal)
    })
}

/// Distance from `p` to the segment `a`–`b` in the plane.
fn seg_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

impl Policy for ScriptedPolicy {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        let (action, why) = self.decide(obs);
        self.last = Some(why);
        action
    }

    fn reads(&self) -> Option<ObsMode> {
        (self.choice == Choice::Observed).then_some(ObsMode::Entities)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obs_hash_actions_are_pinned_across_languages() {
        // The same bits python/tests/test_evaluate.py pins for blockpuzzle.policies.obs_hash.
        let bits = |obs: &[f32]| ObsHashPolicy::action(obs).map(f32::to_bits);
        assert_eq!(bits(&[0.5, 1.0, -2.0]), [0x3e9cc9bc, 0xbd467480, 0x3eb28cc8, 0xbf50d8e4]);
        assert_eq!(bits(&[0.0, 0.0, 0.0]), [0xbf2d9f90, 0x3f5afb30, 0x3f49a61c, 0x3ecbabcc]);
        assert!(ObsHashPolicy::action(&[1.0; 30]).iter().all(|a| (-1.0..1.0).contains(a)));
    }
}
