//! What `petrel hz` reports, computed from write stamps alone (pure, so it is tested without
//! a clock): the rate, and the intervals' mean, extremes and spread (jitter).

/// Figures over a window of stamps.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Rate {
    /// Samples in the window.
    pub samples: usize,
    /// Changes per second.
    pub hz: f64,
    /// Mean interval, s.
    pub mean_s: f64,
    /// Shortest interval, s.
    pub min_s: f64,
    /// Longest interval, s.
    pub max_s: f64,
    /// Standard deviation of the intervals, s.
    pub jitter_s: f64,
}

/// The figures of `stamps_ns` (in arrival order); `None` under two samples. The stamps are
/// taken in time order, not arrival order: a queue's batch can arrive with its first item
/// stamped after the others, and an interval counted from arrival order would go backwards
/// (left out, it made `petrel hz` report 4 items per batch of 5).
pub(crate) fn rate(stamps_ns: &[u64]) -> Option<Rate> {
    let mut sorted = stamps_ns.to_vec();
    sorted.sort_unstable();
    let intervals: Vec<f64> = sorted
        .windows(2)
        .map(|w| (w[1] - w[0]) as f64 / 1e9)
        .collect();
    if intervals.is_empty() {
        return None;
    }
    let n = intervals.len() as f64;
    let mean_s = intervals.iter().sum::<f64>() / n;
    let variance = intervals.iter().map(|i| (i - mean_s).powi(2)).sum::<f64>() / n;
    Some(Rate {
        samples: stamps_ns.len(),
        hz: if mean_s > 0.0 {
            1.0 / mean_s
        } else {
            f64::INFINITY
        },
        mean_s,
        min_s: intervals.iter().copied().fold(f64::INFINITY, f64::min),
        max_s: intervals.iter().copied().fold(0.0, f64::max),
        jitter_s: variance.sqrt(),
    })
}

impl std::fmt::Display for Rate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ms = |s: f64| s * 1e3;
        write!(
            f,
            "rate {:.3} Hz over {} samples: interval mean {:.3} ms, min {:.3} ms, max {:.3} ms, jitter {:.3} ms",
            self.hz,
            self.samples,
            ms(self.mean_s),
            ms(self.min_s),
            ms(self.max_s),
            ms(self.jitter_s)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_stream_has_its_rate_and_no_jitter() {
        let stamps: Vec<u64> = (0..11).map(|i| 1_000 + i * 20_000_000).collect();
        let r = rate(&stamps).unwrap();
        assert_eq!(r.samples, 11);
        assert!((r.hz - 50.0).abs() < 1e-9, "{r:?}");
        assert_eq!((r.min_s, r.max_s), (0.02, 0.02));
        assert!(r.jitter_s < 1e-12, "{r:?}");
        assert_eq!(
            r.to_string(),
            "rate 50.000 Hz over 11 samples: interval mean 20.000 ms, min 20.000 ms, max 20.000 ms, jitter 0.000 ms"
        );
    }

    #[test]
    fn uneven_intervals_show_as_extremes_and_jitter() {
        // Intervals 10 ms and 30 ms alternating: mean 20 ms, deviation 10 ms.
        let stamps = [0, 10_000_000, 40_000_000, 50_000_000, 80_000_000];
        let r = rate(&stamps).unwrap();
        assert!(
            (r.mean_s - 0.02).abs() < 1e-12 && (r.jitter_s - 0.01).abs() < 1e-12,
            "{r:?}"
        );
        assert_eq!((r.min_s, r.max_s), (0.01, 0.03));
    }

    #[test]
    fn too_few_samples_give_nothing() {
        assert_eq!(rate(&[]), None);
        assert_eq!(rate(&[5]), None);
    }

    #[test]
    fn batches_arriving_out_of_stamp_order_count_every_item() {
        // Batches of 5 every 10 ms, the first item of each stamped 450 ns after the rest.
        let stamps: Vec<u64> = (0..20u64)
            .flat_map(|b| {
                let t = b * 10_000_000;
                [t + 450, t, t, t, t]
            })
            .collect();
        let r = rate(&stamps).unwrap();
        // 100 items over 190 ms + 450 ns: 99 intervals, 521 Hz (it said 4 items per batch).
        assert!((r.hz - 99.0 / 0.190_000_45).abs() < 1e-6, "{r:?}");
        assert_eq!(r.min_s, 0.0);
    }
}
