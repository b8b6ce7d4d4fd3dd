//! Layer 2, sim: the physics and the colour rules, below any task.
//!
//! | module | what |
//! |---|---|
//! | [`mj`] | the safe MuJoCo wrapper: every FFI call (rendering's included) |
//! | [`scene`] | the Fetch scene with coloured boxes, compiled from a scene spec; where the Fetch files come from |
//! | [`rules`] | the colour rules: touching sets per substep to a verdict (success, failure) |
//! | [`dynamics`] | dynamics that vary per episode: scales of friction, mass, damping and contact softness applied to a model |

pub mod dynamics;
pub mod mj;
pub mod rules;
pub mod scene;
