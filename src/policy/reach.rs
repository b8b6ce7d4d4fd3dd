//! The reaching behaviour: a blue gripper onto the green block, over any red block in the way.

use super::{toward, xy_dist, Seen, ACTION_DIM};
use crate::sim::rules::Colour;

/// Height of the table top.
const TABLE_TOP: f64 = 0.4;
/// How far the fingertips reach below the grip site.
const FINGERTIP_BELOW: f64 = 0.0185;

/// Onto the green block nearest the gripper (blue gripper); while red blocks stand around, first
/// above the highest red top (a block's top is read from its centre height).
pub(super) fn reach(seen: &Seen) -> [f32; ACTION_DIM] {
    {
        let (grip, blocks) = (seen.grip, seen.blocks);
        let Some(g) = super::nearest(blocks, Colour::Green, grip, |_| true) else {
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
