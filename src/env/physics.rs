//! Per-episode dynamics of a task with a `[physics]` table: drawn at reset from the episode's
//! seed (stream 1 of its ChaCha8 generator, so the layout's draws on stream 0 are those of the
//! same task without the table), with every layout the reset tries, applied to the environment's
//! own copy of the model before the layout's settle, and the action's and observation's parts
//! applied every step.

use super::*;
use crate::sim::dynamics::Nominal;
use crate::task::physics::{PhysicsDraw, PhysicsSpec};
use rand_distr::{Distribution, StandardNormal};
use std::collections::VecDeque;

/// The stream of an episode seed's generator that physics draws from.
const PHYSICS_STREAM: u64 = 1;

/// What an environment with a `[physics]` table keeps.
pub(super) struct Dynamics {
    /// The ranges drawn from: the task's, or the task's with some pinned (`reset`'s options).
    spec: PhysicsSpec,
    /// The model's nominal values.
    nominal: Nominal,
    /// Draws the episode's values, then its action and observation noise.
    rng: ChaCha8Rng,
    /// This episode's values.
    pub(super) draw: PhysicsDraw,
    /// Actions given and not yet applied (latency).
    pending: VecDeque<[f32; ACTION_DIM]>,
    /// This step's offsets of the observed positions (grip, then blocks).
    pub(super) obs_offsets: Vec<[f64; 3]>,
}

impl Dynamics {
    /// For `spec` on `model` (the scene's, read before any draw) with these block bodies.
    pub(super) fn new(spec: PhysicsSpec, model: &crate::sim::mj::Model, blocks: &[usize]) -> Self {
        let mut rng = ChaCha8Rng::from_entropy();
        rng.set_stream(PHYSICS_STREAM);
        let draw = PhysicsSpec::default().draw(&mut rng);
        Self {
            spec,
            nominal: Nominal::read(model, blocks),
            rng,
            draw,
            pending: VecDeque::new(),
            obs_offsets: Vec::new(),
        }
    }

    fn noise(&mut self, sd: f64) -> f64 {
        let z: f64 = StandardNormal.sample(&mut self.rng);
        sd * z
    }
}

impl BlockEnv {
    /// The episode's drawn dynamics (None: the task has no `[physics]` table).
    pub fn physics(&self) -> Option<PhysicsDraw> {
        self.dynamics.as_ref().map(|d| d.draw)
    }

    /// Pins parameters of the task's `[physics]` table to values, for the episodes that follow
    /// (`reset`'s `physics` option); an empty list draws every one again.
    ///
    /// # Errors
    /// [`EnvError::Physics`] for a task without a `[physics]` table, an unknown parameter, one the
    /// task does not vary, or a value outside the task's range; nothing changes.
    pub fn pin_physics(&mut self, fixed: &[(String, f64)]) -> Result<(), EnvError> {
        let task = self.config.task.spec.physics.as_ref();
        let (Some(task), Some(d)) = (task, self.dynamics.as_mut()) else {
            if fixed.is_empty() {
                return Ok(());
            }
            return Err(EnvError::Physics(format!(
                "physics options for {}, a task with no [physics] table: its dynamics do not vary; drop the \
                 option, or add a [physics] table to the task",
                self.config.task.source.id
            )));
        };
        d.spec = task.pinned(fixed).map_err(EnvError::Physics)?;
        Ok(())
    }

    /// Re-seeds the dynamics' generator with the episode's seed (`reset(Some(seed))`).
    pub(super) fn seed_physics(&mut self, seed: u64) {
        if let Some(d) = self.dynamics.as_mut() {
            d.rng = ChaCha8Rng::seed_from_u64(seed);
            d.rng.set_stream(PHYSICS_STREAM);
        }
    }

    /// Draws the episode's dynamics and sets the model's, before the layout's settle: at every
    /// layout a reset tries, so a layout redrawn (a stack that fell while settling under soft
    /// contacts, say) is redrawn with its dynamics.
    pub(super) fn draw_physics(&mut self) -> Result<(), EnvError> {
        let Some(d) = self.dynamics.as_mut() else { return Ok(()) };
        d.draw = d.spec.draw(&mut d.rng);
        d.pending.clear();
        d.obs_offsets.clear();
        let model = self.data.model_mut()?;
        d.nominal.apply(model, &d.draw.scales);
        Ok(())
    }

    /// The action to apply this step: the given one with the episode's noise, after its latency
    /// (a zero action until the first given one is due); the given one without a table.
    pub(super) fn acting(&mut self, action: &[f32]) -> [f32; ACTION_DIM] {
        let given: [f32; ACTION_DIM] = std::array::from_fn(|k| action[k]);
        let Some(d) = self.dynamics.as_mut() else { return given };
        let sd = d.draw.action_noise;
        let noisy = if sd > 0.0 { given.map(|a| a + d.noise(sd) as f32) } else { given };
        d.pending.push_back(noisy);
        if d.pending.len() > d.draw.latency {
            d.pending.pop_front().unwrap_or([0.0; ACTION_DIM])
        } else {
            [0.0; ACTION_DIM]
        }
    }

    /// The gripper's displacement per unit action (m).
    pub(super) fn action_scale(&self) -> f64 {
        ACTION_SCALE * self.dynamics.as_ref().map_or(1.0, |d| d.draw.gain)
    }

    /// Draws this step's offsets of the observed positions.
    pub(super) fn draw_obs_noise(&mut self) {
        let n = self.scene.blocks.len() + 1;
        let Some(d) = self.dynamics.as_mut() else { return };
        let sd = d.draw.obs_noise;
        d.obs_offsets.clear();
        if sd > 0.0 {
            for _ in 0..n {
                let o = [d.noise(sd), d.noise(sd), d.noise(sd)];
                d.obs_offsets.push(o);
            }
        }
    }
}
