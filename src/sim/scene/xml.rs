//! Turns a [`SceneSpec`] into MJCF text from the template `models/scene.xml`.

use super::{SceneError, SceneSpec};
use crate::sim::rules::Colour;
use std::fmt::Write as _;
use std::path::Path;

/// File name of the scene template inside the models folder.
pub const TEMPLATE_FILE: &str = "scene.xml";

/// Half size of a block (5 cm cubes).
pub const BLOCK_HALF: f64 = 0.025;
/// Height of the table top.
pub const TABLE_TOP_Z: f64 = 0.4;
/// Table centre (x, y) and half extents (x, y).
pub const TABLE_CENTER: [f64; 2] = [1.3, 0.75];
/// Half extents of the table top.
pub const TABLE_HALF: [f64; 2] = [0.25, 0.35];

/// Material name for a colour.
pub fn material(c: Colour) -> &'static str {
    match c {
        Colour::Red => "bp_red",
        Colour::Blue => "bp_blue",
        Colour::Green => "bp_green",
        Colour::Grey => "bp_grey",
    }
}

/// Name of block `i`'s body, geom, site and (with `:joint`) joint.
pub fn block_name(i: usize) -> String {
    format!("block{i}")
}

/// Where the blocks rest before the first reset places them: rows along the
/// far edge of the table, clear of the arm's settling motion, spaced by the
/// widest block (8 cm, five to a row, for the paper's 5 cm cubes).
fn parking_spots(blocks: &[super::BlockSpec]) -> Vec<[f64; 2]> {
    let widest = blocks.iter().map(|b| b.half_extents[0].max(b.half_extents[1])).fold(BLOCK_HALF, f64::max);
    let pitch = if widest <= BLOCK_HALF { 0.08 } else { 2.0 * widest + 0.03 };
    let per_row = ((0.40 / pitch + 1e-9).floor() as usize).max(1);
    (0..blocks.len()).map(|i| [1.1 + pitch * (i % per_row) as f64, 1.05 - pitch * (i / per_row) as f64]).collect()
}

/// Position actuators of the Fetch fingers, as in gymnasium-robotics' pick-and-place scene.
const FINGER_ACTUATORS: &str = r#"    <actuator>
        <position ctrllimited="true" ctrlrange="0 0.2" joint="robot0:l_gripper_finger_joint" kp="30000" name="robot0:l_gripper_finger_joint" user="1"/>
        <position ctrllimited="true" ctrlrange="0 0.2" joint="robot0:r_gripper_finger_joint" kp="30000" name="robot0:r_gripper_finger_joint" user="1"/>
    </actuator>
"#;

/// Renders the template with the blocks, table colour and contact exclusions;
/// `{{FETCH}}` (where the template has it) becomes `fetch_prefix`, the Fetch
/// assets' path relative to the folder the model loads from.
///
/// # Errors
/// [`SceneError::Template`] if the template lacks a placeholder.
pub fn render(
    template: &str,
    spec: &SceneSpec,
    excludes: &[(&str, &str)],
    fetch_prefix: &str,
) -> Result<String, SceneError> {
    let mut blocks = String::new();
    for (i, (block, [x, y])) in spec.blocks.iter().zip(parking_spots(&spec.blocks)).enumerate() {
        let name = block_name(i);
        let [hx, hy, hz] = block.half_extents;
        let z = TABLE_TOP_Z + hz;
        let mass = block.mass;
        let mat = material(block.colour);
        let friction = block.friction.map_or(String::new(), |[a, b, c]| format!(r#" friction="{a} {b} {c}""#));
        // The block is a free body like gymnasium-robotics' object0.
        let _ = writeln!(
            blocks,
            r#"        <body name="{name}" pos="{x} {y} {z}">
            <joint name="{name}:joint" type="free" damping="0.01"/>
            <geom name="{name}" type="box" size="{hx} {hy} {hz}" condim="3" mass="{mass}"{friction} material="{mat}"/>
            <site name="{name}" pos="0 0 0" size="0.02 0.02 0.02" rgba="1 0 0 0" type="sphere"/>
        </body>"#
        );
    }
    let mut contact = String::new();
    if !excludes.is_empty() {
        contact.push_str("    <contact>\n");
        for (a, b) in excludes {
            let _ = writeln!(contact, r#"        <exclude body1="{a}" body2="{b}"/>"#);
        }
        contact.push_str("    </contact>\n");
    }
    let table = if spec.table == Colour::Grey { "bp_table" } else { material(spec.table) };
    if spec.finger_actuators {
        contact.push_str(FINGER_ACTUATORS);
    }
    let floor = spec.floor.map_or("floor_mat", material);
    let mut out = template.replace("{{FETCH}}", fetch_prefix);
    for (key, value) in [
        ("{{BLOCKS}}", blocks.as_str()),
        ("{{CONTACT_EXCLUDES}}", &contact),
        ("{{TABLE_MATERIAL}}", table),
        ("{{FLOOR_MATERIAL}}", floor),
    ] {
        if !out.contains(key) {
            return Err(SceneError::Template { placeholder: key });
        }
        out = out.replace(key, value);
    }
    Ok(out)
}

/// The name under which the generated XML is registered in MuJoCo's virtual
/// file system: inside the folder it loads from, so relative includes resolve.
pub fn virtual_path(base: &Path) -> std::path::PathBuf {
    base.join("blockpuzzle_generated.xml")
}
