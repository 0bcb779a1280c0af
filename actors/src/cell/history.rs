//! Every write of a value property, kept for a consumer that must see each one (a recorder),
//! not only the latest a later read would find.

use std::collections::VecDeque;

use parking_lot::Mutex;
use tokio::time::Instant;

use crate::value::AnyValue;

/// One kept write: the value, its version and its write time.
pub(crate) type Write = (AnyValue, u64, Instant);

/// The writes of the cells a [`Signal`](super::Signal) watches, oldest first, at most
/// `capacity` of them not yet taken; older ones are dropped and counted.
pub(crate) struct History {
    kept: Mutex<Kept>,
    capacity: usize,
}

#[derive(Default)]
struct Kept {
    writes: VecDeque<Write>,
    lost: u64,
}

impl History {
    pub fn new(capacity: usize) -> Self {
        History {
            kept: Mutex::default(),
            capacity: capacity.max(1),
        }
    }

    /// Keeps a write (called under the cell's lock, so writes are kept in version order).
    pub fn push(&self, value: &AnyValue, version: u64, written: Instant) {
        let mut kept = self.kept.lock();
        if kept.writes.len() == self.capacity {
            kept.writes.pop_front();
            kept.lost += 1;
        }
        kept.writes.push_back((value.clone(), version, written));
    }

    /// Moves the kept writes into `out` (oldest first); returns how many were lost so far.
    pub fn take(&self, out: &mut Vec<Write>) -> u64 {
        let mut kept = self.kept.lock();
        out.extend(kept.writes.drain(..));
        kept.lost
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;

    #[test]
    fn keeps_writes_in_order_and_counts_what_it_had_to_drop() {
        let history = History::new(3);
        let at = Instant::now();
        for v in 1..=5_i64 {
            history.push(&(Arc::new(v) as AnyValue), v as u64, at);
        }
        let mut out = Vec::new();
        assert_eq!(history.take(&mut out), 2, "the two oldest");
        let versions: Vec<u64> = out.iter().map(|w| w.1).collect();
        assert_eq!(versions, [3, 4, 5]);
        out.clear();
        assert_eq!(history.take(&mut out), 2);
        assert!(out.is_empty());
    }
}
