//! Policies that need no learning: uniform random actions, and a scripted
//! pushing controller that proves the tasks solvable.
//!
//! Both read only the observation (plus, for the scripted one, which task it
//! is playing), so they run on exactly what an agent sees.

use crate::env::{EnvConfig, ACTION_DIM, BLOCK_OBS, ROBOT_OBS};
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

/// A block as seen in the observation.
#[derive(Debug, Clone, Copy)]
struct SeenBlock {
    pos: [f64; 3],
    colour: Colour,
}

fn read_blocks(obs: &[f32]) -> Vec<SeenBlock> {
    obs[ROBOT_OBS..]
        .chunks_exact(BLOCK_OBS)
        .map(|b| {
            let hot = &b[15..19];
            let k = (0..4).max_by(|&i, &j| hot[i].total_cmp(&hot[j])).unwrap_or(3);
            SeenBlock { pos: [b[0] as f64, b[1] as f64, b[2] as f64], colour: Colour::ALL[k] }
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

/// The scripted controller: for block tasks, get behind the blue block and
/// push it towards the green one (or push the green one onto the blue one if
/// that path is clearer of grey blocks); for a blue-gripper task, move the
/// gripper onto the green block.
pub struct ScriptedPolicy {
    reach: bool,
}

impl ScriptedPolicy {
    /// The controller for an environment configuration.
    pub fn for_env(config: &EnvConfig) -> Self {
        Self { reach: config.gripper() == Colour::Blue }
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
    fn push(&self, grip: [f64; 3], blocks: &[SeenBlock]) -> [f32; ACTION_DIM] {
        let find = |c: Colour| blocks.iter().find(|b| b.colour == c).map(|b| b.pos);
        let (Some(blue), Some(green)) = (find(Colour::Blue), find(Colour::Green)) else {
            return [0.0; ACTION_DIM];
        };
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
}

impl Policy for ScriptedPolicy {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        if obs.len() < ROBOT_OBS {
            return [0.0; ACTION_DIM]; // not a BlockPuzzle observation: stand still
        }
        let grip = [obs[0] as f64, obs[1] as f64, obs[2] as f64];
        let blocks = read_blocks(obs);
        if self.reach {
            return match blocks.iter().find(|b| b.colour == Colour::Green) {
                Some(g) if xy_dist(grip, g.pos) > 0.01 => {
                    toward(grip, [g.pos[0], g.pos[1], grip[2].max(g.pos[2] + 0.05)])
                }
                Some(g) => toward(grip, [g.pos[0], g.pos[1], g.pos[2]]),
                None => [0.0; ACTION_DIM],
            };
        }
        self.push(grip, &blocks)
    }
}
