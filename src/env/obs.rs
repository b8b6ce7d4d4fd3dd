//! The observation: what it holds ([`ObsSpec`]) and how it is read off the
//! simulation ([`write`]), laid out as in the paper and gymnasium-robotics.
//!
//! Robot part (10): grip position (3), finger positions (2), grip linear
//! velocity × dt (3), finger velocities × dt (2). Then per block, in scene
//! order (19): position (3), position relative to the grip (3), orientation
//! as Euler angles (3), linear velocity relative to the grip × dt (3),
//! angular velocity × dt (3), colour one-hot (red, blue, green, grey) (4).
//! In the `objects` mode each object row also holds the object's half
//! extents (3), and a mask follows the rows (1 per object slot present).
//! The `entities` mode adds a type one-hot (gripper, table, floor, block) to
//! each row, and after the blocks' rows one row for each of the other rule
//! objects: the gripper, the table and the floor (see [`ObsMode::Entities`]).

use crate::sim::mj::{Data, ObjType};
use crate::sim::rules::Colour;
use crate::sim::scene::Scene;
use crate::support::math::mat2euler;
use serde::{Deserialize, Serialize};

/// Robot features.
pub const ROBOT_OBS: usize = ROBOT_FEATURES.len();
/// Features per block.
pub const BLOCK_OBS: usize = OBJECT_FEATURES.len();

/// The robot features' names, in order.
pub const ROBOT_FEATURES: [&str; 10] = [
    "grip_pos.x",
    "grip_pos.y",
    "grip_pos.z",
    "finger_pos.0",
    "finger_pos.1",
    "grip_velp.x",
    "grip_velp.y",
    "grip_velp.z",
    "finger_vel.0",
    "finger_vel.1",
];

/// Each object's features' names, in order (the colour one-hot last).
pub const OBJECT_FEATURES: [&str; 19] = [
    "pos.x",
    "pos.y",
    "pos.z",
    "rel_pos.x",
    "rel_pos.y",
    "rel_pos.z",
    "euler.x",
    "euler.y",
    "euler.z",
    "rel_velp.x",
    "rel_velp.y",
    "rel_velp.z",
    "velr.x",
    "velr.y",
    "velr.z",
    "colour.red",
    "colour.blue",
    "colour.green",
    "colour.grey",
];

/// Where an object row's colour one-hot (red, blue, green, grey) begins.
pub const COLOUR_FEATURE: usize = 15;

/// The features an object row has in the `objects` mode after [`OBJECT_FEATURES`]: its half extents.
pub const SIZE_FEATURES: [&str; 3] = ["size.x", "size.y", "size.z"];

/// The features a row has in the `entities` mode after [`OBJECT_FEATURES`]: its half extents, then
/// what it is (one-hot).
pub const ENTITY_FEATURES: [&str; 7] =
    ["size.x", "size.y", "size.z", "type.gripper", "type.table", "type.floor", "type.block"];

/// Where a row's type one-hot (gripper, table, floor, block) begins, in the `entities` mode.
pub const TYPE_FEATURE: usize = OBJECT_FEATURES.len() + SIZE_FEATURES.len();

/// The rule objects other than blocks, in the order of their rows in the `entities` mode (after
/// the blocks' rows). Saved policies record their mode's list (`fixtures`), so a file written
/// before a change to it is refused rather than misread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Fixture {
    /// The gripper: both fingers and the gripper link.
    Gripper,
    /// The table.
    Table,
    /// The floor (a rule object only where the task colours it).
    Floor,
}

impl Fixture {
    /// Every fixture, in row order.
    pub const ALL: [Fixture; 3] = [Fixture::Gripper, Fixture::Table, Fixture::Floor];

    /// Its name in the observation's component names.
    pub fn name(self) -> &'static str {
        match self {
            Fixture::Gripper => "gripper",
            Fixture::Table => "table",
            Fixture::Floor => "floor",
        }
    }

    /// Its type one-hot (gripper, table, floor, block).
    pub fn one_hot(self) -> [f32; 4] {
        let mut v = [0.0; 4];
        v[self as usize] = 1.0;
        v
    }
}

/// A block's type one-hot (gripper, table, floor, block).
pub const BLOCK_TYPE: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

/// Observation size for `n_blocks` blocks (the flat mode).
pub const fn obs_dim(n_blocks: usize) -> usize {
    ROBOT_OBS + BLOCK_OBS * n_blocks
}

/// How an environment presents its observation, chosen per environment
/// (like ManiSkill's `obs_mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObsMode {
    /// One vector: the robot features, then each object's (the paper's; every id's default).
    #[default]
    Flat,
    /// Object-centric: the robot features, a (max objects × features) array
    /// and a mask of the slots holding an object (Gymnasium: a `Dict` of
    /// `robot`, `objects`, `mask`); in one vector laid out robot | objects
    /// (row by row) | mask.
    Objects,
    /// Every rule object a row: the blocks' rows (as in `objects`, each with a
    /// type one-hot after its size), then the gripper's, the table's and the
    /// floor's, so that every colour that decides the rules is observed
    /// (Gymnasium: a `Dict` of `robot`, `entities`, `mask`). The floor's row
    /// is present (mask 1) only where the task makes the floor a rule object.
    Entities,
}

/// What depends on the mode lives here, each in a `match` the compiler checks for every mode: a
/// new mode is a compile error wherever it must be handled (Python reads the results through
/// `obs_layout`'s `mode`, `object_dim`, `dim`, `names` and `mask`, and checks its own layouts
/// against [`ObsMode::ALL`]).
impl ObsMode {
    /// Every mode, in the order the docs list them.
    pub const ALL: [ObsMode; 3] = [ObsMode::Flat, ObsMode::Objects, ObsMode::Entities];

    /// Whether it is the `entities` mode (the solver's, the demonstrations' and the generalist's),
    /// decided here by a `match`, not by `==` at each caller.
    pub fn is_entities(self) -> bool {
        match self {
            ObsMode::Entities => true,
            ObsMode::Flat | ObsMode::Objects => false,
        }
    }

    /// Its name, as `obs_mode` takes it.
    pub fn name(self) -> &'static str {
        match self {
            ObsMode::Flat => "flat",
            ObsMode::Objects => "objects",
            ObsMode::Entities => "entities",
        }
    }

    /// The features of an object row after [`OBJECT_FEATURES`].
    pub fn extra_object_features(self) -> &'static [&'static str] {
        match self {
            ObsMode::Flat => &[],
            ObsMode::Objects => &SIZE_FEATURES,
            ObsMode::Entities => &ENTITY_FEATURES,
        }
    }

    /// The rule objects other than blocks that have a row, after the blocks'.
    pub fn fixtures(self) -> &'static [Fixture] {
        match self {
            ObsMode::Flat | ObsMode::Objects => &[],
            ObsMode::Entities => &Fixture::ALL,
        }
    }

    /// Whether the observation ends with a mask of the slots holding an object.
    pub fn has_mask(self) -> bool {
        match self {
            ObsMode::Flat => false,
            ObsMode::Objects | ObsMode::Entities => true,
        }
    }

    /// Whether a set network reads it: rows of one layout, any number of them, and a mask.
    pub fn is_set(self) -> bool {
        match self {
            ObsMode::Flat => false,
            ObsMode::Objects | ObsMode::Entities => true,
        }
    }

    /// The name of its rows in Python's `Dict` space (`None`: one flat `Box`).
    pub fn rows_key(self) -> Option<&'static str> {
        match self {
            ObsMode::Flat => None,
            ObsMode::Objects => Some("objects"),
            ObsMode::Entities => Some("entities"),
        }
    }
}

impl std::fmt::Display for ObsMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ObsMode {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            let known: Vec<String> = Self::ALL.iter().map(|m| format!("{:?}", m.name())).collect();
            format!("unknown observation mode {s:?}; use {}", known.join(" or "))
        })
    }
}

/// What an observation holds and where: every reader (replay, normaliser,
/// networks, the expert's view, scripted controllers, Python's spaces)
/// takes shapes and offsets from here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ObsSpec {
    /// The layout.
    pub mode: ObsMode,
    /// Block slots (the compiled scene's blocks).
    pub max_objects: usize,
}

impl ObsSpec {
    /// The spec of `mode` with `max_objects` object slots.
    pub fn new(mode: ObsMode, max_objects: usize) -> Self {
        Self { mode, max_objects }
    }

    /// The flat spec with `n` objects.
    pub fn flat(n: usize) -> Self {
        Self::new(ObsMode::Flat, n)
    }

    /// Robot features.
    pub fn robot_dim(&self) -> usize {
        ROBOT_OBS
    }

    /// Features per row: [`OBJECT_FEATURES`], then in the `objects` mode [`SIZE_FEATURES`], in the
    /// `entities` mode [`ENTITY_FEATURES`].
    pub fn object_dim(&self) -> usize {
        BLOCK_OBS + self.mode.extra_object_features().len()
    }

    /// Rows: one per block slot, then in the `entities` mode one per [`Fixture`].
    pub fn rows(&self) -> usize {
        self.max_objects + self.mode.fixtures().len()
    }

    /// The observation vector's length.
    pub fn dim(&self) -> usize {
        let mask = if self.mode.has_mask() { self.rows() } else { 0 };
        ROBOT_OBS + self.object_dim() * self.rows() + mask
    }

    /// The row of `fixture` (an index among [`ObsSpec::rows`]), where the mode has one.
    pub fn fixture_row(&self, fixture: Fixture) -> Option<usize> {
        self.mode.fixtures().iter().position(|&f| f == fixture).map(|i| self.max_objects + i)
    }

    /// Every row of `obs` (blocks, then the fixtures), one slice of [`ObsSpec::object_dim`] values each.
    pub fn all_rows<'a>(&self, obs: &'a [f32]) -> std::slice::ChunksExact<'a, f32> {
        let end = (ROBOT_OBS + self.object_dim() * self.rows()).min(obs.len());
        obs[ROBOT_OBS.min(end)..end].chunks_exact(self.object_dim())
    }

    /// The robot features of `obs`.
    pub fn robot<'a>(&self, obs: &'a [f32]) -> &'a [f32] {
        &obs[..ROBOT_OBS.min(obs.len())]
    }

    /// The blocks' rows of `obs`, one slice of [`ObsSpec::object_dim`] values per slot.
    pub fn objects<'a>(&self, obs: &'a [f32]) -> std::slice::ChunksExact<'a, f32> {
        let end = (ROBOT_OBS + self.object_dim() * self.max_objects).min(obs.len());
        obs[ROBOT_OBS.min(end)..end].chunks_exact(self.object_dim())
    }

    /// The mask of `obs` (1 for a row holding an object, one per [`ObsSpec::rows`]), in the modes that have one.
    pub fn mask<'a>(&self, obs: &'a [f32]) -> Option<&'a [f32]> {
        self.mode.has_mask().then(|| &obs[(ROBOT_OBS + self.object_dim() * self.rows()).min(obs.len())..])
    }

    /// The colour one-hot (red, blue, green, grey) of an object row.
    pub fn colour(row: &[f32]) -> &[f32] {
        &row[COLOUR_FEATURE.min(row.len())..(COLOUR_FEATURE + 4).min(row.len())]
    }

    /// The observation with the object rows `keep` refuses left out, in the
    /// flat layout (e.g. AggreVaTeD's expert view without grey blocks).
    pub fn keep_objects(&self, obs: &[f32], keep: impl Fn(&[f32]) -> bool) -> Vec<f32> {
        let mut out = self.robot(obs).to_vec();
        for row in self.objects(obs).filter(|r| keep(r)) {
            out.extend_from_slice(row);
        }
        out
    }

    /// Every component's name, in order: `robot/grip_pos.x`, …,
    /// `object0/pos.x`, …, in the `entities` mode `gripper/pos.x`, …,
    /// `table/…`, `floor/…`, and where there is a mask `mask/0`, … (in the
    /// `entities` mode ending `mask/gripper`, `mask/table`, `mask/floor`).
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = ROBOT_FEATURES.iter().map(|f| format!("robot/{f}")).collect();
        let extra = self.mode.extra_object_features();
        let rows: Vec<String> = (0..self.max_objects)
            .map(|k| format!("object{k}"))
            .chain(self.mode.fixtures().iter().map(|f| f.name().to_owned()))
            .collect();
        for row in &rows {
            names.extend(OBJECT_FEATURES.iter().chain(extra).map(|f| format!("{row}/{f}")));
        }
        if self.mode.has_mask() {
            names.extend((0..self.max_objects).map(|k| format!("mask/{k}")));
            names.extend(self.mode.fixtures().iter().map(|f| format!("mask/{}", f.name())));
        }
        names
    }
}

fn site_velocity(data: &Data, site: usize) -> [f64; 6] {
    // Site ids come from the compiled scene, so they are always in range.
    data.object_velocity(ObjType::Site, site, false).unwrap_or([0.0; 6])
}

/// The colours of the rule objects other than blocks this episode: what the
/// `entities` mode's fixture rows show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FixtureColours {
    /// The gripper's.
    pub gripper: Colour,
    /// The table's.
    pub table: Colour,
    /// The floor's, where it is a rule object.
    pub floor: Option<Colour>,
}

/// What [`write`] reads besides the simulation: the layout, and the blocks'
/// colours this episode and half extents.
pub struct ObsContext<'a> {
    /// The layout.
    pub spec: &'a ObsSpec,
    /// Each block's colour this episode.
    pub colours: &'a [Colour],
    /// Each block's half extents.
    pub sizes: &'a [[f64; 3]],
    /// Which blocks take part in the episode (an absent one's row is zero, its mask 0).
    pub present: &'a [bool],
    /// The gripper's, table's and floor's colours this episode.
    pub fixtures: FixtureColours,
    /// Offsets (m) of the positions reported this step: the grip's, then each block's (a task's
    /// `physics.obs_noise`); empty: none.
    pub noise: &'a [[f64; 3]],
}

/// The half extents of the world-aligned box around box geom `g`.
fn box_extents(scene: &Scene, data: &Data, g: usize) -> ([f64; 3], [f64; 3]) {
    let (c, m, s) = (data.geom_xpos()[g], data.geom_xmat()[g], scene.model.geom_size()[g]);
    (c, std::array::from_fn(|i| (0..3).map(|j| m[3 * i + j].abs() * s[j]).sum()))
}

/// Writes the observation of `data` into `out` (resized as needed).
pub fn write(ctx: &ObsContext, scene: &Scene, data: &Data, dt: f64, out: &mut Vec<f32>) {
    let (spec, colours) = (ctx.spec, ctx.colours);
    out.clear();
    let offset = |k: usize| ctx.noise.get(k).copied().unwrap_or([0.0; 3]);
    let shift = |p: [f64; 3], k: usize| -> [f64; 3] { std::array::from_fn(|i| p[i] + offset(k)[i]) };
    let grip = shift(data.site_xpos()[scene.grip_site], 0);
    let gv = site_velocity(data, scene.grip_site);
    let grip_velp = [gv[3] * dt, gv[4] * dt, gv[5] * dt];
    let (q, v) = (data.qpos(), data.qvel());
    out.extend(grip.iter().map(|&x| x as f32));
    out.extend(scene.finger_qpos.iter().map(|&a| q[a] as f32));
    out.extend(grip_velp.iter().map(|&x| x as f32));
    out.extend(scene.finger_dof.iter().map(|&a| (v[a] * dt) as f32));
    let row = spec.object_dim();
    // One row: position, position relative to the grip, orientation, linear velocity relative to
    // the grip and angular velocity (both per step), colour; then the mode's extra features.
    let put = |out: &mut Vec<f32>, pos: [f64; 3], xmat: &[f64; 9], vel: [f64; 6], colour: Colour, extra: &[f32]| {
        let euler = mat2euler(xmat);
        out.extend(pos.iter().map(|&x| x as f32));
        out.extend((0..3).map(|k| (pos[k] - grip[k]) as f32));
        out.extend(euler.iter().map(|&x| x as f32));
        out.extend((0..3).map(|k| (vel[3 + k] * dt - grip_velp[k]) as f32));
        out.extend((0..3).map(|k| (vel[k] * dt) as f32));
        out.extend(colour.one_hot());
        out.extend_from_slice(extra);
    };
    for (k, (block, &colour)) in scene.blocks.iter().zip(colours).enumerate() {
        if !ctx.present.get(k).copied().unwrap_or(true) {
            out.extend(std::iter::repeat(0.0).take(row));
            continue;
        }
        let size = ctx.sizes.get(k).map_or([0.0; 3], |s| s.map(|v| v as f32));
        let (pos, xmat, vel) = (
            shift(data.site_xpos()[block.site], k + 1),
            &data.site_xmat()[block.site],
            site_velocity(data, block.site),
        );
        match spec.mode {
            ObsMode::Flat => put(out, pos, xmat, vel, colour, &[]),
            ObsMode::Objects => put(out, pos, xmat, vel, colour, &size),
            ObsMode::Entities => {
                let extra: Vec<f32> = size.iter().chain(&BLOCK_TYPE).copied().collect();
                put(out, pos, xmat, vel, colour, &extra)
            }
        }
    }
    // Slots beyond the task's blocks (a layout shared by several tasks): absent rows.
    let padding = spec.max_objects.saturating_sub(scene.blocks.len());
    out.extend(std::iter::repeat(0.0).take(row * padding));
    for &fixture in spec.mode.fixtures() {
        let with = |size: [f64; 3]| -> Vec<f32> { size.iter().map(|&v| v as f32).chain(fixture.one_hot()).collect() };
        match fixture {
            // At the grip site, its orientation, the fingers' box around both fingers.
            Fixture::Gripper => {
                let [(ca, ea), (cb, eb)] = scene.finger_geoms.map(|g| box_extents(scene, data, g));
                let size = std::array::from_fn(|i| {
                    ((ca[i] + ea[i]).max(cb[i] + eb[i]) - (ca[i] - ea[i]).min(cb[i] - eb[i])) / 2.0
                });
                put(out, grip, &data.site_xmat()[scene.grip_site], gv, ctx.fixtures.gripper, &with(size))
            }
            // The centre of the table's top, the table box's half extents.
            Fixture::Table => {
                let g = scene.table_geom;
                let (c, m, s) = (data.geom_xpos()[g], data.geom_xmat()[g], scene.model.geom_size()[g]);
                let top = std::array::from_fn(|i| c[i] + m[3 * i + 2] * s[2]);
                let vel = data.object_velocity(ObjType::Geom, g, false).unwrap_or([0.0; 6]);
                put(out, top, &m, vel, ctx.fixtures.table, &with(s))
            }
            // The point of the floor under the grip, size 0 (a plane without bounds); a zero row
            // where the floor is not a rule object.
            Fixture::Floor => match ctx.fixtures.floor {
                Some(colour) => {
                    let g = scene.floor_geom;
                    let point = [grip[0], grip[1], data.geom_xpos()[g][2]];
                    put(out, point, &data.geom_xmat()[g], [0.0; 6], colour, &with([0.0; 3]))
                }
                None => out.extend(std::iter::repeat(0.0).take(row)),
            },
        }
    }
    if spec.mode.has_mask() {
        let present = |k: usize| k < scene.blocks.len() && ctx.present.get(k).copied().unwrap_or(true);
        out.extend((0..spec.max_objects).map(|k| if present(k) { 1.0 } else { 0.0 }));
        out.extend(spec.mode.fixtures().iter().map(|f| match f {
            Fixture::Gripper | Fixture::Table => 1.0,
            Fixture::Floor => ctx.fixtures.floor.map_or(0.0, |_| 1.0),
        }));
    }
}
