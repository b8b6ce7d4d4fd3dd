//! The observation vector (f32), laid out as in the paper and gymnasium-robotics.
//!
//! Robot part (10): grip position (3), finger positions (2), grip linear
//! velocity × dt (3), finger velocities × dt (2). Then per block, in scene
//! order (19): position (3), position relative to the grip (3), orientation
//! as Euler angles (3), linear velocity relative to the grip × dt (3),
//! angular velocity × dt (3), colour one-hot (red, blue, green, grey) (4).

use crate::math::mat2euler;
use crate::mj::{Data, ObjType};
use crate::rules::Colour;
use crate::scene::Scene;

/// Robot features.
pub const ROBOT_OBS: usize = 10;
/// Features per block.
pub const BLOCK_OBS: usize = 19;

/// Observation size for `n_blocks` blocks.
pub const fn obs_dim(n_blocks: usize) -> usize {
    ROBOT_OBS + BLOCK_OBS * n_blocks
}

fn site_velocity(data: &Data, site: usize) -> [f64; 6] {
    // Site ids come from the compiled scene, so they are always in range.
    data.object_velocity(ObjType::Site, site, false).unwrap_or([0.0; 6])
}

/// Writes the observation of `data` into `out` (resized as needed), with
/// `colours` the blocks' colours this episode.
pub fn write(scene: &Scene, data: &Data, dt: f64, colours: &[Colour], out: &mut Vec<f32>) {
    out.clear();
    let grip = data.site_xpos()[scene.grip_site];
    let gv = site_velocity(data, scene.grip_site);
    let grip_velp = [gv[3] * dt, gv[4] * dt, gv[5] * dt];
    let (q, v) = (data.qpos(), data.qvel());
    out.extend(grip.iter().map(|&x| x as f32));
    out.extend(scene.finger_qpos.iter().map(|&a| q[a] as f32));
    out.extend(grip_velp.iter().map(|&x| x as f32));
    out.extend(scene.finger_dof.iter().map(|&a| (v[a] * dt) as f32));
    for (block, colour) in scene.blocks.iter().zip(colours) {
        let pos = data.site_xpos()[block.site];
        let euler = mat2euler(&data.site_xmat()[block.site]);
        let bv = site_velocity(data, block.site);
        out.extend(pos.iter().map(|&x| x as f32));
        out.extend((0..3).map(|k| (pos[k] - grip[k]) as f32));
        out.extend(euler.iter().map(|&x| x as f32));
        out.extend((0..3).map(|k| (bv[3 + k] * dt - grip_velp[k]) as f32));
        out.extend((0..3).map(|k| (bv[k] * dt) as f32));
        out.extend(colour.one_hot());
    }
}
