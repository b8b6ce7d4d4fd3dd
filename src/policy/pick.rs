//! The behaviours with the gripper action on: pick blue up and put it on green, or, with several
//! blue blocks, put each on green side by side. Both are functions of one observation: whether a
//! block is held is read off the fingers (closed on something and at rest, around the block), and
//! whether a block is being let go off the blocks on green and the fingers' aperture.

use super::{nearest, smoothstep, toward, xy_dist, Seen, SeenBlock, ACTION_DIM};
use crate::sim::rules::Colour;

/// Finger aperture (the two finger joints' sum) above which the fingers count as open.
const OPEN: f64 = 0.07;
/// Aperture below which closed fingers hold nothing (a block is 4 cm or more wide).
const EMPTY: f64 = 0.02;
/// Finger speed (joint travel per step, both fingers together) below which the fingers are at rest:
/// closing they travel 0.014 or more a step, and closed on a block they bounce back about 0.005.
const AT_REST: f64 = 0.008;

/// `action` with the gripper command `g` (1 opens, -1 closes).
fn with(mut action: [f32; ACTION_DIM], g: f32) -> [f32; ACTION_DIM] {
    action[3] = g;
    action
}

/// The fingers' aperture.
fn aperture(seen: &Seen) -> f64 {
    seen.fingers[0] + seen.fingers[1]
}

/// The grip site is at the block at `at`: centred on it, at its height.
fn around(seen: &Seen, at: [f64; 3]) -> bool {
    xy_dist(seen.grip, at) < 0.02 && (seen.grip[2] - at[2]).abs() < 0.02
}

/// The fingers hold the block at `at`: around it, closed on something and at rest.
fn holds(seen: &Seen, at: [f64; 3]) -> bool {
    let a = aperture(seen);
    let still = seen.finger_vel[0].abs() + seen.finger_vel[1].abs() < AT_REST;
    around(seen, at) && (EMPTY..OPEN).contains(&a) && still
}

/// Within this distance (in the plane) of the block's centre the grip comes all the way down; beyond
/// [`FUNNEL_WIDE`] it stays above the block; between, its height is a smooth step of the distance.
const FUNNEL_NARROW: f64 = 0.012;
const FUNNEL_WIDE: f64 = 0.025;
/// Down at the block and within this distance of its centre, the fingers close. Open, the fingers
/// are 10 cm apart and the blocks at most 6 cm wide; the arm near the far edge of its reach can
/// settle a centimetre off the target, so the grasp must not ask for less.
const CLOSE_WITHIN: f64 = 0.02;

/// Open above the block at `at` (travelling no lower than `travel_z`), come down around it and
/// close. Whether it is held is [`holds`]'s to say, from what the fingers show. The way down is a
/// funnel: the grip's height is a smooth step of how far it is from the block's centre, so that the
/// action is a continuous function of where the grip is (a threshold here left the arm hovering a
/// few millimetres out, or rising and coming down again as closing fingers nudged it).
fn grasp(seen: &Seen, at: [f64; 3], travel_z: f64) -> [f32; ACTION_DIM] {
    let grip = seen.grip;
    let open = aperture(seen) > OPEN;
    let off = xy_dist(grip, at);
    if grip[2] <= at[2] + 0.005 && off < CLOSE_WITHIN {
        // Down around it: close until the fingers rest on the block. Fingers that closed on nothing,
        // or are opening again after that, open all the way first.
        let opening = seen.finger_vel[0] + seen.finger_vel[1] > AT_REST;
        let empty = aperture(seen) < EMPTY;
        if (empty || opening) && !open {
            return with([0.0; ACTION_DIM], 1.0);
        }
        return with([0.0; ACTION_DIM], -1.0);
    }
    // Above the block, fingers opening; coming down as the grip centres on it, once they are open.
    let high = (at[2] + 0.06).max(grip[2].min(at[2] + 0.08)).max(travel_z);
    let down = if open { 1.0 - smoothstep(off, FUNNEL_NARROW, FUNNEL_WIDE) } else { 0.0 };
    with(toward(grip, [at[0], at[1], high + (at[2] - high) * down]), 1.0)
}

/// Open, come down around blue, close, lift, carry above green, lower onto it (success ends the
/// episode at the touch). Gripper action on.
pub(super) fn pick_place(seen: &Seen) -> [f32; ACTION_DIM] {
    let (grip, blocks) = (seen.grip, seen.blocks);
    // Blue nearest the gripper, and the green block nearest to it.
    let Some(blue) = nearest(blocks, Colour::Blue, grip, |_| true).map(|b| b.pos) else {
        return [0.0; ACTION_DIM];
    };
    let Some(green) = nearest(blocks, Colour::Green, blue, |_| true).map(|b| b.pos) else {
        return [0.0; ACTION_DIM];
    };
    if !holds(seen, blue) {
        return grasp(seen, blue, 0.0);
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

/// Each blue block in turn: the one held, else the one with the least y of those not on green yet
/// (by where the blocks are, not by their order in the observation).
/// Pick it up, carry it above green high enough to pass over the blocks already there, set it down
/// on a free corner of green's top, open the fingers and rise straight up clear of it. Gripper
/// action on, several blue blocks.
pub(super) fn gather(seen: &Seen) -> [f32; ACTION_DIM] {
    let (grip, blocks) = (seen.grip, seen.blocks);
    let size = |b: &SeenBlock| seen.sizes.get(b.slot).copied().unwrap_or([0.025; 3]);
    // The green block nearest the gripper (a tray, as the family draws it).
    let Some(green) = nearest(blocks, Colour::Green, grip, |_| true) else {
        return [0.0; ACTION_DIM];
    };
    let (g, gs) = (green.pos, size(green));
    let top = g[2] + gs[2];
    let on_green = |b: &SeenBlock| {
        (b.pos[0] - g[0]).abs() < gs[0]
            && (b.pos[1] - g[1]).abs() < gs[1]
            && (b.pos[2] - top - size(b)[2]).abs() < 0.006
    };
    let blues: Vec<&SeenBlock> = blocks.iter().filter(|b| b.colour == Colour::Blue).collect();
    // Where `blue` goes: a free corner of green's top (a block's width in from the edges), away
    // from the blue blocks already there.
    let spot = |blue: &SeenBlock| {
        let bh = size(blue)[2];
        let inset = [(gs[0] - bh - 0.01).max(0.0), (gs[1] - bh - 0.01).max(0.0)];
        let placed: Vec<[f64; 3]> =
            blues.iter().filter(|b| b.slot != blue.slot && on_green(b)).map(|b| b.pos).collect();
        [[-1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [1.0, -1.0]]
            .iter()
            .map(|c| [g[0] + c[0] * inset[0], g[1] + c[1] * inset[1], 0.0])
            .find(|p| placed.iter().all(|&q| xy_dist(*p, q) > 2.0 * bh))
            .unwrap_or([g[0], g[1], 0.0])
    };
    let set_down =
        |b: &SeenBlock| on_green(b) || (xy_dist(b.pos, spot(b)) <= 0.006 && b.pos[2] < top + size(b)[2] + 0.003);
    // Letting go: around a blue block that is set down, fingers not open yet.
    if aperture(seen) <= OPEN && blues.iter().any(|b| around(seen, b.pos) && set_down(b)) {
        return with([0.0; ACTION_DIM], 1.0);
    }
    if let Some(blue) = nearest(blocks, Colour::Blue, grip, |b| holds(seen, b.pos)) {
        // Carry with blue's bottom 3 cm above the tops of the blocks already on green.
        let (bh, spot) = (size(blue)[2], spot(blue));
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
        return with(toward(grip, [grip[0], grip[1], top + bh - 0.01]), -1.0);
    }
    // The next blue block: the one with the least y (then x) of those not on green. A fixed order
    // of where the blocks are, not the nearest to the gripper, so the choice does not waver as the
    // gripper moves, and blocks at like distances are not averaged into a way between them.
    let next = blues.iter().copied().filter(|b| !on_green(b)).min_by(|a, b| {
        a.pos[1].total_cmp(&b.pos[1]).then(a.pos[0].total_cmp(&b.pos[0])).then(a.pos[2].total_cmp(&b.pos[2]))
    });
    let Some(next) = next else {
        return with([0.0; ACTION_DIM], 1.0); // all there (success ends the episode)
    };
    // Over green (and the blocks set down there) and not at the next block: pass above them,
    // rising straight up first where the grip is low.
    let over_green = (grip[0] - g[0]).abs() < gs[0] + 0.03 && (grip[1] - g[1]).abs() < gs[1] + 0.03;
    let clear_of_blocks = over_green && xy_dist(grip, next.pos) > 0.02;
    if clear_of_blocks && grip[2] < top + 0.09 {
        return with(toward(grip, [grip[0], grip[1], top + 0.10]), 1.0);
    }
    grasp(seen, next.pos, if clear_of_blocks { top + 0.095 } else { 0.0 })
}
