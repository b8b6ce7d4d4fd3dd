//! Dynamics that vary per episode: scales of a model's friction, block masses, joint damping and
//! contact softness, applied from the nominal values read once (so draws never compound).

use super::mj::Model;
use serde::{Deserialize, Serialize};

/// Scales of the model's parameters (1: nominal).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Scales {
    /// Every geom's sliding friction.
    pub friction: f64,
    /// Every geom's torsional friction.
    pub torsional_friction: f64,
    /// Each block's mass and inertia.
    pub mass: f64,
    /// Every joint's damping.
    pub damping: f64,
    /// Every geom's contact time constant (`solref[0]`).
    pub solref: f64,
    /// Every geom's contact impedance (`solimp`'s dmin and dmax, kept below 1).
    pub solimp: f64,
}

impl Default for Scales {
    fn default() -> Self {
        Self { friction: 1.0, torsional_friction: 1.0, mass: 1.0, damping: 1.0, solref: 1.0, solimp: 1.0 }
    }
}

/// The highest impedance a scaled `solimp` may reach (MuJoCo needs it below 1).
const MAX_IMPEDANCE: f64 = 0.9999;

/// A model's nominal values of what [`Scales`] scale.
#[derive(Debug, Clone)]
pub struct Nominal {
    friction: Vec<[f64; 3]>,
    solref: Vec<[f64; 2]>,
    solimp: Vec<[f64; 5]>,
    damping: Vec<f64>,
    /// The blocks' bodies, with their mass and inertia.
    blocks: Vec<(usize, f64, [f64; 3])>,
}

impl Nominal {
    /// Reads the nominal values from `model`; `blocks` are the bodies whose mass scales.
    pub fn read(model: &Model, blocks: &[usize]) -> Self {
        Self {
            friction: model.geom_friction().to_vec(),
            solref: model.geom_solref().to_vec(),
            solimp: model.geom_solimp().to_vec(),
            damping: model.dof_damping().to_vec(),
            blocks: blocks.iter().map(|&b| (b, model.body_mass()[b], model.body_inertia()[b])).collect(),
        }
    }

    /// Sets `model`'s parameters to the nominal values times `scales`: a model of the same
    /// MJCF as the one read.
    pub fn apply(&self, model: &mut Model, scales: &Scales) {
        for (f, n) in model.geom_friction_mut().iter_mut().zip(&self.friction) {
            *f = [n[0] * scales.friction, n[1] * scales.torsional_friction, n[2]];
        }
        for (r, n) in model.geom_solref_mut().iter_mut().zip(&self.solref) {
            // A positive time constant is MuJoCo's standard form; a negative one is a direct
            // stiffness, left as it is.
            *r = if n[0] > 0.0 { [n[0] * scales.solref, n[1]] } else { *n };
        }
        for (s, n) in model.geom_solimp_mut().iter_mut().zip(&self.solimp) {
            let scale = |v: f64| (v * scales.solimp).clamp(0.0001, MAX_IMPEDANCE);
            *s = [scale(n[0]), scale(n[1]), n[2], n[3], n[4]];
        }
        for (d, n) in model.dof_damping_mut().iter_mut().zip(&self.damping) {
            *d = n * scales.damping;
        }
        for &(b, mass, inertia) in &self.blocks {
            model.body_mass_mut()[b] = mass * scales.mass;
            model.body_inertia_mut()[b] = inertia.map(|i| i * scales.mass);
        }
    }
}
