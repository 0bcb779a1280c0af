//! Which watched properties to push now: each at most once per its interval (10 Hz for
//! values, slower for bulky ones), and only when its version moved since it was last sent.
//! Time is passed in, so this is tested without a clock.

use std::time::{Duration, Instant};

/// The fastest a property is pushed: 10 times a second.
pub const VALUE_INTERVAL: Duration = Duration::from_millis(100);
/// Bulky values (grids, images, scans) are pushed at most twice a second.
pub const BULKY_INTERVAL: Duration = Duration::from_millis(500);

/// Types whose values are large: pushed less often, and as a summary only.
pub fn is_bulky(type_name: &str) -> bool {
    matches!(type_name, "OccupancyGrid" | "Image" | "LaserScan" | "Path2")
}

/// The push interval of a property of `type_name`.
pub fn interval_of(type_name: &str) -> Duration {
    match is_bulky(type_name) {
        true => BULKY_INTERVAL,
        false => VALUE_INTERVAL,
    }
}

#[derive(Debug, Clone)]
struct Slot {
    interval: Duration,
    /// The version last pushed (`None`: never pushed).
    sent: Option<u64>,
    sent_at: Option<Instant>,
}

/// Per-property push state of one WebSocket client.
#[derive(Debug, Clone, Default)]
pub struct Throttle {
    slots: Vec<Slot>,
}

impl Throttle {
    /// Adds a property pushed at most once per `interval`; returns its index.
    pub fn add(&mut self, interval: Duration) -> usize {
        self.slots.push(Slot {
            interval,
            sent: None,
            sent_at: None,
        });
        self.slots.len() - 1
    }

    /// Number of properties watched.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether nothing is watched.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Whether property `index`, now at `version`, is to be pushed at `now`; if so, it counts
    /// as pushed. A change inside the interval waits: it is pushed (its newest version) at
    /// the first call after the interval, so the last value always arrives.
    pub fn due(&mut self, index: usize, version: u64, now: Instant) -> bool {
        let slot = &mut self.slots[index];
        if slot.sent == Some(version) {
            return false;
        }
        if let Some(at) = slot.sent_at {
            if now.saturating_duration_since(at) < slot.interval {
                return false;
            }
        }
        slot.sent = Some(version);
        slot.sent_at = Some(now);
        true
    }

    /// When the next push could be due: the soonest end of an interval among properties that
    /// were pushed (a caller sleeps until then or until something changes).
    pub fn next_check(&self, now: Instant) -> Instant {
        self.slots
            .iter()
            .filter_map(|s| s.sent_at.map(|at| at + s.interval))
            .filter(|t| *t > now)
            .min()
            .unwrap_or(now + VALUE_INTERVAL)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_property_is_pushed_once_per_version_and_at_most_once_per_interval() {
        let t0 = Instant::now();
        let mut throttle = Throttle::default();
        let p = throttle.add(VALUE_INTERVAL);
        assert!(throttle.due(p, 1, t0), "the first value goes at once");
        assert!(
            !throttle.due(p, 1, t0 + Duration::from_secs(5)),
            "unchanged: not again"
        );
        let t1 = t0 + Duration::from_secs(5);
        assert!(throttle.due(p, 2, t1));
        // Changes 20 ms apart: held back until the interval has passed.
        for (i, ms) in [20, 40, 60, 80].into_iter().enumerate() {
            assert!(!throttle.due(p, 3 + i as u64, t1 + Duration::from_millis(ms)));
        }
        assert!(
            throttle.due(p, 6, t1 + Duration::from_millis(100)),
            "the newest, after 100 ms"
        );
    }

    #[test]
    fn a_property_written_at_1_khz_is_pushed_at_10_hz() {
        let t0 = Instant::now();
        let mut throttle = Throttle::default();
        let p = throttle.add(VALUE_INTERVAL);
        let pushed = (0..1000u64)
            .filter(|ms| throttle.due(p, ms + 1, t0 + Duration::from_millis(*ms)))
            .count();
        assert_eq!(pushed, 10);
    }

    #[test]
    fn bulky_types_go_slower_and_the_next_check_is_the_soonest_interval_end() {
        assert_eq!(interval_of("OccupancyGrid"), BULKY_INTERVAL);
        assert_eq!(interval_of("f64"), VALUE_INTERVAL);
        let t0 = Instant::now();
        let mut throttle = Throttle::default();
        let grid = throttle.add(BULKY_INTERVAL);
        let value = throttle.add(VALUE_INTERVAL);
        assert!(throttle.due(grid, 1, t0));
        assert_eq!(throttle.next_check(t0), t0 + BULKY_INTERVAL);
        assert!(throttle.due(value, 1, t0));
        assert_eq!(throttle.next_check(t0), t0 + VALUE_INTERVAL);
    }
}
