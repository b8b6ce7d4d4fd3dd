//! Dynamics drawn per episode (a task's `[physics]` table, issue 76): the ranges a task gives,
//! their bounds, and the draw from the episode's seed. No MuJoCo here: `sim::dynamics` applies
//! the drawn scales to a model, and `env` the action's and observation's parts.
//!
//! Every parameter is a range `[low, high]`; an absent one keeps its nominal value. Scales
//! multiply the model's own values and are drawn log-uniformly (×0.5 as likely as ×2); noise
//! levels are drawn uniformly, latency uniformly among the integers of its range. Every
//! parameter is drawn, given or not, in [`PARAMS`]' order, so that adding one to a task does not
//! move the others' draws.

use crate::sim::dynamics::Scales;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// A task's `[physics]` table: per-episode ranges of the dynamics.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhysicsSpec {
    /// Scale of every geom's sliding friction (the contact's is the larger of its two geoms').
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<[f64; 2]>,
    /// Scale of every geom's torsional friction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torsional_friction: Option<[f64; 2]>,
    /// Scale of each block's mass and inertia (its density).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<[f64; 2]>,
    /// Scale of every joint's damping (the arm's and the fingers').
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<[f64; 2]>,
    /// Scale of the arm's position control: how far the gripper's target moves per unit of
    /// action (0.05 m nominal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain: Option<[f64; 2]>,
    /// Scale of every geom's contact time constant (`solref[0]`): above 1, softer contacts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solref: Option<[f64; 2]>,
    /// Scale of every geom's contact impedance (`solimp`'s dmin and dmax): below 1, softer.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solimp: Option<[f64; 2]>,
    /// Standard deviation of the Gaussian noise added to each action component, every step
    /// (in action units, before the action is clipped to [−1, 1]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action_noise: Option<[f64; 2]>,
    /// Steps by which the action applied lags the action given (0: none; the first steps of
    /// an episode apply a zero action).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latency: Option<[f64; 2]>,
    /// Standard deviation (m) of the Gaussian noise on the positions the observation reports
    /// (the grip's and each block's), drawn every step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obs_noise: Option<[f64; 2]>,
}

/// How a parameter is drawn within its range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Draw {
    /// Log-uniformly: a scale, positive.
    Scale,
    /// Uniformly: a noise level, zero or more.
    Level,
    /// Uniformly among the integers of the range.
    Steps,
}

/// One parameter of the `[physics]` table.
#[derive(Debug, Clone, Copy)]
pub struct Param {
    /// Its name in the table.
    pub name: &'static str,
    /// How it is drawn.
    pub draw: Draw,
    /// Its nominal value (what an absent parameter keeps).
    pub nominal: f64,
    /// The widest range a task may give: beyond it the simulation is not trusted (a mass
    /// ×1000 breaks the contact solver) or the task is no longer the task.
    pub bounds: [f64; 2],
    /// What it changes, for messages and docs.
    pub what: &'static str,
}

/// Every parameter, in draw order.
pub const PARAMS: [Param; 10] = [
    Param { name: "friction", draw: Draw::Scale, nominal: 1.0, bounds: [0.1, 10.0], what: "scale of sliding friction" },
    Param {
        name: "torsional_friction",
        draw: Draw::Scale,
        nominal: 1.0,
        bounds: [0.1, 10.0],
        what: "scale of torsional friction",
    },
    Param { name: "mass", draw: Draw::Scale, nominal: 1.0, bounds: [0.1, 10.0], what: "scale of each block's mass" },
    Param { name: "damping", draw: Draw::Scale, nominal: 1.0, bounds: [0.1, 20.0], what: "scale of joint damping" },
    Param {
        name: "gain",
        draw: Draw::Scale,
        nominal: 1.0,
        bounds: [0.25, 2.0],
        what: "scale of the gripper's displacement per unit action",
    },
    Param {
        name: "solref",
        draw: Draw::Scale,
        nominal: 1.0,
        bounds: [0.5, 4.0],
        what: "scale of the contacts' time constant",
    },
    Param {
        name: "solimp",
        draw: Draw::Scale,
        nominal: 1.0,
        bounds: [0.5, 1.04],
        what: "scale of the contacts' impedance",
    },
    Param {
        name: "action_noise",
        draw: Draw::Level,
        nominal: 0.0,
        bounds: [0.0, 1.0],
        what: "standard deviation of the action noise",
    },
    Param { name: "latency", draw: Draw::Steps, nominal: 0.0, bounds: [0.0, 4.0], what: "steps of action latency" },
    Param {
        name: "obs_noise",
        draw: Draw::Level,
        nominal: 0.0,
        bounds: [0.0, 0.05],
        what: "standard deviation (m) of the observed positions' noise",
    },
];

impl PhysicsSpec {
    /// The ranges in [`PARAMS`]' order (None: not given).
    pub fn ranges(&self) -> [Option<[f64; 2]>; 10] {
        [
            self.friction,
            self.torsional_friction,
            self.mass,
            self.damping,
            self.gain,
            self.solref,
            self.solimp,
            self.action_noise,
            self.latency,
            self.obs_noise,
        ]
    }

    /// Checks every range: finite, low ≤ high, within the parameter's bounds, latency whole steps.
    ///
    /// # Errors
    /// The first range that is not, naming `physics.NAME` and the fix.
    pub fn check(&self) -> Result<(), String> {
        for (p, range) in PARAMS.iter().zip(self.ranges()) {
            let Some([lo, hi]) = range else { continue };
            let name = p.name;
            let [min, max] = p.bounds;
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(format!("physics.{name} = [{lo}, {hi}]: give two finite numbers [low, high]"));
            }
            if lo > hi {
                return Err(format!("physics.{name} = [{lo}, {hi}]: low is above high; write [{hi}, {lo}]"));
            }
            if p.draw == Draw::Scale && lo <= 0.0 {
                return Err(format!("physics.{name} = [{lo}, {hi}]: a {} must be positive (1 is nominal)", p.what));
            }
            if lo < min || hi > max {
                return Err(format!(
                    "physics.{name} = [{lo}, {hi}]: the {} must stay within [{min}, {max}] (beyond, the \
                     simulation is not trusted); narrow the range",
                    p.what
                ));
            }
            if p.draw == Draw::Steps && (lo.fract() != 0.0 || hi.fract() != 0.0) {
                return Err(format!("physics.{name} = [{lo}, {hi}]: latency counts whole steps; write integers"));
            }
        }
        Ok(())
    }

    /// One episode's values, drawn from `rng` in [`PARAMS`]' order (every parameter is drawn, an
    /// absent one at its nominal value).
    pub fn draw(&self, rng: &mut impl Rng) -> PhysicsDraw {
        let v: Vec<f64> = PARAMS
            .iter()
            .zip(self.ranges())
            .map(|(p, range)| {
                let u: f64 = rng.gen();
                let [lo, hi] = range.unwrap_or([p.nominal; 2]);
                match p.draw {
                    Draw::Scale => (lo.ln() + u * (hi.ln() - lo.ln())).exp().clamp(lo, hi),
                    Draw::Level => (lo + u * (hi - lo)).clamp(lo, hi),
                    Draw::Steps => (lo + (u * (hi - lo + 1.0)).floor()).min(hi),
                }
            })
            .collect();
        PhysicsDraw {
            scales: Scales {
                friction: v[0],
                torsional_friction: v[1],
                mass: v[2],
                damping: v[3],
                solref: v[5],
                solimp: v[6],
            },
            gain: v[4],
            action_noise: v[7],
            latency: v[8] as usize,
            obs_noise: v[9],
        }
    }

    /// `self` with the parameters of `fixed` (name, value) pinned to those values, for one
    /// episode (`reset`'s `physics` option).
    ///
    /// # Errors
    /// An unknown name, a parameter the task does not vary, or a value outside the task's range.
    pub fn pinned(&self, fixed: &[(String, f64)]) -> Result<PhysicsSpec, String> {
        let mut ranges = self.ranges();
        for (name, value) in fixed {
            let Some(i) = PARAMS.iter().position(|p| p.name == name) else {
                let known: Vec<&str> = PARAMS.iter().map(|p| p.name).collect();
                return Err(format!("physics option {name:?}: no such parameter; known: {}", known.join(", ")));
            };
            let Some([lo, hi]) = ranges[i] else {
                return Err(format!(
                    "physics option {name:?}: this task's [physics] table does not vary it; pin only what it varies"
                ));
            };
            if !value.is_finite() || *value < lo || *value > hi {
                return Err(format!(
                    "physics option {name} = {value}: outside the task's range [{lo}, {hi}]; give a value within it"
                ));
            }
            if PARAMS[i].draw == Draw::Steps && value.fract() != 0.0 {
                return Err(format!("physics option {name} = {value}: latency counts whole steps; give an integer"));
            }
            ranges[i] = Some([*value; 2]);
        }
        let [friction, torsional_friction, mass, damping, gain, solref, solimp, action_noise, latency, obs_noise] =
            ranges;
        Ok(PhysicsSpec {
            friction,
            torsional_friction,
            mass,
            damping,
            gain,
            solref,
            solimp,
            action_noise,
            latency,
            obs_noise,
        })
    }
}

/// One episode's dynamics: what `info` and the episode's dump report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhysicsDraw {
    /// The scales applied to the model.
    #[serde(flatten)]
    pub scales: Scales,
    /// The scale of the gripper's displacement per unit action.
    pub gain: f64,
    /// The standard deviation of the action noise.
    pub action_noise: f64,
    /// Steps of action latency.
    pub latency: usize,
    /// The standard deviation (m) of the observed positions' noise.
    pub obs_noise: f64,
}

impl PhysicsDraw {
    /// The values by name, in [`PARAMS`]' order.
    pub fn values(&self) -> [(&'static str, f64); 10] {
        let s = &self.scales;
        let v = [
            s.friction,
            s.torsional_friction,
            s.mass,
            s.damping,
            self.gain,
            s.solref,
            s.solimp,
            self.action_noise,
            self.latency as f64,
            self.obs_noise,
        ];
        std::array::from_fn(|i| (PARAMS[i].name, v[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn spec(toml_text: &str) -> PhysicsSpec {
        toml::from_str(toml_text).unwrap()
    }

    #[test]
    fn the_parameter_list_and_the_table_agree() {
        let all = spec(
            "friction = [0.5, 2]\ntorsional_friction = [0.5, 2]\nmass = [0.5, 2]\ndamping = [0.5, 2]\n\
             gain = [0.5, 2]\nsolref = [0.5, 2]\nsolimp = [0.9, 1]\naction_noise = [0, 0.1]\nlatency = [0, 2]\n\
             obs_noise = [0, 0.01]",
        );
        assert!(all.ranges().iter().all(Option::is_some));
        let d = all.draw(&mut ChaCha8Rng::seed_from_u64(1));
        for ((name, v), (p, r)) in d.values().iter().zip(PARAMS.iter().zip(all.ranges())) {
            assert_eq!(*name, p.name);
            let [lo, hi] = r.unwrap();
            assert!((lo..=hi).contains(v), "{name} = {v}");
        }
        // Serialised names are the table's.
        let json = serde_json::to_value(d).unwrap();
        for p in PARAMS {
            assert!(json.get(p.name).is_some(), "{}", p.name);
        }
    }

    #[test]
    fn an_absent_table_draws_the_nominal_values_and_keeps_the_stream_in_step() {
        let d = PhysicsSpec::default().draw(&mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(d.values().map(|(_, v)| v), PARAMS.map(|p| p.nominal));
        // Every parameter takes one draw, given or not: adding mass does not move friction's.
        let a = spec("friction = [0.5, 2]").draw(&mut ChaCha8Rng::seed_from_u64(3));
        let b = spec("friction = [0.5, 2]\nmass = [1, 3]").draw(&mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(a.scales.friction, b.scales.friction);
        assert_ne!(a.scales.mass, b.scales.mass);
    }

    #[test]
    fn latency_covers_each_whole_step_of_its_range() {
        let s = spec("latency = [0, 2]");
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let mut seen = [0; 3];
        for _ in 0..300 {
            seen[s.draw(&mut rng).latency] += 1;
        }
        assert!(seen.iter().all(|&n| n > 60), "{seen:?}");
    }

    #[test]
    fn bad_ranges_are_refused_naming_the_field_and_the_fix() {
        for (text, wanted) in [
            ("friction = [2, 0.5]", "physics.friction = [2, 0.5]: low is above high"),
            ("mass = [0, 2]", "must be positive"),
            ("damping = [-1, 2]", "must be positive"),
            ("mass = [1, 1000]", "within [0.1, 10]"),
            ("obs_noise = [0, 1]", "within [0, 0.05]"),
            ("latency = [0, 1.5]", "whole steps"),
            ("friction = [0.5, inf]", "finite"),
            ("friction = [nan, 1]", "finite"),
        ] {
            let e = spec(text).check().unwrap_err();
            assert!(e.contains(wanted), "{text}: {e}");
        }
        assert!(toml::from_str::<PhysicsSpec>("wind = [0, 1]").unwrap_err().to_string().contains("unknown field"));
        spec("friction = [0.5, 2]\nlatency = [0, 2]").check().unwrap();
    }

    #[test]
    fn a_pinned_parameter_must_be_one_the_task_varies_within_its_range() {
        let s = spec("friction = [0.5, 2]");
        let p = s.pinned(&[("friction".into(), 1.5)]).unwrap();
        assert_eq!(p.friction, Some([1.5, 1.5]));
        assert_eq!(p.draw(&mut ChaCha8Rng::seed_from_u64(0)).scales.friction, 1.5);
        for (name, v, wanted) in [
            ("wind", 1.0, "no such parameter"),
            ("mass", 1.0, "does not vary it"),
            ("friction", 3.0, "outside the task's range [0.5, 2]"),
            ("friction", f64::NAN, "outside"),
        ] {
            let e = s.pinned(&[(name.into(), v)]).unwrap_err();
            assert!(e.contains(wanted), "{name}: {e}");
        }
    }
}
