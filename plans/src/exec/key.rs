//! A plan's state as a compact list of numbers: saved and restored by a mission across
//! restarts, and the analysis' key for a visited state.

use std::collections::HashSet;

use super::step::has_tokens;
use super::{PlanState, Scratch};
use crate::model::Plan;

/// A state saved and restored (a mission module keeps its plan's marking across restarts).
impl PlanState {
    /// The marking as a compact list of numbers (sub-plans included), for
    /// [`restore`](PlanState::restore).
    pub fn save(&self) -> Vec<u32> {
        let mut key = Vec::new();
        self.encode(&mut key);
        key
    }

    /// Like [`save`](PlanState::save), appending to `out` (a caller that saves often reuses
    /// one buffer).
    pub fn save_into(&self, out: &mut Vec<u32>) {
        self.encode(out);
    }

    /// Sets the marking saved by [`save`](PlanState::save) from a state of the same plan.
    /// A list that does not fit the plan (another plan, an edited snapshot) is refused and
    /// the state left unchanged.
    pub fn restore(&mut self, plan: &Plan, saved: &[u32]) -> Result<(), String> {
        match fits(plan, saved) {
            Some(used) if used == saved.len() => {
                self.decode(saved);
                Ok(())
            }
            _ => Err(format!(
                "the saved marking does not fit plan `{}` (was the plan changed?)",
                plan.name()
            )),
        }
    }
}

/// How many words of `key` a state of `plan` takes, if they are a valid key for it.
fn fits(plan: &Plan, key: &[u32]) -> Option<usize> {
    let n = (*key.first()? & !FAILED_BIT) as usize;
    let pairs = key.get(1..1 + 2 * n)?;
    if pairs
        .chunks_exact(2)
        .any(|p| p[0] as usize >= plan.places().len() || p[1] == 0)
    {
        return None;
    }
    let mut used = 1 + 2 * n;
    for e in plan.executables() {
        if let Some(sp) = &e.subplan {
            used += fits(sp, key.get(used..)?)?;
        }
    }
    Some(used)
}

/// The analysis' view of a state: its marking as a compact key, and back.
impl PlanState {
    /// Appends the marking: the number of marked places, then `place, tokens` for each in
    /// place order, then each sub-plan's own key in executable order. Equal states give equal
    /// keys, and a key costs what is marked, not the net size.
    pub(crate) fn encode(&self, out: &mut Vec<u32>) {
        // An unhandled failure sets the top bit of the count, so it never matches a running key.
        let failed = if self.failed.is_some() { FAILED_BIT } else { 0 };
        out.push(self.marked.len() as u32 | failed);
        for &p in &self.marked {
            out.extend([p, self.tokens[p as usize]]);
        }
        for &e in &self.sub_execs {
            if let Some(sub) = &self.subs[e] {
                sub.encode(out);
            }
        }
    }

    /// Sets the marking to `key` (from [`PlanState::encode`] on a state of the same plan),
    /// touching only the places marked before and after; returns what follows the key.
    pub(crate) fn decode<'k>(&mut self, key: &'k [u32]) -> &'k [u32] {
        for &p in &self.marked {
            self.tokens[p as usize] = 0;
        }
        self.marked.clear();
        // Which executable failed does not matter to the analysis, only that one did.
        self.failed = (key[0] & FAILED_BIT != 0).then_some(0);
        let n = (key[0] & !FAILED_BIT) as usize;
        for pair in key[1..1 + 2 * n].chunks_exact(2) {
            self.tokens[pair[0] as usize] = pair[1];
            self.marked.push(pair[0]);
        }
        // Keys list places in order (`encode`); one from elsewhere may not.
        if !self.marked.is_sorted() {
            self.marked.sort_unstable();
            self.marked.dedup();
        }
        let mut rest = &key[1 + 2 * n..];
        for &e in &self.sub_execs {
            if let Some(sub) = &mut self.subs[e] {
                rest = sub.decode(rest);
            }
        }
        rest
    }

    /// Stops looking for unhandled failures, here and in sub-plans (see `ignore_unhandled`).
    pub(crate) fn for_analysis(mut self) -> Self {
        self.ignore_unhandled = true;
        for sub in self.subs.iter_mut().flatten() {
            let s = std::mem::replace(sub.as_mut(), PlanState::empty());
            **sub = s.for_analysis();
        }
        self
    }

    fn empty() -> PlanState {
        PlanState {
            tokens: Vec::new(),
            marked: Vec::new(),
            subs: Vec::new(),
            sub_execs: Vec::new(),
            failed: None,
            ignore_unhandled: false,
            reported: HashSet::new(),
            scratch: Scratch::default(),
        }
    }

    /// Whether some transition has the tokens it needs (guards aside).
    pub(crate) fn token_enabled(&self, plan: &Plan) -> bool {
        let hot = plan.hot();
        self.marked.iter().any(|&p| {
            plan.output_transitions(p as usize)
                .iter()
                .any(|&t| has_tokens(self, hot.trans[t as usize].inputs(&hot.arcs)))
        })
    }
}

/// Set in the first word of a key ([`PlanState::encode`]) when an unhandled failure failed the plan.
pub(crate) const FAILED_BIT: u32 = 1 << 31;
