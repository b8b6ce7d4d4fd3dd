//! The pushing behaviour: get behind the blue block and push it towards the green one (or the
//! green one onto blue, where that path is clearer of grey blocks); around red blocks through a
//! waypoint chosen afresh at every step from where the blocks are; with a red gripper, always green
//! onto blue.

use super::{nearest, seg_dist, smoothstep, toward, xy_dist, Seen, ACTION_DIM, GAIN, PUSH_Z, SAFE_Z, STANDOFF};
use crate::sim::rules::Colour;

/// Push blue against green (grey gripper, blocked fingers; the green block nearest blue), around
/// red blocks; or, where `green_onto_blue` (a red gripper, which must never touch blue), green onto
/// blue, straight.
pub(super) fn push(seen: &Seen, green_onto_blue: bool) -> [f32; ACTION_DIM] {
    let (grip, blocks) = (seen.grip, seen.blocks);
    // Blue nearest the gripper, and the green block nearest to it.
    let Some(blue) = nearest(blocks, Colour::Blue, grip, |_| true).map(|b| b.pos) else {
        return [0.0; ACTION_DIM];
    };
    let Some(green) = nearest(blocks, Colour::Green, blue, |_| true).map(|b| b.pos) else {
        return [0.0; ACTION_DIM];
    };
    if green_onto_blue {
        return push_line(grip, green, blue);
    }
    let reds: Vec<[f64; 3]> = blocks.iter().filter(|b| b.colour == Colour::Red).map(|b| b.pos).collect();
    if !reds.is_empty() {
        return push_line(grip, blue, waypoint(blue, green, &reds).unwrap_or(green));
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

/// Least distance from the centre of a pushed block to a red block's centre
/// along a route (two 5 cm blocks touch at 5 cm; the rest is room for the
/// push's wander and the blocks' turning).
const RED_CLEARANCE: f64 = 0.085;
/// Least distance from where the gripper comes down behind the block to a red block.
const STANDOFF_CLEARANCE: f64 = 0.065;
/// Waypoints stay this far inside the table's edges.
const ROUTE_MARGIN: f64 = 0.06;

/// How much more than clear a waypoint's last leg must be (as a share of the clearance needed):
/// pushed along the first leg, blue finds the straight way to green clear before it reaches the
/// waypoint, and goes straight on.
const LAST_LEG_MARGIN: f64 = 1.1;
/// Distances from a red block's centre at which waypoints are tried, and how many directions.
const WAYPOINT_RADII: [f64; 4] = [0.10, 0.13, 0.16, 0.20];
const WAYPOINT_DIRECTIONS: usize = 16;
/// Within this distance of a waypoint blue has reached it, and it is not tried.
const REACHED: f64 = 0.03;

/// Where to push `blue` next on its way to `green` clear of `reds`, from where they are now: none
/// (straight to green) when the straight push is clear; otherwise the waypoint of the shortest
/// route whose two legs, and the places where the gripper comes down behind blue for each, keep
/// their distance from every red block (the clearest route if none does). The waypoints tried
/// stand around the red blocks, at fixed distances and directions, so they do not move as blue
/// does: pushed towards the chosen one, blue keeps choosing it (no other route gets shorter
/// faster), and one it has come within 3 cm of is not tried.
fn waypoint(blue: [f64; 3], green: [f64; 3], reds: &[[f64; 3]]) -> Option<[f64; 3]> {
    use crate::sim::scene::xml::{TABLE_CENTER, TABLE_HALF};
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
    let on_table = |p: [f64; 3]| (0..2).all(|k| (p[k] - TABLE_CENTER[k]).abs() <= TABLE_HALF[k] - ROUTE_MARGIN);
    // Blue has reached `w`.
    let passed = |w: [f64; 3]| xy_dist(blue, w) < REACHED;
    let mut best: Option<(bool, f64, f64, [f64; 3])> = None;
    for r in reds {
        for radius in WAYPOINT_RADII {
            for k in 0..WAYPOINT_DIRECTIONS {
                let angle = std::f64::consts::TAU * k as f64 / WAYPOINT_DIRECTIONS as f64;
                let w = [r[0] + radius * angle.cos(), r[1] + radius * angle.sin(), blue[2]];
                if !on_table(w) || passed(w) {
                    continue;
                }
                let (first, last) = (leg(blue, w, false), leg(w, green, true));
                let ok = first >= 1.0 && last >= LAST_LEG_MARGIN;
                let length = xy_dist(blue, w) + xy_dist(w, green);
                // Clear routes first, shortest among them; otherwise the clearest, in steps of a
                // hundredth, then the shortest: routes that tie (their clearance set by the same
                // red block) must not trade places on the blocks' jitter from one step to the next.
                let key = if ok { (true, 0.0, -length) } else { (false, (first.min(last) * 100.0).floor(), -length) };
                if best.map_or(true, |(o, c, l, _)| key > (o, c, l)) {
                    best = Some((key.0, key.1, key.2, w));
                }
            }
        }
    }
    match best {
        Some((ok, clear, _, w)) if ok || clear > (direct * 100.0).floor() => Some(w),
        _ => None,
    }
}

/// Push `mover` towards `target`: get behind it (over the blocks when not already behind), line
/// up, and push through it, steering back onto the line. Every threshold is a smooth step, so that
/// the action is a continuous function of where the gripper and the block are.
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
    // How far the gripper is lined up behind the block, low: 1 pushes, 0 approaches.
    let lined_up = (1.0 - smoothstep(across.abs(), 0.008, 0.016))
        * (1.0 - smoothstep(along, -0.035, -0.025))
        * (1.0 - smoothstep(grip[2], PUSH_Z + 0.01, PUSH_Z + 0.03));
    // The push: aim through the mover towards the target, steering back onto the line, at most a
    // full action's length ahead, so that the push keeps its direction.
    let push = {
        let aim = [target[0] - across * -d[1] * 2.0, target[1] - across * d[0] * 2.0, PUSH_Z];
        let (dx, dy) = (aim[0] - grip[0], aim[1] - grip[1]);
        let scale = (1.0 / GAIN / dx.hypot(dy).max(1e-9)).min(1.0);
        toward(grip, [grip[0] + dx * scale, grip[1] + dy * scale, PUSH_Z])
    };
    // The approach: to the standoff point, low inside the corridor behind the block or on
    // arriving there, above the blocks elsewhere; near the block and below that height, rise
    // before moving across.
    let corridor = (1.0 - smoothstep(along, -0.05, -0.03)) * (1.0 - smoothstep(across.abs(), 0.03, 0.05));
    let arriving = 1.0 - smoothstep(xy_dist(grip, behind), 0.01, 0.03);
    let high = SAFE_Z.max(grip[2].min(SAFE_Z + 0.05));
    let height = PUSH_Z + (high - PUSH_Z) * (1.0 - corridor.max(arriving));
    let go = (1.0 - smoothstep(height - grip[2], 0.01, 0.03)).max(smoothstep(xy_dist(grip, mover), 0.10, 0.14));
    let approach = toward(grip, [grip[0] + (behind[0] - grip[0]) * go, grip[1] + (behind[1] - grip[1]) * go, height]);
    std::array::from_fn(|k| (lined_up as f32) * push[k] + (1.0 - lined_up as f32) * approach[k])
}
