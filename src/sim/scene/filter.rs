//! Collision filtering: body pairs of the Fetch model whose bounding spheres
//! overlap at (nearly) every substep, so MuJoCo runs a mesh collision test on
//! them every time, but which never touch in this workspace.
//!
//! How the list was made: rollouts of random actions in BlocksChoose-v0
//! recorded every body pair with overlapping bounding spheres and every pair
//! that actually produced a contact (`cargo run --release --example
//! collision_pairs`). Pairs that overlapped but never touched were kept here
//! when the robot's structure rules a contact out: the base, torso and head
//! never move relative to each other (slide joints with damping 1e11, a
//! torso joint with damping 1e7, no actuators), the base never moves towards
//! the table, and the arm links listed are separated by a roll joint that
//! cannot bring them together. Pairs of arm links that *do* touch the head
//! or torso in normal use (upper-arm roll vs. head, shoulder lift vs. torso)
//! are not excluded. `tests/it/collision_filter.rs` proves that trajectories
//! with and without this list are bit-identical over many seeded random and
//! scripted rollouts.

/// Body pairs excluded with `<contact><exclude>` when
/// [`SceneSpec::collision_filter`](super::SceneSpec) is on.
pub const EXCLUDED_BODY_PAIRS: &[(&str, &str)] = &[
    // the static base / torso / head group among itself
    ("robot0:base_link", "robot0:shoulder_pan_link"),
    ("robot0:head_pan_link", "robot0:shoulder_pan_link"),
    ("robot0:head_pan_link", "robot0:torso_fixed_link"),
    ("robot0:head_tilt_link", "robot0:shoulder_pan_link"),
    ("robot0:head_tilt_link", "robot0:torso_lift_link"),
    ("robot0:shoulder_pan_link", "robot0:torso_fixed_link"),
    // the base and its laser never reach the table
    ("robot0:base_link", "table0"),
    ("robot0:laser_link", "table0"),
    // arm links two apart across a roll joint
    ("robot0:upperarm_roll_link", "robot0:forearm_roll_link"),
    ("robot0:forearm_roll_link", "robot0:wrist_roll_link"),
    ("robot0:wrist_flex_link", "robot0:gripper_link"),
];
