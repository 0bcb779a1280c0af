//! Which modules are inside a step, readable from any thread.
//!
//! A module whose step loops on the CPU or blocks in a read holds its worker thread, and with
//! every worker held the async runtime can neither stop it nor say so. A watchdog on its own
//! thread reads these marks instead, to name the modules a stop is waiting for before it ends
//! the process.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// One module instance's step counter: odd while a step runs.
#[derive(Debug, Default)]
pub(crate) struct StepMark(AtomicU64);

impl StepMark {
    /// Marks a step as running until the returned guard is dropped (the step returned, failed,
    /// or its future was dropped by a kill).
    pub fn enter(&self) -> InStep<'_> {
        self.0.fetch_add(1, Ordering::Relaxed);
        InStep(self)
    }
}

/// A running step; see [`StepMark::enter`].
pub(crate) struct InStep<'a>(&'a StepMark);

impl Drop for InStep<'_> {
    fn drop(&mut self) {
        (self.0).0.fetch_add(1, Ordering::Relaxed);
    }
}

/// Each module's name and the mark of its current instance.
type Marks = Vec<(String, Arc<StepMark>)>;

/// The step marks of one agent's modules, shared with a watchdog outside the runtime.
#[derive(Debug, Clone, Default)]
pub struct StepProbe {
    marks: Arc<parking_lot::Mutex<Marks>>,
}

/// What a [`StepProbe`] saw at one moment: each module's step counter.
#[derive(Debug, Clone, Default)]
pub struct StepSample(Vec<(String, u64)>);

impl StepProbe {
    /// A fresh mark for a new instance of `module`, replacing its predecessor's.
    pub(crate) fn mark(&self, module: &str) -> Arc<StepMark> {
        let mark = Arc::<StepMark>::default();
        let mut marks = self.marks.lock();
        match marks.iter_mut().find(|(name, _)| name == module) {
            Some(entry) => entry.1 = mark.clone(),
            None => marks.push((module.to_string(), mark.clone())),
        }
        mark
    }

    /// Every module's step counter now.
    pub fn sample(&self) -> StepSample {
        StepSample(
            self.marks
                .lock()
                .iter()
                .map(|(name, mark)| (name.clone(), mark.0.load(Ordering::Relaxed)))
                .collect(),
        )
    }

    /// The modules that were inside a step when `earlier` was taken and are still inside that
    /// same step: stuck at least since then.
    pub fn stuck_since(&self, earlier: &StepSample) -> Vec<String> {
        let now = self.sample();
        now.0
            .into_iter()
            .filter(|(name, count)| {
                count % 2 == 1 && earlier.0.iter().any(|(n, c)| n == name && c == count)
            })
            .map(|(name, _)| name)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_only_modules_inside_the_same_step_in_both_samples() {
        let probe = StepProbe::default();
        let stuck = probe.mark("stuck");
        let quick = probe.mark("quick");
        let _idle = probe.mark("idle");
        let _in_step = stuck.enter();
        let quick_step = quick.enter();
        let before = probe.sample();
        drop(quick_step);
        // Another step of `quick` began since: not the same step.
        let _again = quick.enter();
        assert_eq!(probe.stuck_since(&before), vec!["stuck".to_string()]);
    }

    #[test]
    fn a_new_instance_replaces_its_predecessors_mark() {
        let probe = StepProbe::default();
        let old = probe.mark("m");
        let _old_step = old.enter();
        let before = probe.sample();
        let _new = probe.mark("m");
        assert!(probe.stuck_since(&before).is_empty());
    }
}
