//! `PublishGate`: how often a module publishes a value it keeps changing (a mapper's map).
//!
//! SLAM mappers publish their grid at a rate of their own, not with every scan: a grid is the
//! largest value a robot writes, and its readers (a planner, a recording, a console) need it
//! far less often than it changes. The gate counts the data it was given (scans), never the
//! clock, so it means the same at any simulation speed and a replay publishes the same maps,
//! at any rate, as the run it replays.

/// Publishes a changed value at most once per `every` inputs (scans); 1 publishes every change.
#[derive(Debug, Clone)]
pub struct PublishGate {
    every: u32,
    /// Inputs taken since the last publication; `every` before the first, so the first change
    /// is published at once.
    since: u32,
    pending: bool,
}

impl PublishGate {
    /// A gate publishing at most once per `every` inputs (0 is taken as 1: every change).
    pub fn new(every: u32) -> Self {
        let every = every.max(1);
        PublishGate {
            every,
            since: every,
            pending: false,
        }
    }

    /// Notes `inputs` more inputs taken, and whether they changed the value; answers whether
    /// to publish now. The first change is published at once; later ones once `every` inputs
    /// were taken since the last publication, even if the last of them changed nothing.
    pub fn update(&mut self, inputs: u32, changed: bool) -> bool {
        self.since = self.since.saturating_add(inputs);
        self.pending |= changed;
        if self.pending && self.since >= self.every {
            self.published();
            return true;
        }
        false
    }

    /// Whether a change waits to be published (what a module publishes when it stops).
    pub fn pending(&self) -> bool {
        self.pending
    }

    /// Notes a publication (also one made outside `update`, when stopping).
    pub fn published(&mut self) {
        self.pending = false;
        self.since = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_one_publishes_every_change_and_nothing_else() {
        let mut gate = PublishGate::new(1);
        assert!(gate.update(1, true));
        assert!(gate.update(1, true));
        assert!(!gate.update(1, false));
        assert!(gate.update(3, true));
        assert_eq!(PublishGate::new(0).every, 1);
    }

    #[test]
    fn changes_wait_until_enough_inputs_were_taken() {
        let mut gate = PublishGate::new(10);
        assert!(
            gate.update(1, true),
            "the first change is published at once"
        );
        assert!(!gate.update(4, true));
        assert!(!gate.update(5, false), "nine inputs so far");
        assert!(gate.pending());
        // Published with an input that changed nothing: the change before is not lost.
        assert!(gate.update(1, false));
        assert!(!gate.pending());
        assert!(!gate.update(30, false), "nothing changed since");
        assert!(
            gate.update(1, true),
            "ten inputs have passed since the last one"
        );
    }

    #[test]
    fn a_publication_when_stopping_empties_the_gate() {
        let mut gate = PublishGate::new(10);
        assert!(gate.update(1, true));
        assert!(!gate.update(1, true));
        gate.published();
        assert!(!gate.pending());
        assert!(!gate.update(9, false));
    }
}
