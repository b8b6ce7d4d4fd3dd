//! The task framework against real MuJoCo: every registered task resets
//! cleanly at every level, the rules fire in simulation for the new tasks,
//! the scripted controllers solve them, and task files round-trip.

use blockpuzzle::env::{registry, BlockEnv, EnvConfig, EnvError};
use blockpuzzle::episode::rollout::run_episode;
use blockpuzzle::policy::{RandomPolicy, ScriptedPolicy};
use blockpuzzle::sim::rules::Colour;
use blockpuzzle::task::Task;

fn make(id: &str) -> BlockEnv {
    registry::make(id).unwrap()
}

/// Index of the first rule object of this colour.
fn object(env: &BlockEnv, colour: Colour) -> usize {
    env.objects().iter().position(|o| o.colour == colour).unwrap()
}

#[test]
fn every_task_round_trips_through_its_file() {
    for id in registry::ids() {
        let task = registry::task(id).unwrap();
        let text = toml::to_string(&task.spec).unwrap();
        let again = Task::from_toml(&text, None).unwrap();
        assert_eq!(again.spec, task.spec, "{id}");
        assert_eq!(again.source.hash, task.source.hash, "{id}: the hash is of the content, not the text");
        assert!(task.differences(&again).is_empty());
    }
}

#[test]
fn every_task_resets_at_every_level_without_a_rule_broken() {
    for id in registry::ids() {
        let mut env = make(id);
        let task = env.config().task.clone();
        let mut settings: Vec<(usize, Option<&str>)> = (0..=task.max_level()).map(|l| (l, None)).collect();
        settings.extend(task.distribution_names().into_iter().map(|d| (task.max_level(), Some(d))));
        for (level, dist) in settings {
            env.set_level(level).unwrap();
            env.set_distribution(dist).unwrap();
            for seed in 0..8 {
                let (obs, info) = env.reset(Some(seed)).unwrap_or_else(|e| panic!("{id} level {level} {dist:?}: {e}"));
                assert!(obs.iter().all(|v| v.is_finite()));
                let colour = |i: usize| env.objects()[i].colour;
                for &(a, b) in &info.touching {
                    let pair = [colour(a), colour(b)];
                    assert!(
                        !(pair.contains(&Colour::Red) && pair.contains(&Colour::Blue)),
                        "{id} level {level} seed {seed}: red touches blue at reset"
                    );
                }
                assert_eq!(env.verdict(), None);
            }
        }
    }
}

#[test]
fn scripted_controllers_solve_the_new_tasks_and_random_actions_rarely_do() {
    // (id, scripted successes at least, and rule breaks at most, of 20 seeded episodes at the
    // evaluation level); results/tasks.md reports the rates over 200 episodes. Only the route
    // around BlocksAvoid-v0's red blocks sometimes brushes one (2% at level 5).
    for (id, at_least, broke_at_most) in [
        ("ReachAvoid-v0", 18, 0),
        ("ToppleTower-v0", 16, 0),
        ("BlocksStack-v0", 18, 0),
        ("BlocksChooseShuffled-v0", 15, 0),
        ("BlocksChooseN-v0", 15, 0),
        ("BlocksAvoid-v0", 16, 2),
        ("BlocksGather-v0", 13, 0),
    ] {
        let mut env = make(id);
        env.set_level(env.max_level()).unwrap();
        let mut scripted = ScriptedPolicy::for_env(env.config());
        let mut random = RandomPolicy::new(0);
        let (mut wins, mut broke, mut random_wins) = (0, 0, 0);
        for seed in 1000..1020 {
            let ep = run_episode(&mut env, &mut scripted, seed).unwrap();
            broke += ep.failure as usize;
            wins += ep.success as usize;
            random_wins += run_episode(&mut env, &mut random, seed).unwrap().success as usize;
        }
        assert!(broke <= broke_at_most, "{id}: the scripted controller broke the rule in {broke}/20");
        assert!(wins >= at_least, "{id}: scripted {wins}/20");
        assert!(random_wins <= 4, "{id}: random actions won {random_wins}/20");
    }
}

/// Steps towards `target` with the gripper (proportional, clipped) until the episode ends.
fn drive(env: &mut BlockEnv, target: impl Fn(&BlockEnv) -> [f64; 3], grip_action: f32) -> blockpuzzle::Step {
    loop {
        let g = env.gripper_position();
        let t = target(env);
        let mut a = [grip_action; 4];
        for k in 0..3 {
            a[k] = ((t[k] - g[k]) / 0.05).clamp(-1.0, 1.0) as f32;
        }
        let s = env.step(&a).unwrap();
        if s.terminated || s.truncated {
            return s;
        }
    }
}

#[test]
fn toppled_tower_succeeds_and_the_red_gripper_touching_blue_fails() {
    let mut env = make("ToppleTower-v0");
    env.reset(Some(3)).unwrap();
    let mut policy = ScriptedPolicy::for_env(env.config());
    let ep = run_episode(&mut env, &mut policy, 3).unwrap();
    let (blue, table) = (object(&env, Colour::Blue), 1);
    assert!(ep.success, "the scripted swipe toppled the tower onto the table");
    let last = ep.steps.last().unwrap();
    assert!(last.touching.contains(&(table, blue)), "blue lies on the green table: {:?}", last.touching);

    // Straight at the blue block, at its height: the red gripper touches it.
    env.reset(Some(3)).unwrap();
    let b = blue - 2;
    let s = drive(&mut env, |e| e.block_positions()[b], 0.0);
    assert!(s.terminated && s.info.is_failure && !s.info.is_success, "{:?}", s.info);
    assert!(s.info.touching.contains(&(0, blue)), "{:?}", s.info.touching);
}

#[test]
fn reach_avoid_fails_through_the_wall_and_succeeds_over_it() {
    let mut env = make("ReachAvoid-v0");
    env.set_level(env.max_level()).unwrap();
    let (green, red) = (object(&env, Colour::Green) - 2, object(&env, Colour::Red));
    let mut failures = 0;
    for seed in 0..5 {
        env.reset(Some(seed)).unwrap();
        // The straight line to the block runs into the wall at the last level.
        let s = drive(&mut env, |e| e.block_positions()[green], 0.0);
        if s.info.is_failure {
            assert!(s.info.touching.contains(&(0, red)), "{:?}", s.info.touching);
            failures += 1;
        }
    }
    assert!(failures >= 4, "the wall blocked the straight path in {failures}/5");
    let mut policy = ScriptedPolicy::for_env(env.config());
    let ep = run_episode(&mut env, &mut policy, 0).unwrap();
    assert!(ep.success && !ep.failure);
}

#[test]
fn stacking_fails_when_blue_touches_the_red_table() {
    let mut env = make("BlocksStack-v0");
    let blue_obj = object(&env, Colour::Blue);
    let blue = blue_obj - 2;
    env.reset(Some(0)).unwrap();
    // Knock blue off its pedestal with the closed fingers: it falls onto the red table.
    let start = env.block_positions()[blue];
    let grip = env.gripper_position();
    let dir = [start[0] - grip[0], start[1] - grip[1]];
    let n = dir[0].hypot(dir[1]);
    let behind = [start[0] - dir[0] / n * 0.08, start[1] - dir[1] / n * 0.08, start[2]];
    let through = [start[0] + dir[0] / n * 0.2, start[1] + dir[1] / n * 0.2, start[2]];
    let mut steps = 0;
    let s = drive(
        &mut env,
        |e| {
            let g = e.gripper_position();
            let near = (g[0] - behind[0]).hypot(g[1] - behind[1]) < 0.01 && (g[2] - behind[2]).abs() < 0.01;
            if near || (g[2] - behind[2]).abs() < 0.01 && (g[0] - start[0]).hypot(g[1] - start[1]) < 0.08 {
                through
            } else if (g[0] - behind[0]).hypot(g[1] - behind[1]) > 0.01 {
                [behind[0], behind[1], behind[2] + 0.1]
            } else {
                behind
            }
        },
        -1.0,
    );
    steps += s.info.elapsed_steps;
    assert!(s.info.is_failure, "after {steps} steps: {:?}", s.info);
    assert!(s.info.touching.contains(&(1, blue_obj)), "blue touched the table: {:?}", s.info.touching);
}

#[test]
fn shuffled_roles_move_between_slots_and_the_one_hots_follow() {
    let mut env = make("BlocksChooseShuffled-v0");
    let mut blue_slots = std::collections::BTreeSet::new();
    for seed in 0..30 {
        let (obs, _) = env.reset(Some(seed)).unwrap();
        let colours = env.block_colours().to_vec();
        let mut sorted = colours.clone();
        sorted.sort_by_key(|c| *c as usize);
        assert_eq!(sorted, vec![Colour::Blue, Colour::Green, Colour::Grey], "a permutation of the roles");
        for (slot, c) in colours.iter().enumerate() {
            let hot = &obs[10 + 19 * slot + 15..10 + 19 * slot + 19];
            assert_eq!(hot, c.one_hot(), "seed {seed} slot {slot}");
            assert_eq!(env.objects()[2 + slot].colour, *c);
        }
        // The blue role keeps its start: within R = 0.08 of the gripper at level 0.
        let b = colours.iter().position(|c| *c == Colour::Blue).unwrap();
        let (p, g) = (env.block_positions()[b], env.initial_gripper_position());
        assert!((p[0] - g[0]).hypot(p[1] - g[1]) <= 0.08 + 1e-9);
        blue_slots.insert(b);
    }
    assert_eq!(blue_slots.len(), 3, "blue visited every slot");
    // Same seed, same deal.
    let a = env.reset(Some(5)).unwrap().0;
    assert_eq!(a, env.reset(Some(5)).unwrap().0);
}

#[test]
fn gripper_action_opens_and_closes_the_fingers_only_where_enabled() {
    let mut stack = make("BlocksStack-v0");
    stack.reset(Some(0)).unwrap();
    let open = (0..5).map(|_| stack.step(&[0.0, 0.0, 0.0, 1.0]).unwrap()).last().unwrap();
    assert!(open.obs[3] > 0.04 && open.obs[4] > 0.04, "fingers open: {:?}", &open.obs[3..5]);
    let closed = (0..5).map(|_| stack.step(&[0.0, 0.0, 0.0, -1.0]).unwrap()).last().unwrap();
    assert!(closed.obs[3] < 0.005 && closed.obs[4] < 0.005, "fingers closed: {:?}", &closed.obs[3..5]);
    let mut push = make("BlocksTouch-v0");
    push.reset(Some(0)).unwrap();
    let s = push.step(&[0.0, 0.0, 0.0, 1.0]).unwrap();
    assert_eq!(&s.obs[3..5], &[0.0, 0.0], "blocked fingers stay closed");
}

#[test]
fn a_layout_that_cannot_be_met_names_the_constraint() {
    let mut spec = registry::task("BlocksTouch-v0").unwrap().spec;
    spec.placement.min_separation = 0.5;
    spec.placement.max_attempts = 200;
    let mut env = BlockEnv::new(EnvConfig::from_spec(spec).unwrap()).unwrap();
    let err = env.reset(Some(0)).unwrap_err();
    assert!(matches!(err, EnvError::Placement(_)), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("200 attempts") && msg.contains("closer than min_separation"), "{msg}");
}

#[test]
fn a_coloured_floor_is_a_rule_object_and_only_blocks_avoid_has_one() {
    use blockpuzzle::task::spec::{SurfaceSpec, TaskSpec};
    // Blue near the table's edge, green far from it; the gripper pushes blue off the table.
    let spec = |floor: Option<Colour>| {
        let mut s = TaskSpec::fixed("Floor-v0", &[Colour::Blue, Colour::Green], &[[1.30, 0.44], [1.12, 1.02]]).unwrap();
        s.floor = floor.map(|colour| SurfaceSpec { colour });
        BlockEnv::new(EnvConfig::from_spec(s).unwrap()).unwrap()
    };
    let push_off = |env: &mut BlockEnv| {
        env.reset(Some(0)).unwrap();
        // Behind blue (towards the table's centre), down to the table, then out over the edge.
        for t in [[1.30, 0.52, 0.55], [1.30, 0.52, 0.425], [1.30, 0.25, 0.425]] {
            for _ in 0..12 {
                let g = env.gripper_position();
                let a: Vec<f32> = (0..3).map(|k| ((t[k] - g[k]) / 0.05).clamp(-1.0, 1.0) as f32).chain([0.0]).collect();
                let s = env.step(&a).unwrap();
                if s.terminated || s.truncated {
                    return s;
                }
            }
        }
        loop {
            let s = env.step(&[0.0; 4]).unwrap();
            if s.terminated || s.truncated {
                return s;
            }
        }
    };
    let mut red_floor = spec(Some(Colour::Red));
    assert_eq!(red_floor.objects().last().unwrap().name, "floor");
    let s = push_off(&mut red_floor);
    let floor = red_floor.objects().len() - 1;
    assert!(s.info.is_failure && s.info.touching.contains(&(2, floor)), "{:?}", s.info);
    let mut plain = spec(None);
    let s = push_off(&mut plain);
    assert!(!s.info.is_failure && s.truncated, "without a floor object, falling off changes nothing: {:?}", s.info);
    // Of the built-ins, only BlocksAvoid-v0 has a (red) floor: blue pushed off the table fails.
    for id in registry::ids() {
        let floor = registry::task(id).unwrap().spec.floor.map(|f| f.colour);
        assert_eq!(floor, (id == "BlocksAvoid-v0").then_some(Colour::Red), "{id}");
    }
}
