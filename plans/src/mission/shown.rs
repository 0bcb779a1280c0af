//! What a mission shows of its plan (`out/marking`, `out/running`, the labels in
//! `out/firings`), built once per marking rather than at every step.
//!
//! Why: a mission reacting to a request fires a few transitions and publishes what it left;
//! building the texts anew each time (a string per marked place and per running action,
//! then joined) cost as much as the plan step. Plans come back to the same markings (a loop,
//! a waiting place), so the texts are kept by marking.

use std::sync::Arc;

use crate::exec::PlanState;
use crate::model::{Plan, Transition};

/// Markings whose texts are kept; past this the memo starts over (a plan visiting many
/// markings pays what it paid before, no memory grows without bound).
const MAX_TEXTS: usize = 256;

/// The texts of one marking, shared: `out/firings` items hold them without a copy.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(super) struct Texts {
    /// Marked places, `label` or `label*n`, comma-separated (`out/marking`).
    pub marking: Arc<str>,
    /// Running actions, comma-separated (`out/running`).
    pub running: Arc<str>,
}

/// Transition labels and the texts of the markings seen, for one plan.
#[derive(Debug, Default)]
pub(super) struct Shown {
    labels: Vec<Arc<str>>,
    texts: foldhash::HashMap<Vec<u32>, Texts>,
    /// The marking key whose texts were published last (its buffer reused).
    published: Option<Vec<u32>>,
}

/// What a step has to publish (see [`Shown::news`]).
pub(super) struct News {
    /// The texts of the marking the step left (shared with the memo).
    pub texts: Texts,
    /// The marking text differs from the one published last (or none was).
    pub marking: bool,
    /// So does the running text.
    pub running: bool,
}

impl Shown {
    /// The labels of `plan`'s transitions, computed once.
    pub fn new(plan: &Plan) -> Shown {
        Shown {
            labels: plan.transitions().iter().map(|t| shown(t).into()).collect(),
            texts: foldhash::HashMap::default(),
            published: None,
        }
    }

    /// Transition `t` as the log and `out/firings` show it.
    pub fn label(&self, t: usize) -> &Arc<str> {
        &self.labels[t]
    }

    /// Transitions `fired` as the log and `out/firings` show them (shared, not copied).
    pub fn labels(&self, fired: &[usize]) -> Vec<Arc<str>> {
        fired.iter().map(|&t| self.labels[t].clone()).collect()
    }

    /// The texts of `state` (marking key `key`), and which of them changed since the last
    /// call: the mission writes only those, without reading back what it wrote (a write wakes
    /// every reader; a read and compare per output cost as much as the write).
    pub fn news(&mut self, plan: &Plan, state: &PlanState, key: &[u32]) -> News {
        self.texts(plan, state, key);
        let mut published = self.published.take().unwrap_or_default();
        let texts = &self.texts[key];
        // The texts published last, if still kept (the memo may have started over).
        let (marking, running) = match self.texts.get(&published) {
            _ if published == key => (false, false),
            Some(last) => (true, last.running != texts.running),
            None => (true, true),
        };
        published.clear();
        published.extend_from_slice(key);
        self.published = Some(published);
        News {
            texts: texts.clone(),
            marking,
            running,
        }
    }

    /// The texts of `state`, whose marking key ([`PlanState::save`]) is `key`.
    pub fn texts(&mut self, plan: &Plan, state: &PlanState, key: &[u32]) -> &Texts {
        if !self.texts.contains_key(key) {
            if self.texts.len() >= MAX_TEXTS {
                self.texts.clear();
            }
            let texts = Texts {
                marking: marking(plan, state).into(),
                running: state.running_actions(plan).join(", ").into(),
            };
            self.texts.insert(key.to_vec(), texts);
        }
        &self.texts[key]
    }
}

/// A transition as the log shows it: its label, or its id when it has none (a jump).
pub(super) fn shown(t: &Transition) -> String {
    match t.label.trim() {
        "" => t.id.clone(),
        label => label.to_string(),
    }
}

/// Marked places, `label` or `label*n`, comma-separated.
pub(super) fn marking(plan: &Plan, state: &PlanState) -> String {
    let places = plan.places();
    let shown: Vec<String> = state
        .marked()
        .map(|(p, n)| {
            let l = if places[p].label.is_empty() {
                &places[p].id
            } else {
                &places[p].label
            };
            if n == 1 {
                l.clone()
            } else {
                format!("{l}*{n}")
            }
        })
        .collect();
    shown.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(text: &str) -> Plan {
        crate::compile_text(text, "p.plan", "p", None).unwrap()
    }

    #[test]
    fn texts_are_those_of_the_marking_asked_for_and_kept_per_marking() {
        let plan = plan("a; b\n");
        let mut shown = Shown::new(&plan);
        let state = PlanState::new(&plan);
        let key = state.save();
        let first = shown.texts(&plan, &state, &key).clone();
        assert_eq!(*first.marking, marking(&plan, &state));
        assert_eq!(*first.running, state.running_actions(&plan).join(", "));
        // A second state of another marking gets its own texts.
        let mut other = state.clone();
        let last = plan.places().len() as u32 - 1;
        other.restore(&plan, &[1, last, 2]).unwrap();
        let second = shown.texts(&plan, &other, &other.save()).clone();
        assert_ne!(second.marking, first.marking);
        assert!(second.marking.ends_with("*2"), "{}", second.marking);
        assert_eq!(shown.texts(&plan, &state, &key), &first);
    }

    #[test]
    fn news_names_only_the_texts_that_changed_since_the_last_call() {
        let plan = plan("a; b\n");
        let mut shown = Shown::new(&plan);
        let state = PlanState::new(&plan);
        let key = state.save();
        let first = shown.news(&plan, &state, &key);
        assert!(first.marking && first.running, "nothing was published yet");
        let again = shown.news(&plan, &state, &key);
        assert!(!again.marking && !again.running, "same marking");
        // Another marking with no action running: the running text stays empty.
        let mut other = state.clone();
        let last = plan.places().len() as u32 - 1;
        other.restore(&plan, &[1, last, 1]).unwrap();
        let next = shown.news(&plan, &other, &other.save());
        assert!(next.marking && !next.running, "{:?}", next.texts);
        assert_eq!(*next.texts.marking, marking(&plan, &other));
    }

    #[test]
    fn the_memo_starts_over_when_full() {
        let plan = plan("a; b\n");
        let mut shown = Shown::new(&plan);
        let state = PlanState::new(&plan);
        for n in 1..=(MAX_TEXTS as u32 + 10) {
            // Not real markings of the plan: only the keys matter to the memo.
            shown.texts(&plan, &state, &[1, 0, n]);
        }
        assert!(shown.texts.len() <= MAX_TEXTS);
    }
}
