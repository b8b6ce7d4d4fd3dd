//! Scene building: a [`SceneSpec`] (coloured blocks, gripper and table
//! colours) becomes a compiled MuJoCo model of the Fetch robot at a table,
//! plus the ids the environment needs and the geom → object map of the rules.

mod assets;
mod filter;
pub mod xml;

pub use assets::{
    assets, check_assets, models_dir, registered_fetch_assets, use_fetch_assets, verify_fetch_files, Assets,
    FETCH_ASSETS, FETCH_FILES, MODELS_DIR_VAR,
};
pub use filter::EXCLUDED_BODY_PAIRS;

use crate::sim::mj::{MjError, Model, ObjType};
use crate::sim::rules::{Colour, RuleError, Rules};
use std::path::PathBuf;
use std::sync::Arc;
use thiserror::Error;

/// Errors while building a scene.
#[derive(Debug, Error)]
pub enum SceneError {
    /// A file of the scene is missing: usually the Fetch assets were never fetched.
    #[error("missing scene file {missing}: in a checkout `make setup` (scripts/setup.sh) fetches the Fetch robot assets; the Python package reads them from `pip install gymnasium-robotics==1.4.2`; or set BLOCKPUZZLE_MODELS_DIR to a folder that has them")]
    MissingAssets { missing: PathBuf },
    /// A Fetch file differs from gymnasium-robotics 1.4.2's.
    #[error("{path} is not gymnasium-robotics 1.4.2's file (sha256 {found}, expected {expected}): reinstall it with `pip install --force-reinstall gymnasium-robotics==1.4.2`, or set BLOCKPUZZLE_MODELS_DIR to a folder of your own")]
    AssetChecksum { path: PathBuf, expected: String, found: String },
    /// No folder of Fetch assets is known (a build without a checkout, nothing registered).
    #[error("no Fetch robot assets: this build has no checkout to read them from; the Python package finds them in gymnasium-robotics (`pip install gymnasium-robotics==1.4.2`), or set BLOCKPUZZLE_MODELS_DIR")]
    NoAssets,
    /// The scene template could not be read.
    #[error("cannot read {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The scene template lacks a placeholder.
    #[error("scene template models/scene.xml lacks the placeholder {placeholder}")]
    Template { placeholder: &'static str },
    /// MuJoCo refused the model, or a name the scene relies on is missing.
    #[error(transparent)]
    Mujoco(#[from] MjError),
    /// The colours do not make a valid task.
    #[error("invalid task colours: {0}")]
    Rules(#[from] RuleError),
}

/// One block of a scene: a free box.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockSpec {
    /// Rule-object name (the model names its body `block0`, `block1`, ...).
    pub name: String,
    /// Colour.
    pub colour: Colour,
    /// Half extents (x, y, z) in metres.
    pub half_extents: [f64; 3],
    /// Mass in kg.
    pub mass: f64,
    /// MuJoCo friction, or its default.
    pub friction: Option<[f64; 3]>,
}

impl BlockSpec {
    /// A 5 cm cube of 2 kg (the paper's block) named `name`.
    pub fn cube(name: &str, colour: Colour) -> Self {
        Self { name: name.to_owned(), colour, half_extents: [xml::BLOCK_HALF; 3], mass: 2.0, friction: None }
    }
}

/// What a scene contains.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSpec {
    /// The blocks, in scene (and observation) order.
    pub blocks: Vec<BlockSpec>,
    /// Colour of the gripper (both fingers and the gripper link).
    pub gripper: Colour,
    /// Colour of the table.
    pub table: Colour,
    /// Colour of the floor when it is a rule object (the last one); `None`: not one.
    pub floor: Option<Colour>,
    /// Position actuators on the fingers (the gripper action of FetchPickAndPlace).
    pub finger_actuators: bool,
    /// Exclude robot collision pairs that cannot touch in this workspace
    /// ([`EXCLUDED_BODY_PAIRS`]); trajectories are bit-identical either way.
    pub collision_filter: bool,
}

/// A rule object of the scene (gripper, table or block).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneObject {
    /// "gripper", "table", "block0", ...
    pub name: String,
    /// Its colour.
    pub colour: Colour,
}

/// Ids of one block in the compiled model.
#[derive(Debug, Clone, Copy)]
pub struct BlockIds {
    /// Body id.
    pub body: usize,
    /// Centre site id.
    pub site: usize,
    /// Geom id.
    pub geom: usize,
    /// Address of its free joint in qpos (7 values).
    pub qpos: usize,
    /// Address of its free joint in qvel (6 values).
    pub dof: usize,
}

/// Index of the gripper among the rule objects.
pub const GRIPPER_OBJECT: usize = 0;
/// Index of the table among the rule objects.
pub const TABLE_OBJECT: usize = 1;
/// Index of the first block among the rule objects.
pub const FIRST_BLOCK_OBJECT: usize = 2;

/// A compiled scene.
#[derive(Debug)]
pub struct Scene {
    /// The compiled model (shared by every state of this scene).
    pub model: Arc<Model>,
    /// The spec it was built from.
    pub spec: SceneSpec,
    /// `robot0:grip` site.
    pub grip_site: usize,
    /// `robot0:gripper_link` body (welded to the mocap).
    pub gripper_body: usize,
    /// The rule object of the floor, if it is one.
    pub floor_object: Option<usize>,
    /// The table's box geom.
    pub table_geom: usize,
    /// The floor's plane geom.
    pub floor_geom: usize,
    /// The right and left fingers' box geoms.
    pub finger_geoms: [usize; 2],
    /// Index of `robot0:mocap` among mocap bodies.
    pub mocap: usize,
    /// qpos addresses of the right and left finger joints.
    pub finger_qpos: [usize; 2],
    /// qvel addresses of the right and left finger joints.
    pub finger_dof: [usize; 2],
    /// qpos addresses of `robot0:slide0..2`.
    pub slide_qpos: [usize; 3],
    /// The blocks in spec order.
    pub blocks: Vec<BlockIds>,
    /// Rule objects: gripper, table, then the blocks.
    pub objects: Vec<SceneObject>,
    /// Rule object of each geom, or -1.
    pub geom_object: Vec<i16>,
}

const GRIPPER_BODIES: [&str; 3] =
    ["robot0:gripper_link", "robot0:r_gripper_finger_link", "robot0:l_gripper_finger_link"];

/// gymnasium-robotics' reset_mocap_welds: the weld's anchor and relative
/// pose become the identity, so the gripper is pulled onto the mocap.
fn reset_mocap_welds(model: &mut Model) {
    let welds: Vec<usize> =
        model.eq_type().iter().enumerate().filter(|(_, &t)| t == crate::sim::mj::EQ_WELD).map(|(i, _)| i).collect();
    for i in welds {
        model.eq_data_mut()[i][..7].copy_from_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    }
}

/// Colours the gripper's geoms when it takes part in the task (it is not grey).
fn colour_gripper(model: &mut Model, gripper_bodies: &[usize], colour: Colour) -> Result<(), SceneError> {
    if colour == Colour::Grey {
        return Ok(());
    }
    let mat = model.id(ObjType::Material, xml::material(colour))?;
    let geoms: Vec<usize> =
        (0..model.ngeom()).filter(|&g| gripper_bodies.contains(&(model.geom_bodyid()[g] as usize))).collect();
    for g in geoms {
        model.set_geom_material(g, mat)?;
    }
    Ok(())
}

/// The ids of block `i` (its body, site, geom and free joint's addresses).
fn block_ids(model: &Model, i: usize) -> Result<BlockIds, SceneError> {
    let name = xml::block_name(i);
    let (qpos, dof) = joint_adr(model, &format!("{name}:joint"))?;
    Ok(BlockIds {
        body: model.id(ObjType::Body, &name)?,
        site: model.id(ObjType::Site, &name)?,
        geom: model.id(ObjType::Geom, &name)?,
        qpos,
        dof,
    })
}

fn joint_adr(model: &Model, name: &str) -> Result<(usize, usize), MjError> {
    let j = model.id(ObjType::Joint, name)?;
    Ok((model.jnt_qposadr()[j] as usize, model.jnt_dofadr()[j] as usize))
}

/// The MJCF text of a scene: the scene template with the blocks, table colour
/// and collision exclusions filled in, and the folder it loads from
/// ([`assets`]). Its includes are relative to that folder, so a copy saved
/// there loads in any MuJoCo.
///
/// # Errors
/// [`SceneError`] for missing assets or an unreadable template.
pub fn mjcf(spec: &SceneSpec) -> Result<(String, PathBuf), SceneError> {
    let found = assets()?;
    let excludes: &[(&str, &str)] = if spec.collision_filter { EXCLUDED_BODY_PAIRS } else { &[] };
    Ok((xml::render(&found.template, spec, excludes, found.fetch_prefix)?, found.base))
}

impl Scene {
    /// Builds the scene from the template and the Fetch assets ([`assets`]).
    ///
    /// # Errors
    /// [`SceneError`] for missing assets, an invalid task, or a model MuJoCo refuses.
    pub fn build(spec: &SceneSpec) -> Result<Scene, SceneError> {
        crate::sim::mj::install_handlers();
        let colours: Vec<Colour> = [spec.gripper, spec.table]
            .into_iter()
            .chain(spec.blocks.iter().map(|b| b.colour))
            .chain(spec.floor)
            .collect();
        Rules::new(colours)?;
        let (text, dir) = mjcf(spec)?;
        let mut model = Model::from_xml_string(&text, &xml::virtual_path(&dir))?;

        reset_mocap_welds(&mut model);
        let gripper_bodies: Vec<usize> =
            GRIPPER_BODIES.iter().map(|n| model.id(ObjType::Body, n)).collect::<Result<_, _>>()?;
        colour_gripper(&mut model, &gripper_bodies, spec.gripper)?;

        let grip_site = model.id(ObjType::Site, "robot0:grip")?;
        let gripper_body = gripper_bodies[0];
        let mocap_body = model.id(ObjType::Body, "robot0:mocap")?;
        let mocap = usize::try_from(model.body_mocapid()[mocap_body])
            .map_err(|_| MjError::UnknownName { kind: "mocap body", name: "robot0:mocap".into() })?;
        let (rq, rd) = joint_adr(&model, "robot0:r_gripper_finger_joint")?;
        let (lq, ld) = joint_adr(&model, "robot0:l_gripper_finger_joint")?;
        let mut slide_qpos = [0; 3];
        for (i, s) in slide_qpos.iter_mut().enumerate() {
            *s = joint_adr(&model, &format!("robot0:slide{i}"))?.0;
        }
        let table_body = model.id(ObjType::Body, "table0")?;

        let blocks = (0..spec.blocks.len()).map(|i| block_ids(&model, i)).collect::<Result<Vec<_>, _>>()?;
        let mut objects = vec![
            SceneObject { name: "gripper".into(), colour: spec.gripper },
            SceneObject { name: "table".into(), colour: spec.table },
        ];
        objects.extend(spec.blocks.iter().map(|b| SceneObject { name: b.name.clone(), colour: b.colour }));
        let floor_object = spec.floor.map(|colour| {
            objects.push(SceneObject { name: "floor".into(), colour });
            objects.len() - 1
        });
        let floor_geom = model.id(ObjType::Geom, "floor0")?;
        let finger_geoms = [
            model.id(ObjType::Geom, "robot0:r_gripper_finger_link")?,
            model.id(ObjType::Geom, "robot0:l_gripper_finger_link")?,
        ];
        // The table body's one geom: its top is what the blocks stand on.
        let table_geom = (0..model.ngeom())
            .find(|&g| model.geom_bodyid()[g] as usize == table_body)
            .ok_or_else(|| MjError::UnknownName { kind: "geom of body", name: "table0".into() })?;
        let geom_object = (0..model.ngeom())
            .map(|g| {
                let b = model.geom_bodyid()[g] as usize;
                if gripper_bodies.contains(&b) {
                    GRIPPER_OBJECT as i16
                } else if b == table_body {
                    TABLE_OBJECT as i16
                } else if g == floor_geom {
                    floor_object.map_or(-1, |f| f as i16)
                } else {
                    blocks.iter().position(|k| k.body == b).map_or(-1, |i| (FIRST_BLOCK_OBJECT + i) as i16)
                }
            })
            .collect();

        Ok(Scene {
            model: Arc::new(model),
            spec: spec.clone(),
            grip_site,
            gripper_body,
            mocap,
            finger_qpos: [rq, lq],
            finger_dof: [rd, ld],
            slide_qpos,
            floor_object,
            table_geom,
            floor_geom,
            finger_geoms,
            blocks,
            objects,
            geom_object,
        })
    }

    /// RGBA the scene's material gives `colour`.
    ///
    /// # Errors
    /// A scene template without the BlockPuzzle materials.
    pub fn rgba(&self, colour: Colour) -> Result<[f32; 4], MjError> {
        let id = self.model.id(ObjType::Material, xml::material(colour))?;
        Ok(self.model.mat_rgba()[id])
    }

    /// Colours of the rule objects, in object order.
    pub fn colours(&self) -> Vec<Colour> {
        self.objects.iter().map(|o| o.colour).collect()
    }
}
