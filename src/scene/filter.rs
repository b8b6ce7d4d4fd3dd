//! Collision filtering: body pairs of the Fetch model that MuJoCo would test
//! for contact at every substep but that never touch in this workspace.
//! Filled in from measurements; see `tests/collision_filter.rs`.

/// Body pairs excluded with `<contact><exclude>` when
/// [`SceneSpec::collision_filter`](super::SceneSpec) is on.
pub const EXCLUDED_BODY_PAIRS: &[(&str, &str)] = &[];
