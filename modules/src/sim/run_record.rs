//! What `sim.recorder` gathers over a run for its summary and picture: the sampled trajectory
//! and its colours, the contexts' log, the localization error statistics.
//!
//! It is also the recorder's memory (`state/run`): a recorder restarted or moved off its
//! agent's thread goes on with the same record, so the summary and the picture cover the whole
//! run, not the last instance's part of it.

use petrel_actors::Point2;
use serde::{Deserialize, Serialize};

use super::context_log::ContextLog;

/// A run's record so far.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Sampled positions, in order.
    pub trajectory: Vec<Point2>,
    /// The colour of each trajectory point (the highest-priority context active there).
    pub colours: Vec<[u8; 3]>,
    /// Which contexts were active when.
    pub contexts: ContextLog,
    /// Sum, count and maximum of the localization error samples, metres.
    pub errors: (f64, u64, f64),
    /// The latest position (not necessarily sampled).
    pub last: Option<Point2>,
    /// Simulated time of the latest progress line, s.
    pub last_progress: f64,
    /// Wall time of the run's earlier instances, s.
    pub wall_before: f64,
}

impl RunRecord {
    /// Adds a localization error sample, metres.
    pub fn error(&mut self, e: f64) {
        let (sum, n, max) = self.errors;
        self.errors = (sum + e, n + 1, max.max(e));
    }

    /// Moves to `p`: returns the distance from the latest position (0 for the first), and
    /// samples `p` with `colour` when it is `sample_m` or more from the latest sample.
    pub fn moved(&mut self, p: Point2, sample_m: f64, colour: [u8; 3]) -> f64 {
        let step = self.last.map_or(0.0, |last| (p.0 - last.0).norm());
        let from_sample = self
            .trajectory
            .last()
            .map_or(f64::INFINITY, |q| (p.0 - q.0).norm());
        if from_sample >= sample_m {
            self.sample(p, colour);
        }
        self.last = Some(p);
        step
    }

    /// Samples `p` whatever its distance (the end of a run).
    pub fn sample(&mut self, p: Point2, colour: [u8; 3]) {
        self.trajectory.push(p);
        self.colours.push(colour);
    }

    /// Whether a progress line is due at `t` with one every `every` seconds (0: never); if
    /// so, it is taken as printed.
    pub fn progress_due(&mut self, t: f64, every: f64) -> bool {
        let due = every > 0.0 && t - self.last_progress >= every;
        if due {
            self.last_progress = t;
        }
        due
    }
}

/// For each true victim, the distance to the found one matched to it (greedy by distance,
/// each found victim used once, within `radius`), or `None` when it was missed.
pub fn match_victims(truth: &[Point2], found: &[Point2], radius: f64) -> Vec<Option<f64>> {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (i, t) in truth.iter().enumerate() {
        for (j, f) in found.iter().enumerate() {
            let d = (t.0 - f.0).norm();
            if d <= radius {
                pairs.push((d, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = vec![None; truth.len()];
    let mut used = vec![false; found.len()];
    for (d, i, j) in pairs {
        if out[i].is_none() && !used[j] {
            out[i] = Some(d);
            used[j] = true;
        }
    }
    out
}

impl petrel_actors::PropertyType for RunRecord {
    const TYPE_NAME: &'static str = "sim.run_record";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_every_so_many_metres_and_sums_the_distance() {
        let mut r = RunRecord::default();
        let blue = [0, 0, 255];
        assert_eq!(r.moved(Point2::new(0.0, 0.0), 0.5, blue), 0.0);
        assert_eq!(r.moved(Point2::new(0.3, 0.0), 0.5, blue), 0.3);
        assert!((r.moved(Point2::new(0.6, 0.0), 0.5, [9, 9, 9]) - 0.3).abs() < 1e-12);
        assert_eq!(r.trajectory, [Point2::new(0.0, 0.0), Point2::new(0.6, 0.0)]);
        assert_eq!(r.colours, [blue, [9, 9, 9]]);
        assert!(!r.progress_due(5.0, 0.0), "0: never");
        assert!(r.progress_due(5.0, 5.0) && !r.progress_due(9.0, 5.0) && r.progress_due(10.0, 5.0));
    }

    #[test]
    fn the_record_comes_back_whole_through_rons_dynamic_values() {
        let mut r = RunRecord::default();
        r.moved(Point2::new(1.0, 2.0), 0.05, [1, 2, 3]);
        r.error(0.25);
        r.contexts.update(1.0, "dark, rough");
        r.contexts.update(2.0, "rough");
        r.wall_before = 3.5;
        // A snapshot is read back through RON's dynamic values.
        let back: RunRecord = crate::test_support::through_ron_values(&r);
        assert_eq!(back, r);
        assert_eq!(back.contexts.totals(3.0), r.contexts.totals(3.0));
    }
}
