//! A periodic module's ticks: the fine timer or tokio's interval.

use std::time::Duration;

use tokio::time::{Instant, MissedTickBehavior};

/// A periodic module's clock: the fine timer where the runtime's clock cannot be paused (a
/// tick within microseconds of its time, not tokio's 1 ms slots), else tokio's, which a paused
/// test clock drives.
pub(super) enum Ticker {
    Fine(crate::fine_timer::FineTicker),
    Tokio(tokio::time::Interval),
}

impl Ticker {
    /// Ticks every `period` from now, on the clock that fits this runtime; missed ticks are
    /// skipped on the start's grid.
    pub(super) fn new(period: Duration) -> Ticker {
        match crate::fine_timer::fine_clock_here() {
            true => Ticker::Fine(crate::fine_timer::FineTicker::new(period)),
            false => {
                let mut t = tokio::time::interval_at(Instant::now() + period, period);
                t.set_missed_tick_behavior(MissedTickBehavior::Skip);
                Ticker::Tokio(t)
            }
        }
    }
}

/// The next tick of `ticker`; never, for a module without a period.
pub(super) async fn tick(ticker: &mut Option<Ticker>) {
    match ticker {
        Some(Ticker::Fine(t)) => t.tick().await,
        Some(Ticker::Tokio(t)) => {
            t.tick().await;
        }
        None => std::future::pending().await,
    }
}
