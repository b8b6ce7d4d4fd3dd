//! Hindsight colour relabelling (the core part; training stores the copies): an episode in
//! which blue touched a grey block is a success of the task in which that
//! block had been green. Given the contacts an episode recorded at every
//! physics substep, this module proposes other colourings of its blocks and
//! replays the same colour rules ([`Rules`]) over the same contacts, so a
//! relabelled reward or termination is exactly what the environment would
//! have reported had the colours been those (a relabelled red–blue contact
//! is a failure; nothing succeeds that the rules would not call a success).
//!
//! Pure: no MuJoCo, no training. The environment records the substeps'
//! contacts on request ([`crate::env::BlockEnv::record_substeps`]); the
//! observation's colour one-hots are rewritten with [`recolour_obs`].

use crate::env::Fixture;
use crate::env::ObsSpec;
use crate::sim::rules::{Colour, RuleError, Rules, Touching, Verdict};
use crate::sim::scene::{FIRST_BLOCK_OBJECT, GRIPPER_OBJECT, TABLE_OBJECT};
use serde::{Deserialize, Serialize};

/// Which other tasks an episode is relabelled as (`--hindsight-strategy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// A block that blue touched becomes green (the green blocks take its colour).
    #[default]
    BlueTouched,
    /// That, and also: a block that touched a green one becomes blue (the blue blocks take its
    /// colour), the task in which it was the block to move. Candidates in the order the
    /// contacts first happened, whichever kind.
    Pairs,
}

/// One step of an episode replayed under some colouring: the reward and
/// termination the environment gives (see [`crate::env::Step`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Replayed {
    /// −1 per step, 0 on success, −(steps left, this one included) on failure.
    pub reward: f32,
    /// The rules ended the episode at this step.
    pub terminated: bool,
}

/// The rewards and terminations of an episode whose rule objects had
/// `colours`, from the contacts of each step's substeps (`steps[t]` lists
/// the [`Touching`] of every substep of step t, in order). The replay stops
/// at the first terminal step: under this colouring the episode ended there.
///
/// # Errors
/// A colouring the rules refuse (no blue, no green, too many objects).
pub fn replay(colours: &[Colour], steps: &[Vec<Touching>], max_steps: usize) -> Result<Vec<Replayed>, RuleError> {
    let mut rules = Rules::new(colours.to_vec())?;
    let mut out = Vec::with_capacity(steps.len());
    for (t, substeps) in steps.iter().enumerate() {
        for touching in substeps {
            rules.observe(touching);
        }
        let reward = match rules.verdict() {
            Some(Verdict::Success) => 0.0,
            Some(Verdict::Failure) => -((max_steps + 1).saturating_sub(t + 1) as f32),
            None => -1.0,
        };
        let terminated = rules.verdict().is_some();
        out.push(Replayed { reward, terminated });
        if terminated {
            break;
        }
    }
    Ok(out)
}

/// Up to `k` other colourings of the blocks under which the episode would
/// have gone differently, in the order the contacts first happened: for
/// each block that is neither blue nor green and touched a blue object,
/// the task in which it is green and every green block takes its colour
/// (the roles swapped); with [`Strategy::Pairs`] also, for each such block
/// that touched a green object, the task in which it is blue and every blue
/// block takes its colour. With `fixtures` (an observation that shows the gripper's and the
/// table's colours: the `entities` one) the gripper and the table are candidates too, where the
/// rules allow: a gripper that pushed blue becomes the green goal, one that touched green becomes
/// the blue object to move; a colouring the rules decide in the episode's first step (the table
/// under a blue block from the start) is left out, as nothing was done to reach it. Without, the
/// gripper and table keep their colours. Colourings equal to the original or to an earlier one
/// are left out.
pub fn alternatives(
    colours: &[Colour],
    steps: &[Vec<Touching>],
    k: usize,
    strategy: Strategy,
    fixtures: bool,
) -> Vec<Vec<Colour>> {
    let is_block = |o: usize| o >= FIRST_BLOCK_OBJECT && o < colours.len();
    let is_fixture = |o: usize| fixtures && (o == GRIPPER_OBJECT || o == TABLE_OBJECT) && o < colours.len();
    // (block, the role it takes)
    let mut order: Vec<(usize, Colour)> = Vec::new();
    for touching in steps.iter().flatten() {
        for (a, b) in touching.pairs() {
            for (x, y) in [(a, b), (b, a)] {
                if !(is_block(y) || is_fixture(y)) || matches!(colours[y], Colour::Blue | Colour::Green) {
                    continue;
                }
                let role = match colours[x] {
                    Colour::Blue => Colour::Green,
                    Colour::Green if strategy == Strategy::Pairs => Colour::Blue,
                    _ => continue,
                };
                if !order.contains(&(y, role)) {
                    order.push((y, role));
                }
            }
        }
    }
    let mut out: Vec<Vec<Colour>> = Vec::new();
    for (y, role) in order {
        if out.len() == k {
            break;
        }
        let mut c = colours.to_vec();
        for (o, colour) in c.iter_mut().enumerate() {
            if is_block(o) && *colour == role {
                *colour = colours[y];
            }
        }
        c[y] = role;
        let decided_at_once =
            || replay(&c, &steps[..steps.len().min(1)], 1).map_or(true, |r| r.iter().any(|s| s.terminated));
        if is_fixture(y) && decided_at_once() {
            continue;
        }
        if c != colours && !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

/// `obs` (laid out as `spec` says) with each block's colour one-hot set to
/// its colour in `colours` (rule objects: gripper, table, blocks, …), and the
/// gripper's and table's rows' where the layout has them (`entities`);
/// absent blocks (no colour in the observation) stay as they are.
pub fn recolour_obs(spec: &ObsSpec, obs: &mut [f32], colours: &[Colour]) {
    let (start, dim) = (spec.robot_dim(), spec.object_dim());
    let fixture_rows = [(Fixture::Gripper, GRIPPER_OBJECT), (Fixture::Table, TABLE_OBJECT)]
        .into_iter()
        .filter_map(|(f, o)| Some((spec.fixture_row(f)?, *colours.get(o)?)));
    let block_rows = (0..spec.max_objects).map_while(|k| Some((k, *colours.get(FIRST_BLOCK_OBJECT + k)?)));
    for (k, colour) in block_rows.chain(fixture_rows) {
        let at = start + k * dim + crate::env::COLOUR_FEATURE;
        let Some(hot) = obs.get_mut(at..at + 4) else { continue };
        if hot.iter().any(|&v| v > 0.5) {
            hot.copy_from_slice(&colour.one_hot());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Colour::{Blue, Green, Grey, Red};

    /// gripper, table, blue, green, grey, red: the objects of a small task.
    const COLOURS: [Colour; 6] = [Grey, Grey, Blue, Green, Grey, Red];

    fn substeps(pairs: &[&[(usize, usize)]]) -> Vec<Touching> {
        pairs.iter().map(|p| Touching::from_pairs(COLOURS.len(), p)).collect()
    }

    #[test]
    fn blue_touching_grey_is_a_success_once_grey_is_green() {
        // step 0: gripper pushes blue; step 1: blue touches grey; step 2: blue touches red.
        let steps = vec![substeps(&[&[(0, 2)], &[(0, 2)]]), substeps(&[&[(0, 2)], &[(2, 4)]]), substeps(&[&[(2, 5)]])];
        let original = replay(&COLOURS, &steps, 50).unwrap();
        assert_eq!(original.len(), 3);
        assert_eq!(original[2], Replayed { reward: -48.0, terminated: true }, "red touched blue at step 3");
        let alt = alternatives(&COLOURS, &steps, 4, Strategy::BlueTouched, false);
        // grey (4) first, then red (5): both touched blue.
        assert_eq!(alt, vec![vec![Grey, Grey, Blue, Grey, Green, Red], vec![Grey, Grey, Blue, Red, Grey, Green]]);
        let grey_green = replay(&alt[0], &steps, 50).unwrap();
        assert_eq!(
            grey_green,
            vec![Replayed { reward: -1.0, terminated: false }, Replayed { reward: 0.0, terminated: true }]
        );
        // Red as the goal: blue reached it at step 3, and nothing red touched blue before.
        let red_green = replay(&alt[1], &steps, 50).unwrap();
        assert_eq!(red_green.last(), Some(&Replayed { reward: 0.0, terminated: true }));
        assert_eq!(alternatives(&COLOURS, &steps, 1, Strategy::BlueTouched, false).len(), 1);
    }

    #[test]
    fn with_pairs_a_block_that_touched_green_becomes_blue() {
        // step 0: blue touches grey; step 1: grey touches green; step 2: red touches grey.
        let steps = vec![substeps(&[&[(2, 4)]]), substeps(&[&[(3, 4)]]), substeps(&[&[(4, 5)]])];
        assert_eq!(
            alternatives(&COLOURS, &steps, 4, Strategy::BlueTouched, false),
            vec![vec![Grey, Grey, Blue, Grey, Green, Red]]
        );
        let alt = alternatives(&COLOURS, &steps, 4, Strategy::Pairs, false);
        // grey as green first (blue touched it first), then grey as blue (blue becomes grey).
        assert_eq!(alt, vec![vec![Grey, Grey, Blue, Grey, Green, Red], vec![Grey, Grey, Grey, Green, Blue, Red]]);
        let grey_blue = replay(&alt[1], &steps, 50).unwrap();
        assert_eq!(grey_blue.len(), 2, "ends when the new blue meets green, before red touches it");
        assert_eq!(grey_blue[1], Replayed { reward: 0.0, terminated: true });
        // Red touching the block first makes that task a failure instead.
        let red_first = vec![substeps(&[&[(4, 5)]]), substeps(&[&[(3, 4)]])];
        let alt = alternatives(&COLOURS, &red_first, 4, Strategy::Pairs, false);
        assert_eq!(alt, vec![vec![Grey, Grey, Grey, Green, Blue, Red]]);
        assert_eq!(replay(&alt[0], &red_first, 50).unwrap(), vec![Replayed { reward: -50.0, terminated: true }]);
        assert_eq!(alternatives(&COLOURS, &steps, 1, Strategy::Pairs, false).len(), 1, "at most k");
    }

    #[test]
    fn a_relabelled_red_blue_contact_is_a_failure_and_failure_wins_a_tie() {
        // Blue touches grey and, in the same substep, the block that is red.
        let steps = vec![substeps(&[&[(2, 4), (2, 5)]])];
        let alt = alternatives(&COLOURS, &steps, 4, Strategy::BlueTouched, false);
        let as_green = replay(&alt[0], &steps, 50).unwrap();
        assert_eq!(as_green, vec![Replayed { reward: -50.0, terminated: true }]);
    }

    #[test]
    fn relabelling_creates_no_success_the_rules_would_not() {
        // Random contact sequences: wherever a replay reports success, some substep of that step
        // has every blue touching a green one, and no substep before it has red touching blue.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..300 {
            let steps: Vec<Vec<Touching>> = (0..rng.gen_range(1..8))
                .map(|_| {
                    (0..3)
                        .map(|_| {
                            let pairs: Vec<(usize, usize)> =
                                (0..rng.gen_range(0..3)).map(|_| (rng.gen_range(0..6), rng.gen_range(0..6))).collect();
                            Touching::from_pairs(6, &pairs)
                        })
                        .collect()
                })
                .collect();
            let alts = [(Strategy::BlueTouched, false), (Strategy::Pairs, false), (Strategy::Pairs, true)]
                .map(|(s, fixtures)| alternatives(&COLOURS, &steps, 3, s, fixtures));
            for colours in std::iter::once(COLOURS.to_vec()).chain(alts.into_iter().flatten()) {
                let r = replay(&colours, &steps, 50).unwrap();
                let Some(end) = r.iter().position(|s| s.terminated) else { continue };
                if r[end].reward != 0.0 {
                    continue;
                }
                let rules = Rules::new(colours.clone()).unwrap();
                let earlier_violation = steps[..end].iter().flatten().any(|t| rules.violation(t).is_some());
                assert!(!earlier_violation, "{colours:?}: success after a failure");
                let succeeded = steps[end].iter().any(|t| rules.all_blue_on_green(t));
                assert!(succeeded, "{colours:?}: success with no substep of every blue on green");
            }
        }
    }

    #[test]
    fn with_fixtures_the_gripper_becomes_the_goal_or_the_object_but_the_table_under_blue_does_not() {
        // step 0: the table under blue, green and grey (resting); step 1: the gripper pushes blue;
        // step 2: the gripper touches green.
        let resting: &[(usize, usize)] = &[(1, 2), (1, 3), (1, 4)];
        let steps = vec![substeps(&[resting]), substeps(&[&[(0, 2), (1, 2)]]), substeps(&[&[(0, 3), (1, 3)]])];
        assert_eq!(alternatives(&COLOURS, &steps, 4, Strategy::Pairs, false), Vec::<Vec<Colour>>::new());
        let alt = alternatives(&COLOURS, &steps, 4, Strategy::Pairs, true);
        // The gripper as the green goal (the green block grey), then as the blue object (blue grey);
        // the table green or blue is decided at step 0 (blue rests on it) and left out.
        assert_eq!(alt, vec![vec![Green, Grey, Blue, Grey, Grey, Red], vec![Blue, Grey, Grey, Green, Grey, Red]]);
        assert_eq!(replay(&alt[0], &steps, 50).unwrap().last(), Some(&Replayed { reward: 0.0, terminated: true }));
        let as_blue = replay(&alt[1], &steps, 50).unwrap();
        assert_eq!((as_blue.len(), as_blue[2]), (3, Replayed { reward: 0.0, terminated: true }));
        // A table that blue reaches only later (a block lifted off the start) is a candidate; the
        // gripper, holding blue from the first step, is not.
        let later = vec![substeps(&[&[(0, 2)]]), substeps(&[&[(1, 2)]])];
        let table = alternatives(&COLOURS, &later, 4, Strategy::BlueTouched, true);
        assert_eq!(table, vec![vec![Grey, Green, Blue, Grey, Grey, Red]]);
    }

    #[test]
    fn recolouring_rewrites_the_gripper_and_table_rows_of_an_entities_observation() {
        let spec = ObsSpec::new(crate::env::ObsMode::Entities, 3);
        let mut obs = vec![0.0; spec.dim()];
        let row = |k: usize| spec.robot_dim() + k * spec.object_dim() + crate::env::COLOUR_FEATURE;
        let (gripper, table, floor) = (
            spec.fixture_row(Fixture::Gripper).unwrap(),
            spec.fixture_row(Fixture::Table).unwrap(),
            spec.fixture_row(Fixture::Floor).unwrap(),
        );
        for (k, c) in [(0, Blue), (1, Green), (gripper, Grey), (table, Grey)] {
            obs[row(k)..row(k) + 4].copy_from_slice(&c.one_hot());
        }
        // The gripper green, the green block grey; slot 2 absent and the floor no rule object: zero rows.
        recolour_obs(&spec, &mut obs, &[Green, Grey, Blue, Grey]);
        assert_eq!(&obs[row(gripper)..row(gripper) + 4], &Green.one_hot());
        assert_eq!(&obs[row(table)..row(table) + 4], &Grey.one_hot());
        assert_eq!(&obs[row(1)..row(1) + 4], &Grey.one_hot());
        assert_eq!(&obs[row(2)..row(2) + 4], &[0.0; 4]);
        assert_eq!(&obs[row(floor)..row(floor) + 4], &[0.0; 4]);
    }

    #[test]
    fn recolouring_rewrites_only_present_blocks() {
        let spec = ObsSpec::new(crate::env::ObsMode::Objects, 4);
        let mut obs = vec![0.0; spec.dim()];
        let row = |k: usize| spec.robot_dim() + k * spec.object_dim() + crate::env::COLOUR_FEATURE;
        for (k, c) in [Blue, Green, Grey].iter().enumerate() {
            obs[row(k)..row(k) + 4].copy_from_slice(&c.one_hot());
        }
        // slot 3 absent: zero row
        recolour_obs(&spec, &mut obs, &[Grey, Grey, Blue, Grey, Green, Grey]);
        assert_eq!(&obs[row(1)..row(1) + 4], &Grey.one_hot());
        assert_eq!(&obs[row(2)..row(2) + 4], &Green.one_hot());
        assert_eq!(&obs[row(3)..row(3) + 4], &[0.0; 4]);
    }
}
