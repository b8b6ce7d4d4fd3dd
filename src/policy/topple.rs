//! The toppling behaviour: a red gripper swipes the tower's base out from under the blue block.

use super::{toward, xy_dist, Behaviour, Seen, ACTION_DIM, GAIN};
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
/// Topple: how far past the tower's centre the swipe goes.
const TOPPLE_THROUGH: f64 = 0.10;

/// Knock the tower under the blue block over without touching blue (red gripper).
#[derive(Debug, Clone, Default)]
pub(super) struct Topple {
    /// The swipe's direction and the base's first position, fixed for the episode.
    push: Option<[f64; 4]>,
    /// The swipe is under way.
    swiping: bool,
    /// The swipe is done; keep still.
    swiped: bool,
}

impl Behaviour for Topple {
    /// Knock the tower's base out from under it: come down to just above
    /// the table (there the whole gripper passes under the blue block) away
    /// from the tower, go round to the side of the base farther from the
    /// table's centre line, then swipe through the base at full speed along y
    /// (along x the wrist leads the fingers) towards the centre line. The
    /// gripper's body hits the pillar too, so the tower falls ahead of it onto
    /// the table, and the gripper passes under blue as it comes down.
    /// (Designed on ToppleTower-v0's tall tower, whose blue block is above the
    /// gripper's body when the fingertips skim the table.)
    fn act(&mut self, seen: &Seen) -> [f32; ACTION_DIM] {
        let (grip, blocks) = (seen.grip, seen.blocks);
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
}
