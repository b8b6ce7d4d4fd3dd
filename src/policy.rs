//! Policies that need no learning: uniform random actions, and scripted
//! controllers that prove the tasks solvable: pushing blue onto green,
//! reaching green with a blue gripper (over any red wall), toppling a tower
//! with a red gripper, and picking blue up and putting it on green.
//!
//! Both read only the observation (plus, for the scripted one, which task it
//! is playing), so they run on exactly what an agent sees.

use crate::env::{EnvConfig, ObsSpec, ACTION_DIM, ROBOT_OBS};
use crate::rules::Colour;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Something that maps observations to actions.
pub trait Policy {
    /// Called at the start of each episode.
    fn reset(&mut self) {}
    /// The action for `obs`.
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM];
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

/// A push's route around red blocks: the waypoint and where blue started
/// (none: straight), and whether blue has passed the waypoint.
type Route = (Option<([f64; 3], [f64; 3])>, bool);

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
        .map(|(slot, b)| {
            let hot = ObsSpec::colour(b);
            let k = (0..4).max_by(|&i, &j| hot[i].total_cmp(&hot[j])).unwrap_or(3);
            SeenBlock { pos: [b[0] as f64, b[1] as f64, b[2] as f64], colour: Colour::ALL[k], slot }
        })
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
    /// Blue gripper: move onto the green block, over any red block in the way.
    Reach,
    /// Red gripper: knock the tower under the blue block over without touching blue.
    Topple,
    /// Gripper action on: pick blue up and put it on green.
    PickPlace,
    /// Gripper action on, several blue blocks: put each on the green one, side by side.
    Gather,
}

/// The scripted controller: for block tasks, get behind the blue block and
/// push it towards the green one (or push the green one onto the blue one if
/// that path is clearer of grey blocks); for a blue-gripper task, move the
/// gripper onto the green block, above the top of any red block until over
/// it; for a red-gripper tower, push the grey blocks out from under the blue
/// one; with the gripper action, pick blue up and put it on green (each
/// blue in turn, side by side, when there are several). With red blocks on
/// the table, the push goes around them: through a waypoint chosen at the
/// start of the episode so that blue's path stays clear of every red block.
#[derive(Debug, Clone)]
pub struct ScriptedPolicy {
    script: Script,
    /// Where the observation holds what.
    spec: ObsSpec,
    /// Each slot's half extents (the task's; shuffles only swap alike objects).
    sizes: Vec<[f64; 3]>,
    /// Push around red: the route planned at the episode's first step.
    route: Option<Route>,
    /// Gather: steps left opening the fingers over a block just set down.
    releasing: usize,
    /// Gather: rising clear of the blocks set down before moving on.
    rising: bool,
    /// Pick-and-place: the blue block has been grasped this episode.
    grasped: bool,
    /// Steps spent closing the fingers.
    closing: usize,
    /// Topple: the swipe's direction and the base's first position, fixed for the episode.
    push: Option<[f64; 4]>,
    /// Topple: the swipe is under way.
    swiping: bool,
    /// Topple: the swipe is done; keep still.
    swiped: bool,
}

impl ScriptedPolicy {
    /// The controller for an environment configuration.
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
        let sizes = config.task.objects().map(|o| o.half_extents).collect();
        Self {
            script,
            spec,
            sizes,
            route: None,
            releasing: 0,
            rising: false,
            grasped: false,
            closing: 0,
            push: None,
            swiping: false,
            swiped: false,
        }
    }

    /// The behaviour in use.
    pub fn script(&self) -> Script {
        self.script
    }
}

fn toward(from: [f64; 3], to: [f64; 3]) -> [f32; ACTION_DIM] {
    let mut a = [0.0f32; ACTION_DIM];
    for k in 0..3 {
        a[k] = ((to[k] - from[k]) * GAIN).clamp(-1.0, 1.0) as f32;
    }
    a
}

fn xy_dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Distance from `p` to the segment `a`–`b` in the plane.
fn seg_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

impl ScriptedPolicy {
    fn push(&mut self, grip: [f64; 3], blocks: &[SeenBlock]) -> [f32; ACTION_DIM] {
        let find = |c: Colour| blocks.iter().find(|b| b.colour == c).map(|b| b.pos);
        let (Some(blue), Some(green)) = (find(Colour::Blue), find(Colour::Green)) else {
            return [0.0; ACTION_DIM];
        };
        let reds: Vec<[f64; 3]> = blocks.iter().filter(|b| b.colour == Colour::Red).map(|b| b.pos).collect();
        if !reds.is_empty() {
            return self.push_around(grip, blue, green, &reds);
        }
        // Every other block (grey or red) is an obstacle.
        let obstacles: Vec<[f64; 3]> =
            blocks.iter().filter(|b| b.colour != Colour::Blue && b.colour != Colour::Green).map(|b| b.pos).collect();
        // Push whichever block has the clearer path (an obstacle in the way
        // would be shoved into the target instead).
        let clearance = |mover: [f64; 3], target: [f64; 3]| {
            obstacles.iter().map(|&g| seg_dist(g, mover, target)).fold(f64::INFINITY, f64::min)
        };
        let (mover, target) =
            if clearance(green, blue) > clearance(blue, green) + 0.02 { (green, blue) } else { (blue, green) };
        push_line(grip, mover, target)
    }

    /// Push blue to green along the route planned at the episode's first
    /// step: straight, or through a waypoint, whichever clears the red blocks.
    fn push_around(&mut self, grip: [f64; 3], blue: [f64; 3], green: [f64; 3], reds: &[[f64; 3]]) -> [f32; ACTION_DIM] {
        let (waypoint, passed) =
            self.route.get_or_insert_with(|| (plan_route(blue, green, reds).map(|w| (w, blue)), false));
        let target = match *waypoint {
            Some((w, start)) if !*passed => {
                // Passed: close to the waypoint, or beyond it on the way from the start.
                let ahead = [w[0] - blue[0], w[1] - blue[1]];
                let leg = [w[0] - start[0], w[1] - start[1]];
                if xy_dist(blue, w) < 0.03 || ahead[0] * leg[0] + ahead[1] * leg[1] <= 0.0 {
                    *passed = true;
                    green
                } else {
                    w
                }
            }
            _ => green,
        };
        push_line(grip, blue, target)
    }
}

/// Least distance from the centre of a pushed block to a red block's centre
/// along a route (two 5 cm blocks touch at 5 cm; the rest is room for the
/// push's wander and the blocks' turning).
const RED_CLEARANCE: f64 = 0.085;
/// Least distance from where the gripper comes down behind the block to a red block.
const STANDOFF_CLEARANCE: f64 = 0.065;
/// Waypoints stay this far inside the table's edges.
const ROUTE_MARGIN: f64 = 0.06;

/// A waypoint for pushing `blue` to `green` clear of `reds`: none when the
/// straight push is clear; otherwise the shortest route through a point
/// beside the straight line whose two legs, and the places where the
/// gripper comes down behind blue for each, keep their distance from every
/// red block (the clearest such route if none does).
fn plan_route(blue: [f64; 3], green: [f64; 3], reds: &[[f64; 3]]) -> Option<[f64; 3]> {
    use crate::scene::xml::{TABLE_CENTER, TABLE_HALF};
    let unit = |a: [f64; 3], b: [f64; 3]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let n = dx.hypot(dy).max(1e-9);
        [dx / n, dy / n]
    };
    // A leg ends where the block meets its target (the target's centre for a waypoint).
    let leg = |from: [f64; 3], to: [f64; 3], block: bool| {
        let d = unit(from, to);
        let end = if block { [to[0] - d[0] * 0.05, to[1] - d[1] * 0.05, to[2]] } else { to };
        let behind = [from[0] - d[0] * STANDOFF, from[1] - d[1] * STANDOFF, from[2]];
        let near = |p: [f64; 3]| reds.iter().map(|&r| xy_dist(r, p)).fold(f64::INFINITY, f64::min);
        // Clearance as a share of what is needed (≥ 1 is clear); a block that starts
        // closer to a red one than that only has to keep from getting closer.
        let path = reds
            .iter()
            .map(|&r| seg_dist(r, from, end) / RED_CLEARANCE.min(xy_dist(r, from) - 0.005))
            .fold(f64::INFINITY, f64::min);
        path.min(near(behind) / STANDOFF_CLEARANCE)
    };
    let direct = leg(blue, green, true);
    if direct >= 1.0 {
        return None;
    }
    let n = unit(blue, green);
    let side = [-n[1], n[0]];
    let on_table = |p: [f64; 3]| (0..2).all(|k| (p[k] - TABLE_CENTER[k]).abs() <= TABLE_HALF[k] - ROUTE_MARGIN);
    let mut best: Option<(bool, f64, [f64; 3])> = None;
    for t in [-0.5, -0.25, 0.0, 0.25, 0.5, 0.75, 1.0, 1.25] {
        for s in [0.06, -0.06, 0.09, -0.09, 0.12, -0.12, 0.15, -0.15, 0.18, -0.18, 0.22, -0.22] {
            let base = [blue[0] + (green[0] - blue[0]) * t, blue[1] + (green[1] - blue[1]) * t];
            let w = [base[0] + side[0] * s, base[1] + side[1] * s, blue[2]];
            if !on_table(w) {
                continue;
            }
            let clear = leg(blue, w, false).min(leg(w, green, true));
            let length = xy_dist(blue, w) + xy_dist(w, green);
            // Clear routes first, shortest among them; otherwise the clearest.
            let key = (clear >= 1.0, if clear >= 1.0 { -length } else { clear });
            if best.map_or(true, |(ok, v, _)| (key.0, key.1) > (ok, v)) {
                best = Some((key.0, key.1, w));
            }
        }
    }
    match best {
        Some((ok, v, w)) if ok || v > direct => Some(w),
        _ => None,
    }
}

/// Push `mover` towards `target`: get behind it (over the blocks when not
/// already behind), line up, and push through it, steering back onto the line.
fn push_line(grip: [f64; 3], mover: [f64; 3], target: [f64; 3]) -> [f32; ACTION_DIM] {
    let d = {
        let (dx, dy) = (target[0] - mover[0], target[1] - mover[1]);
        let n = dx.hypot(dy).max(1e-9);
        [dx / n, dy / n]
    };
    let behind = [mover[0] - d[0] * STANDOFF, mover[1] - d[1] * STANDOFF, PUSH_Z];
    // Where the gripper is relative to the push line through the mover.
    let rel = [grip[0] - mover[0], grip[1] - mover[1]];
    let along = rel[0] * d[0] + rel[1] * d[1];
    let across = rel[0] * -d[1] + rel[1] * d[0];
    let lined_up = across.abs() < 0.012 && along < -0.03 && grip[2] < PUSH_Z + 0.02;
    if lined_up {
        // Push: aim through the mover towards the target, steering back onto the line.
        let aim = [target[0] - across * -d[1] * 2.0, target[1] - across * d[0] * 2.0, PUSH_Z];
        return toward(grip, aim);
    }
    if xy_dist(grip, behind) > 0.015 {
        // Travel to the standoff point, above the blocks unless already behind.
        let low_ok = along < -0.04 && across.abs() < 0.04;
        if grip[2] < SAFE_Z - 0.01 && !low_ok && xy_dist(grip, mover) < 0.12 {
            return toward(grip, [grip[0], grip[1], SAFE_Z + 0.02]);
        }
        let z = if low_ok { PUSH_Z } else { SAFE_Z.max(grip[2].min(SAFE_Z + 0.05)) };
        return toward(grip, [behind[0], behind[1], z]);
    }
    toward(grip, behind)
}

/// Height of the table top.
const TABLE_TOP: f64 = 0.4;
/// How far the fingertips reach below the grip site.
const FINGERTIP_BELOW: f64 = 0.0185;

impl ScriptedPolicy {
    /// Onto the green block; while red blocks stand around, first above the
    /// highest red top (a block's top is read from its centre height).
    fn reach(grip: [f64; 3], blocks: &[SeenBlock]) -> [f32; ACTION_DIM] {
        let Some(g) = blocks.iter().find(|b| b.colour == Colour::Green) else {
            return [0.0; ACTION_DIM];
        };
        let red_top = blocks
            .iter()
            .filter(|b| b.colour == Colour::Red)
            .map(|b| TABLE_TOP + 2.0 * (b.pos[2] - TABLE_TOP))
            .fold(f64::NEG_INFINITY, f64::max);
        // Grip height whose fingertips clear every red top by 2.5 cm.
        let clear = red_top + FINGERTIP_BELOW + 0.025;
        if xy_dist(grip, g.pos) <= 0.01 {
            return toward(grip, g.pos);
        }
        if grip[2] < clear - 0.005 {
            // Up first (a little sideways is fine: nothing red is above the start).
            return toward(grip, [grip[0], grip[1], clear + 0.01]);
        }
        toward(grip, [g.pos[0], g.pos[1], grip[2].max(g.pos[2] + 0.05).max(clear)])
    }
}

impl Policy for ScriptedPolicy {
    fn reset(&mut self) {
        self.route = None;
        self.releasing = 0;
        self.rising = false;
        self.grasped = false;
        self.closing = 0;
        self.push = None;
        self.swiping = false;
        self.swiped = false;
    }

    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        if obs.len() < ROBOT_OBS {
            return [0.0; ACTION_DIM]; // not a BlockPuzzle observation: stand still
        }
        let grip = [obs[0] as f64, obs[1] as f64, obs[2] as f64];
        let fingers = [obs[3] as f64, obs[4] as f64];
        let blocks = read_blocks(&self.spec, obs);
        match self.script {
            Script::Push => self.push(grip, &blocks),
            Script::Reach => Self::reach(grip, &blocks),
            Script::Topple => self.topple(grip, &blocks),
            Script::PickPlace => self.pick_place(grip, fingers, &blocks),
            Script::Gather => self.gather(grip, fingers, &blocks),
        }
    }
}

/// The y of the table's centre line.
const TABLE_CENTRE_Y: f64 = 0.75;
/// Topple: grip height of the swipe (fingertips just above the table).
const TOPPLE_Z: f64 = 0.425;
/// Topple: distance from the tower's centre to the start of the swipe.
const TOPPLE_STANDOFF: f64 = 0.12;
/// Topple: speed of the swipe (action units: 0.4 is 2 cm a step; faster
/// throws blue off the table, slower lets the tower ride on the gripper).
const TOPPLE_SPEED: f64 = 0.4;
/// Topple: how far past the tower's centre the swipe goes.
const TOPPLE_THROUGH: f64 = 0.10;

impl ScriptedPolicy {
    /// Knock the tower's base out from under it: come down to just above
    /// the table (there the whole gripper passes under the blue block) away
    /// from the tower, go round to the side of the base farther from the
    /// table's centre line, then swipe through the base at full speed along y
    /// (along x the wrist leads the fingers) towards the centre line. The
    /// gripper's body hits the pillar too, so the tower falls ahead of it onto
    /// the table, and the gripper passes under blue as it comes down.
    /// (Designed on ToppleTower-v0's tall tower, whose blue block is above the
    /// gripper's body when the fingertips skim the table.)
    fn topple(&mut self, grip: [f64; 3], blocks: &[SeenBlock]) -> [f32; ACTION_DIM] {
        let Some(blue) = blocks.iter().find(|b| b.colour == Colour::Blue).map(|b| b.pos) else {
            return [0.0; ACTION_DIM];
        };
        if self.swiped {
            return [0.0; ACTION_DIM];
        }
        // The tower's base: the lowest non-blue block under blue.
        let base = blocks
            .iter()
            .filter(|b| b.colour != Colour::Blue && xy_dist(b.pos, blue) < 0.04)
            .map(|b| b.pos)
            .min_by(|a, b| a[2].total_cmp(&b[2]));
        let Some(base) = base else {
            return [0.0; ACTION_DIM]; // no tower under blue: nothing to do
        };
        let [dx, dy, x0, y0] = *self
            .push
            .get_or_insert_with(|| [0.0, if base[1] >= TABLE_CENTRE_Y { -1.0 } else { 1.0 }, base[0], base[1]]);
        let d = [dx, dy];
        let rel = [grip[0] - base[0], grip[1] - base[1]];
        let along = rel[0] * d[0] + rel[1] * d[1];
        let across = rel[0] * -d[1] + rel[1] * d[0];
        let at = |along: f64, across: f64, z: f64| {
            [base[0] + d[0] * along - d[1] * across, base[1] + d[1] * along + d[0] * across, z]
        };
        let low = grip[2] < TOPPLE_Z + 0.01;
        // Swiping starts behind the base, lined up, and then goes on along the
        // line whatever the blocks do, until a little past where the base stood.
        self.swiping |= low && (along + TOPPLE_STANDOFF).abs() < 0.015 && across.abs() < 0.015;
        if self.swiping {
            let past = (grip[0] - x0) * d[0] + (grip[1] - y0) * d[1];
            if past >= TOPPLE_THROUGH {
                self.swiped = true;
                return [0.0; ACTION_DIM];
            }
            // Full speed along the line, holding the height and the line's offset.
            let off = (grip[0] - x0) * -d[1] + (grip[1] - y0) * d[0];
            let hold = |e: f64| (e * GAIN).clamp(-1.0, 1.0);
            let side = hold(-off);
            return [
                (d[0] * TOPPLE_SPEED - d[1] * side) as f32,
                (d[1] * TOPPLE_SPEED + d[0] * side) as f32,
                hold(TOPPLE_Z - grip[2]) as f32,
                0.0,
            ];
        }
        let clear = TOPPLE_STANDOFF - 0.01;
        if !low {
            // Down, stepping away from the tower while the gripper's body is at blue's height.
            if along.hypot(across) < clear {
                let n = along.hypot(across).max(1e-9);
                return toward(grip, at(along / n * clear, across / n * clear, TOPPLE_Z));
            }
            return toward(grip, [grip[0], grip[1], TOPPLE_Z]);
        }
        if along > -TOPPLE_STANDOFF + 0.01 && across.abs() < clear {
            // Round the tower: out to the side first.
            let side = if across >= 0.0 { 1.0 } else { -1.0 };
            return toward(grip, at(along, side * (clear + 0.02), TOPPLE_Z));
        }
        if along > -TOPPLE_STANDOFF + 0.01 {
            return toward(grip, at(-TOPPLE_STANDOFF, across, TOPPLE_Z));
        }
        toward(grip, at(-TOPPLE_STANDOFF, 0.0, TOPPLE_Z))
    }

    /// Open, come down around blue, close, lift, carry above green, lower
    /// onto it (success ends the episode at the touch).
    fn pick_place(&mut self, grip: [f64; 3], fingers: [f64; 2], blocks: &[SeenBlock]) -> [f32; ACTION_DIM] {
        let find = |c: Colour| blocks.iter().find(|b| b.colour == c).map(|b| b.pos);
        let (Some(blue), Some(green)) = (find(Colour::Blue), find(Colour::Green)) else {
            return [0.0; ACTION_DIM];
        };
        let with = |mut a: [f32; ACTION_DIM], g: f32| {
            a[3] = g;
            a
        };
        let held = xy_dist(grip, blue) < 0.02 && (grip[2] - blue[2]).abs() < 0.02;
        if !self.grasped {
            return self.grasp(grip, fingers, blue);
        }
        if !held {
            // Dropped: start over.
            self.grasped = false;
            self.closing = 0;
            return with([0.0; ACTION_DIM], 1.0);
        }
        // Carry: above green with blue's bottom clear of green's top by 3 cm, then down.
        let carry = green[2] + 0.05 + 0.03;
        if xy_dist(blue, green) > 0.006 {
            let z = if blue[2] < carry - 0.01 { carry + 0.01 } else { carry.max(blue[2]) };
            let up_first = blue[2] < carry - 0.01;
            let target = if up_first {
                [grip[0], grip[1], z]
            } else {
                [green[0] + grip[0] - blue[0], green[1] + grip[1] - blue[1], z]
            };
            return with(toward(grip, target), -1.0);
        }
        with(toward(grip, [grip[0], grip[1], green[2] + 0.05 - 0.01]), -1.0)
    }
}

impl ScriptedPolicy {
    /// Each blue block in turn (the first not yet on green, in observation
    /// order): pick it up, carry it above green high enough to pass over the
    /// blocks already there, set it down on a free corner of green's top,
    /// open the fingers and rise straight up clear of it.
    fn gather(&mut self, grip: [f64; 3], fingers: [f64; 2], blocks: &[SeenBlock]) -> [f32; ACTION_DIM] {
        let with = |mut a: [f32; ACTION_DIM], g: f32| {
            a[3] = g;
            a
        };
        let size = |b: &SeenBlock| self.sizes.get(b.slot).copied().unwrap_or([0.025; 3]);
        let Some(green) = blocks.iter().find(|b| b.colour == Colour::Green) else {
            return [0.0; ACTION_DIM];
        };
        let (g, gs) = (green.pos, size(green));
        let top = g[2] + gs[2];
        let on_green = |b: &SeenBlock| {
            (b.pos[0] - g[0]).abs() < gs[0]
                && (b.pos[1] - g[1]).abs() < gs[1]
                && (b.pos[2] - top - size(b)[2]).abs() < 0.006
        };
        if self.releasing > 0 {
            self.releasing -= 1;
            return with([0.0; ACTION_DIM], 1.0);
        }
        if self.rising {
            if grip[2] < top + 0.09 {
                return with(toward(grip, [grip[0], grip[1], top + 0.10]), 1.0);
            }
            self.rising = false;
        }
        let blues: Vec<&SeenBlock> = blocks.iter().filter(|b| b.colour == Colour::Blue).collect();
        if !self.grasped {
            // The first blue block not on green yet.
            let Some(blue) = blues.iter().find(|b| !on_green(b)) else {
                return with([0.0; ACTION_DIM], 1.0); // all there (success ends the episode)
            };
            return self.grasp(grip, fingers, blue.pos);
        }
        let in_hand = blues.iter().find(|b| xy_dist(grip, b.pos) < 0.02 && (grip[2] - b.pos[2]).abs() < 0.02);
        let Some(&blue) = in_hand else {
            // Dropped: up, and start over.
            self.grasped = false;
            self.closing = 0;
            self.rising = true;
            return with([0.0; ACTION_DIM], 1.0);
        };
        let bh = size(blue)[2];
        // A free corner of green's top (a block's width in from the edges).
        let inset = [(gs[0] - bh - 0.01).max(0.0), (gs[1] - bh - 0.01).max(0.0)];
        let placed: Vec<[f64; 3]> =
            blues.iter().filter(|b| b.slot != blue.slot && on_green(b)).map(|b| b.pos).collect();
        let spot = [[-1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [1.0, -1.0]]
            .iter()
            .map(|c| [g[0] + c[0] * inset[0], g[1] + c[1] * inset[1], 0.0])
            .find(|p| placed.iter().all(|&q| xy_dist(*p, q) > 2.0 * bh))
            .unwrap_or([g[0], g[1], 0.0]);
        if on_green(blue) || (xy_dist(blue.pos, spot) <= 0.006 && blue.pos[2] < top + bh + 0.003) {
            // Set down: let go, then straight up.
            self.grasped = false;
            self.closing = 0;
            self.releasing = 2;
            self.rising = true;
            return with([0.0; ACTION_DIM], 1.0);
        }
        // Carry with blue's bottom 3 cm above the tops of the blocks already on green.
        let carry = top + 3.0 * bh + 0.03;
        if xy_dist(blue.pos, spot) > 0.006 {
            let up_first = blue.pos[2] < carry - 0.01;
            let target = if up_first {
                [grip[0], grip[1], carry + 0.01]
            } else {
                [spot[0] + grip[0] - blue.pos[0], spot[1] + grip[1] - blue.pos[1], carry.max(blue.pos[2])]
            };
            return with(toward(grip, target), -1.0);
        }
        with(toward(grip, [grip[0], grip[1], top + bh - 0.01]), -1.0)
    }

    /// Open above the block at `at`, come down around it and close (sets
    /// `grasped` once the fingers have closed for a few steps).
    fn grasp(&mut self, grip: [f64; 3], fingers: [f64; 2], at: [f64; 3]) -> [f32; ACTION_DIM] {
        let with = |mut a: [f32; ACTION_DIM], g: f32| {
            a[3] = g;
            a
        };
        let open = fingers[0] + fingers[1] > 0.07;
        if xy_dist(grip, at) > 0.008 {
            // Above the block, fingers opening.
            let z = (at[2] + 0.06).max(grip[2].min(at[2] + 0.08));
            return with(toward(grip, [at[0], at[1], z]), 1.0);
        }
        if !open && self.closing == 0 {
            return with([0.0; ACTION_DIM], 1.0);
        }
        if grip[2] > at[2] + 0.005 && self.closing == 0 {
            return with(toward(grip, at), 1.0);
        }
        // Close for a few steps until the fingers stop on the block.
        self.closing += 1;
        if self.closing >= 3 {
            self.grasped = true;
        }
        with([0.0; ACTION_DIM], -1.0)
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
