//! The shell of [`loop_watch`](crate::loop_watch): saying that a module is in a loop.

use crate::blackboard::Blackboard;
use crate::loop_watch;

/// A loop a module was found in.
pub(super) struct Loop {
    pub hops: u32,
    pub steps: u64,
    /// The longest chain that woke the module ended with its own write.
    pub woken_by_itself: bool,
    /// What the module says makes it wake itself ([`Module::loop_hint`]).
    pub hint: Option<String>,
}

/// Says once (then at most every few seconds) that a module keeps waking itself, naming the
/// links that close the loop. A module only woken by a loop elsewhere (on no link cycle, not
/// by its own writes) says nothing: the modules of the loop report it.
pub(super) async fn report_loop(
    span: &tracing::Span,
    blackboard: &Blackboard,
    module: &str,
    found: Loop,
) {
    let cycle = blackboard.feedback_cycle(module).await.ok().flatten();
    let through = match (cycle, found.woken_by_itself) {
        (Some(links), _) => format!("through {}", links.join(", ")),
        (None, true) => "through a property it both writes and watches".to_string(),
        (None, false) => return,
    };
    let hint = found.hint.map(|h| format!(" ({h})")).unwrap_or_default();
    let Loop { hops, steps, .. } = found;
    span.in_scope(|| {
        tracing::warn!(
            hops,
            steps,
            "module `{module}` re-triggers itself without progress {through}{hint}: {hops} steps in a row, each woken by the last one's writes and none by time or outside input; it runs as fast as the CPU allows (reported at most every {}s)",
            loop_watch::REPORT_EVERY.as_secs()
        )
    });
}
