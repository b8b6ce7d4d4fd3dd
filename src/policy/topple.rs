//! The toppling behaviour: a red gripper swipes the tower's base out from under the blue block.

use super::{toward, xy_dist, Seen, ACTION_DIM, GAIN};
use crate::sim::rules::Colour;

/// The y of the table's centre line.
const TABLE_CENTRE_Y: f64 = 0.75;
/// Topple: grip height of the swipe (fingertips just above the table).
const TOPPLE_Z: f64 = 0.425;
/// Topple: distance from the tower's centre to the start of the swipe.
const TOPPLE_STANDOFF: f64 = 0.12;
/// Topple: speed of the swipe (action units: 0.4 is 2 cm a step; faster
/// throws blue off the table, slower lets the tower ride on the gripper).
const TOPPLE_SPEED: f64 = 0.4;
/// Topple: how far off the swipe's line (across it) the grip may be and still swipe.
const LINE: f64 = 0.015;
/// Topple: grip travel along y in a step (the observation's velocity × dt) that marks a swipe under
/// way (a swipe goes about 0.013 a step).
const SWIPING: f64 = 0.008;
/// Topple: how far ahead on the line a block being pushed may be.
const BASE_AHEAD: f64 = 0.16;
/// Topple: within this distance along the line the grip is against the base, pushing it.
const CONTACT: f64 = 0.08;

/// Knock the tower under the blue block over without touching blue (red gripper): come down to
/// just above the table (there the whole gripper passes under the blue block) away from the tower,
/// go round to the side of the base farther from the table's centre line, then swipe through the
/// base at full speed along y (along x the wrist leads the fingers) towards the centre line. The
/// gripper's body hits the pillar too, so the tower falls ahead of it onto the table, and the
/// gripper passes under blue as it comes down. (Designed on ToppleTower-v0's tall tower, whose
/// blue block is above the gripper's body when the fingertips skim the table.)
///
/// Every phase is read off the observation: the swipe is under way wherever the grip is low, on
/// the line along y through the base and behind it within the swipe's start; it goes on the way
/// it points (towards the base); then, moving fast and straight along y with a block ahead on the
/// line (whose line it holds), it goes on as the tower falls, until no block stands under blue.
pub(super) fn topple(seen: &Seen) -> [f32; ACTION_DIM] {
    let (grip, blocks) = (seen.grip, seen.blocks);
    // The blue block nearest the gripper (a tower has one).
    let Some(blue) = super::nearest(blocks, Colour::Blue, grip, |_| true).map(|b| b.pos) else {
        return [0.0; ACTION_DIM];
    };
    let low = grip[2] < TOPPLE_Z + 0.01;
    let hold = |e: f64| (e * GAIN).clamp(-1.0, 1.0);
    // Full speed along y, holding the height and the line x = `line`.
    let swipe = |dy: f64, line: f64| {
        [hold(line - grip[0]) as f32, (dy * TOPPLE_SPEED) as f32, hold(TOPPLE_Z - grip[2]) as f32, 0.0]
    };
    // The tower's base: the lowest non-blue block under blue.
    let base = blocks
        .iter()
        .filter(|b| b.colour != Colour::Blue && xy_dist(b.pos, blue) < 0.04)
        .map(|b| b.pos)
        .min_by(|a, b| a[2].total_cmp(&b[2]));
    let Some(base) = base else {
        return [0.0; ACTION_DIM]; // no tower under blue: nothing to do (or the swipe is done)
    };
    // A swipe under way: low, moving fast and straight along y, a grey block ahead on the line
    // (the base, pushed along). It goes on as the tower falls, while a block stands under blue.
    let [vx, vy] = [seen.grip_vel[0], seen.grip_vel[1]];
    if low && vy.abs() >= SWIPING && vx.abs() < SWIPING / 2.0 {
        let d = vy.signum();
        let ahead = |b: &&super::SeenBlock| (b.pos[1] - grip[1]) * d;
        let pushed = blocks
            .iter()
            .filter(|b| {
                b.colour != Colour::Blue
                    && (b.pos[0] - grip[0]).abs() < 2.0 * LINE
                    && (0.0..BASE_AHEAD).contains(&ahead(b))
            })
            .min_by(|a, b| ahead(a).total_cmp(&ahead(b)));
        if let Some(pushed) = pushed {
            return swipe(d, pushed.pos[0]); // on the line of the block it pushes
        }
    }
    // The swipe goes towards the centre line, from the base's side farther from it.
    let inwards = if base[1] >= TABLE_CENTRE_Y { -1.0 } else { 1.0 };
    let behind = base[1] - grip[1];
    // On the swipe's line (along y through the base), behind the base within the swipe's start:
    // on its far side, or already against it (a base pushed over the centre line is followed).
    let swiping = low
        && (grip[0] - base[0]).abs() < LINE
        && behind.abs() <= TOPPLE_STANDOFF + LINE
        && behind != 0.0
        && (behind.signum() == inwards || behind.abs() < CONTACT);
    let d = [0.0, if swiping { behind.signum() } else { inwards }];
    if swiping {
        return swipe(d[1], base[0]);
    }
    let rel = [grip[0] - base[0], grip[1] - base[1]];
    let along = rel[0] * d[0] + rel[1] * d[1];
    let across = rel[0] * -d[1] + rel[1] * d[0];
    let at = |along: f64, across: f64, z: f64| {
        [base[0] + d[0] * along - d[1] * across, base[1] + d[1] * along + d[0] * across, z]
    };
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
