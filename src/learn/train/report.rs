//! What a run's `progress.csv` says about the time to a result: when the
//! success first reached a target (epoch, environment steps, wall-clock
//! time), and where an epoch's time goes.

use super::EpochRow;
use std::fmt::Write as _;

/// The first epoch at which a success measure reached the target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reached {
    /// The epoch (0-based).
    pub epoch: usize,
    /// Environment steps by its end.
    pub env_steps: u64,
    /// Wall-clock seconds by its end.
    pub wall_seconds: f64,
}

/// Mean seconds per epoch by phase.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Split {
    /// Exploration episodes (environment and policy).
    pub collection: f64,
    /// Gradient and target updates.
    pub updates: f64,
    /// Test and finals episodes.
    pub evaluation: f64,
    /// Writing progress, plot, policies and checkpoint.
    pub persist: f64,
    /// The rest of the epoch (bookkeeping).
    pub other: f64,
}

impl Split {
    /// Seconds per epoch in all.
    pub fn total(&self) -> f64 {
        self.collection + self.updates + self.evaluation + self.persist + self.other
    }
}

/// The first row whose `measure` is at least `target`; with `window` > 1,
/// the first whose mean over the last `window` rows is.
pub fn first_reaching(rows: &[EpochRow], measure: fn(&EpochRow) -> f64, target: f64, window: usize) -> Option<Reached> {
    let w = window.max(1);
    (w - 1..rows.len()).find_map(|i| {
        let mean = rows[i + 1 - w..=i].iter().map(measure).sum::<f64>() / w as f64;
        (mean >= target).then(|| Reached {
            epoch: rows[i].epoch,
            env_steps: rows[i].env_steps,
            wall_seconds: rows[i].wall_seconds,
        })
    })
}

/// Mean time split of the rows, which start at epoch 0 (each epoch's wall
/// time is the difference of consecutive `wall_seconds`; rows written before a column existed count
/// it as zero, and their time lands in `other`).
pub fn split(rows: &[EpochRow]) -> Split {
    if rows.is_empty() {
        return Split::default();
    }
    let mut s = Split::default();
    // Rows start at epoch 0 (a resumed run keeps its earlier rows).
    let mut previous = 0.0;
    for r in rows {
        let wall = r.wall_seconds - previous;
        previous = r.wall_seconds;
        s.collection += r.env_seconds - r.eval_seconds;
        s.evaluation += r.eval_seconds;
        s.updates += r.update_seconds;
        s.persist += r.persist_seconds;
        s.other += (wall - r.env_seconds - r.update_seconds - r.persist_seconds).max(0.0);
    }
    let n = rows.len() as f64;
    Split {
        collection: s.collection / n,
        updates: s.updates / n,
        evaluation: s.evaluation / n,
        persist: s.persist / n,
        other: s.other / n,
    }
}

fn when(r: Option<Reached>) -> String {
    match r {
        Some(r) => {
            format!("epoch {} ({:.2} M env steps, {:.2} h)", r.epoch, r.env_steps as f64 / 1e6, r.wall_seconds / 3600.0)
        }
        None => "not reached".into(),
    }
}

/// A plain-text report: levels, when test and finals success first reached
/// `target` (single epochs and 5-epoch means), and the time split.
pub fn text(title: &str, rows: &[EpochRow], max_level: usize, target: f64) -> String {
    let mut s = String::new();
    let Some(last) = rows.last() else {
        return format!("{title}: no epochs yet\n");
    };
    let _ = writeln!(
        s,
        "{title}: {} epochs, {:.2} M env steps, {:.2} h, level {} of {max_level}",
        rows.len(),
        last.env_steps as f64 / 1e6,
        last.wall_seconds / 3600.0,
        last.level
    );
    let top = rows.iter().find(|r| r.level >= max_level);
    let _ = writeln!(
        s,
        "  maximum level first played: {}",
        when(top.map(|r| Reached { epoch: r.epoch, env_steps: r.env_steps, wall_seconds: r.wall_seconds }))
    );
    let finals = |r: &EpochRow| r.finals_success;
    let _ = writeln!(s, "  finals success >= {target}: {}", when(first_reaching(rows, finals, target, 1)));
    let _ = writeln!(
        s,
        "  finals success, mean of 5 epochs >= {target}: {}",
        when(first_reaching(rows, finals, target, 5))
    );
    let recent = &rows[rows.len().saturating_sub(5)..];
    let mean_finals = recent.iter().map(|r| r.finals_success).sum::<f64>() / recent.len() as f64;
    let _ = writeln!(s, "  finals success, mean of the last {} epochs: {mean_finals:.3}", recent.len());
    let sp = split(rows);
    let pct = |x: f64| 100.0 * x / sp.total().max(1e-9);
    let _ = writeln!(
        s,
        "  seconds per epoch {:.1}: collection {:.1} ({:.0}%), updates {:.1} ({:.0}%), evaluation {:.1} ({:.0}%), files {:.1} ({:.0}%), other {:.1}",
        sp.total(),
        sp.collection,
        pct(sp.collection),
        sp.updates,
        pct(sp.updates),
        sp.evaluation,
        pct(sp.evaluation),
        sp.persist,
        pct(sp.persist),
        sp.other
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(epoch: usize, finals: f64) -> EpochRow {
        EpochRow {
            epoch,
            level: epoch.min(3),
            train_success: 0.0,
            test_success: 0.0,
            finals_success: finals,
            mean_q: 0.0,
            critic_loss: 0.0,
            actor_loss: 0.0,
            env_steps: 1000 * (epoch as u64 + 1),
            updates: 0,
            wall_seconds: 10.0 * (epoch as f64 + 1.0),
            env_seconds: 3.0,
            forward_seconds: 0.5,
            update_seconds: 5.0,
            reduce_seconds: 0.1,
            eval_seconds: 1.0,
            persist_seconds: 1.5,
            beta: 0.0,
            expert_share: 0.0,
            relabelled: 0.0,
            relabelled_success: 0.0,
            cpu_utilisation: 1.0,
        }
    }

    #[test]
    fn first_reaching_single_epochs_and_means() {
        let rows: Vec<EpochRow> =
            [0.1, 0.96, 0.5, 0.95, 0.97, 1.0, 0.95, 0.95].iter().enumerate().map(|(e, &f)| row(e, f)).collect();
        let f = |r: &EpochRow| r.finals_success;
        let r = first_reaching(&rows, f, 0.95, 1).unwrap();
        assert_eq!((r.epoch, r.env_steps, r.wall_seconds), (1, 2000, 20.0));
        // means of 5: epochs 0-4 0.696, 1-5 0.876, 2-6 0.874, 3-7 0.964
        assert_eq!(first_reaching(&rows, f, 0.95, 5).unwrap().epoch, 7);
        assert!(first_reaching(&rows, f, 1.01, 1).is_none());
    }

    #[test]
    fn split_adds_up_to_the_epoch() {
        let rows: Vec<EpochRow> = (0..4).map(|e| row(e, 0.0)).collect();
        let s = split(&rows);
        assert_eq!((s.collection, s.updates, s.evaluation, s.persist), (2.0, 5.0, 1.0, 1.5));
        assert!((s.total() - 10.0).abs() < 1e-9, "{s:?}");
        let t = text("DDPG on X", &rows, 3, 0.95);
        assert!(
            t.contains("4 epochs") && t.contains("maximum level first played: epoch 3") && t.contains("not reached"),
            "{t}"
        );
    }
}
