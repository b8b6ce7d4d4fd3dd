//! The behaviours with the gripper action on: pick blue up and put it on green, or, with several
//! blue blocks, put each on green side by side.

use super::{toward, xy_dist, Behaviour, Seen, SeenBlock, ACTION_DIM};
use crate::sim::rules::Colour;

/// A grasp in progress: whether the block is held, and the steps spent closing the fingers.
#[derive(Debug, Clone, Default)]
struct Grasp {
    /// The block has been grasped.
    grasped: bool,
    /// Steps spent closing the fingers.
    closing: usize,
}

impl Grasp {
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

/// Open, come down around blue, close, lift, carry above green, lower
/// onto it (success ends the episode at the touch). Gripper action on.
#[derive(Debug, Clone, Default)]
pub(super) struct PickPlace {
    grasp: Grasp,
}

impl Behaviour for PickPlace {
    fn act(&mut self, seen: &Seen) -> [f32; ACTION_DIM] {
        let (grip, fingers, blocks) = (seen.grip, seen.fingers, seen.blocks);
        let find = |c: Colour| blocks.iter().find(|b| b.colour == c).map(|b| b.pos);
        let (Some(blue), Some(green)) = (find(Colour::Blue), find(Colour::Green)) else {
            return [0.0; ACTION_DIM];
        };
        let with = |mut a: [f32; ACTION_DIM], g: f32| {
            a[3] = g;
            a
        };
        let held = xy_dist(grip, blue) < 0.02 && (grip[2] - blue[2]).abs() < 0.02;
        if !self.grasp.grasped {
            return self.grasp.grasp(grip, fingers, blue);
        }
        if !held {
            // Dropped: start over.
            self.grasp = Grasp::default();
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

/// Each blue block in turn (the first not yet on green, in observation
/// order): pick it up, carry it above green high enough to pass over the
/// blocks already there, set it down on a free corner of green's top,
/// open the fingers and rise straight up clear of it. Gripper action on,
/// several blue blocks.
#[derive(Debug, Clone, Default)]
pub(super) struct Gather {
    grasp: Grasp,
    /// Steps left opening the fingers over a block just set down.
    releasing: usize,
    /// Rising clear of the blocks set down before moving on.
    rising: bool,
}

impl Behaviour for Gather {
    fn act(&mut self, seen: &Seen) -> [f32; ACTION_DIM] {
        let (grip, fingers, blocks) = (seen.grip, seen.fingers, seen.blocks);
        let with = |mut a: [f32; ACTION_DIM], g: f32| {
            a[3] = g;
            a
        };
        let size = |b: &SeenBlock| seen.sizes.get(b.slot).copied().unwrap_or([0.025; 3]);
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
        if !self.grasp.grasped {
            // The first blue block not on green yet.
            let Some(blue) = blues.iter().find(|b| !on_green(b)) else {
                return with([0.0; ACTION_DIM], 1.0); // all there (success ends the episode)
            };
            return self.grasp.grasp(grip, fingers, blue.pos);
        }
        let in_hand = blues.iter().find(|b| xy_dist(grip, b.pos) < 0.02 && (grip[2] - b.pos[2]).abs() < 0.02);
        let Some(&blue) = in_hand else {
            // Dropped: up, and start over.
            self.grasp = Grasp::default();
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
            self.grasp = Grasp::default();
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
}
