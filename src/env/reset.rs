//! The reset pipeline of [`BlockEnv`]: roles dealt (shuffled tasks), a
//! layout drawn by the task's sampler, the robot's settled state restored,
//! objects placed and settled, the physics checks (overlap, toppled while
//! settling, red touching blue, already solved) and a redraw on failure.

use super::*;

impl BlockEnv {
    /// Starts an episode. With `Some(seed)` the environment's generator is
    /// re-seeded, so the same seed gives a bit-identical episode for the same
    /// actions; with `None` it continues its stream (seeded from the OS at
    /// construction).
    ///
    /// The layout is drawn from the task (shuffled roles first, when the task
    /// shuffles, then the starts), settled when the task asks for it, and
    /// redrawn while the reset state has objects overlapping, an object that
    /// moved while settling, red touching blue, or the task already solved.
    ///
    /// # Errors
    /// [`EnvError::Placement`] if the sampler finds no layout,
    /// [`EnvError::ResetExhausted`] if no layout passes the physics checks,
    /// [`EnvError::InitialViolation`] if a fixed layout has red touching blue.
    pub fn reset(&mut self, seed: Option<u64>) -> Result<(Vec<f32>, Info), EnvError> {
        if let Some(s) = seed {
            self.rng = ChaCha8Rng::seed_from_u64(s);
            self.seed_physics(s);
        }
        self.phase = Phase::NeedsReset;
        let task = &self.config.task;
        let deterministic = task.is_deterministic();
        let attempts = task.spec.placement.max_reset_attempts;
        if self.varies {
            // Once per reset (physics redraws keep the counts, so they stay uniform).
            self.present = task.draw_present(self.distribution, &mut self.rng);
        }
        let mut reasons = Tally::default();
        for _ in 0..attempts {
            let Some(reason) = self.try_layout()? else {
                self.stats.resets += 1;
                self.steps = 0;
                self.phase = Phase::Running;
                self.write_obs();
                let info = self.info(false, false, self.touching.pairs());
                return Ok((self.obs.clone(), info));
            };
            if let Some((r, b)) = self.rules.violation(&self.touching).filter(|_| deterministic) {
                return Err(EnvError::InitialViolation {
                    red: self.objects[r].name.clone(),
                    blue: self.objects[b].name.clone(),
                });
            }
            self.stats.rejected.add(&reason);
            reasons.add(&reason);
            if deterministic {
                break;
            }
        }
        Err(EnvError::ResetExhausted {
            id: self.id().to_owned(),
            attempts: reasons.total() as usize,
            level: match self.distribution_name() {
                Some(d) => format!("distribution {d}"),
                None => format!("level {}", self.level),
            },
            reason: reasons.most(),
        })
    }

    /// Draws roles and a layout and puts the objects there; returns why the
    /// reset state is unusable, if it is.
    fn try_layout(&mut self) -> Result<Option<String>, EnvError> {
        self.data.copy_from(&self.initial)?;
        self.draw_physics()?;
        let roles = self.draw_roles()?;
        let origin = [self.initial_grip[0], self.initial_grip[1]];
        let placed = self.config.task.sample_counted(
            self.level,
            self.distribution,
            origin,
            &self.present,
            &mut self.rng,
            &mut self.stats.draws,
        )?;
        self.stats.layouts += 1;
        let mut targets = Vec::with_capacity(roles.len());
        for (slot, (b, &role)) in self.scene.blocks.iter().zip(&roles).enumerate() {
            // Absent (shuffles never move them): parked upright on the floor, away from everything.
            let park = || Placed {
                xy: [PARK_ORIGIN[0] + PARK_PITCH * slot as f64, PARK_ORIGIN[1]],
                z: Some(self.sizes[slot][2]),
                yaw: Some(0.0),
            };
            let Placed { xy, z, yaw } = placed[role].unwrap_or_else(park);
            let q = self.data.qpos_mut();
            q[b.qpos] = xy[0];
            q[b.qpos + 1] = xy[1];
            if let Some(z) = z {
                q[b.qpos + 2] = z;
            }
            if let Some(t) = yaw {
                let (s, c) = (t / 2.0).sin_cos();
                q[b.qpos + 3..b.qpos + 7].copy_from_slice(&[c, 0.0, 0.0, s]);
            }
            targets.push([xy[0], xy[1], q[b.qpos + 2]]);
            self.data.qvel_mut()[b.dof..b.dof + 6].fill(0.0);
        }
        self.data.forward()?;
        let settled = self.settle(&targets)?;
        self.rules.reset();
        self.scan_contacts();
        if settled.is_some() {
            return Ok(settled);
        }
        if let Some(r) = self.overlap() {
            return Ok(Some(r));
        }
        let name = |i: usize| self.objects[i].name.clone();
        if let Some((r, b)) = self.rules.violation(&self.touching) {
            return Ok(Some(format!("red {:?} touched blue {:?}", name(r), name(b))));
        }
        // A layout that already succeeds teaches nothing (the filter of PHYRE);
        // fixed layouts are kept as written (tests place blocks touching on purpose).
        if !self.config.task.is_deterministic() && self.rules.all_blue_on_green(&self.touching) {
            return Ok(Some("the task was already solved".into()));
        }
        Ok(None)
    }

    /// The role each block slot plays this episode (identity unless the task
    /// shuffles), with the colours, rule objects and rules set to match
    /// (absent blocks count as grey in the rules).
    fn draw_roles(&mut self) -> Result<Vec<usize>, EnvError> {
        let n = self.scene.blocks.len();
        let mut roles: Vec<usize> = (0..n).collect();
        if self.config.task.shuffle.is_empty() {
            if self.varies {
                self.set_rules()?;
            }
            return Ok(roles);
        }
        for group in &self.config.task.shuffle {
            let mut g = group.clone();
            g.shuffle(&mut self.rng);
            for (&slot, &role) in group.iter().zip(&g) {
                roles[slot] = role;
            }
        }
        let specs: Vec<&crate::task::spec::ObjectSpec> = self.config.task.objects().collect();
        for (slot, &role) in roles.iter().enumerate() {
            self.colours[slot] = specs[role].colour;
            let o = &mut self.objects[crate::sim::scene::FIRST_BLOCK_OBJECT + slot];
            o.colour = specs[role].colour;
            o.name.clone_from(&specs[role].name);
        }
        self.set_rules()?;
        Ok(roles)
    }

    /// The rules of this episode's colours, absent blocks counted as grey.
    fn set_rules(&mut self) -> Result<(), EnvError> {
        let colours = (0..self.objects.len())
            .map(|o| if self.is_absent(o) { Colour::Grey } else { self.objects[o].colour })
            .collect();
        self.rules = Rules::new(colours).map_err(crate::sim::scene::SceneError::from)?;
        Ok(())
    }

    /// Runs the task's settling time with the gripper held still; the first
    /// block that moved more than the tolerance from `targets`, in words.
    fn settle(&mut self, targets: &[[f64; 3]]) -> Result<Option<String>, crate::sim::mj::MjError> {
        let p = &self.config.task.spec.placement;
        if p.settle_seconds <= 0.0 {
            return Ok(None);
        }
        let steps = (p.settle_seconds / self.scene.model.timestep()).round() as usize;
        for _ in 0..steps {
            self.data.step()?;
        }
        self.data.forward()?;
        let tol = p.settle_tolerance;
        Ok(self.scene.blocks.iter().zip(targets).enumerate().find_map(|(i, (b, t))| {
            let x = &self.data.qpos()[b.qpos..b.qpos + 3];
            let moved = ((x[0] - t[0]).powi(2) + (x[1] - t[1]).powi(2) + (x[2] - t[2]).powi(2)).sqrt();
            (moved > tol || !moved.is_finite()).then(|| {
                format!(
                    "{:?} moved {moved:.3} m while settling (more than placement.settle_tolerance = {tol}): a stack that falls over?",
                    self.objects[crate::sim::scene::FIRST_BLOCK_OBJECT + i].name
                )
            })
        }))
    }

    /// Two rule objects that interpenetrate deeper than [`OVERLAP_TOLERANCE`], in words.
    fn overlap(&self) -> Option<String> {
        self.data.contacts().iter().find_map(|c| {
            let (a, b) = (self.scene.geom_object[c.geom1()], self.scene.geom_object[c.geom2()]);
            let absent = self.varies && (self.is_absent(a.max(0) as usize) || self.is_absent(b.max(0) as usize));
            (a >= 0 && b >= 0 && a != b && !absent && c.dist() < -OVERLAP_TOLERANCE).then(|| {
                format!(
                    "{:?} and {:?} overlapped (deeper than {} mm)",
                    self.objects[a as usize].name,
                    self.objects[b as usize].name,
                    OVERLAP_TOLERANCE * 1e3
                )
            })
        })
    }
}
