//! The pushing behaviour: get behind the blue block and push it towards the green one (or the
//! green one onto blue, where that path is clearer of grey blocks), around red blocks through a
//! waypoint planned at the episode's first step; with a red gripper, always green onto blue.

use super::{seg_dist, toward, xy_dist, Behaviour, Seen, ACTION_DIM, PUSH_Z, SAFE_Z, STANDOFF};
use crate::sim::rules::Colour;

/// Push blue against green (grey gripper, blocked fingers); around red blocks through a waypoint
/// planned at the episode's first step.
#[derive(Debug, Clone, Default)]
pub(super) struct Push {
    /// The route planned at the episode's first step (with red blocks on the table).
    route: Option<Route>,
    /// Never touch blue (a red gripper): always push green onto blue.
    green_onto_blue: bool,
}

/// A push's route around red blocks: the waypoint and where blue started
/// (none: straight), and whether blue has passed the waypoint.
type Route = (Option<([f64; 3], [f64; 3])>, bool);

impl Behaviour for Push {
    fn act(&mut self, seen: &Seen) -> [f32; ACTION_DIM] {
        let (grip, blocks) = (seen.grip, seen.blocks);
        let find = |c: Colour| blocks.iter().find(|b| b.colour == c).map(|b| b.pos);
        let (Some(blue), Some(green)) = (find(Colour::Blue), find(Colour::Green)) else {
            return [0.0; ACTION_DIM];
        };
        if self.green_onto_blue {
            return push_line(grip, green, blue);
        }
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
}

impl Push {
    /// Whether it pushes green onto blue whatever the layout.
    pub(super) fn pushes_green(&self) -> bool {
        self.green_onto_blue
    }

    /// The push of a red gripper, which must never touch blue: green onto blue, straight.
    pub(super) fn green_onto_blue() -> Self {
        Self { route: None, green_onto_blue: true }
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
