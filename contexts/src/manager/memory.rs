//! What a context manager keeps in `state/memory`, so that a restarted manager (a crash, a
//! restart on request, a move off the agent's thread) goes on where its predecessor was: the
//! active contexts and what they applied, and what was there before, to put back when they
//! end. Without it a restarted manager forgot that it had changed anything: a context that
//! ended meanwhile left its values in place, and one still active saved its own values as the
//! originals.

use std::sync::Arc;

use petrel_actors::{Context, FilePath, PropertyType};
use serde::{Deserialize, Serialize};

use super::ContextManager;
use crate::engine::{fill_in_place, same_name, EngineMemory};

/// `state/memory` of a `context.manager`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ContextMemory {
    /// The rules file this memory is about (`params/rules`).
    pub rules: FilePath,
    /// The contexts switched on and the effects applied.
    pub engine: EngineMemory,
    /// Properties the contexts set, with their value from before (config form).
    pub original_values: Vec<(Arc<str>, ron::Value)>,
    /// Inputs the contexts relinked, with their link from before (none: unlinked).
    pub original_links: Vec<(Arc<str>, Option<String>)>,
    /// Modules the contexts started or stopped, with whether they ran before.
    pub original_runs: Vec<(Arc<str>, bool)>,
}

impl PropertyType for ContextMemory {
    const TYPE_NAME: &'static str = "context.memory";
}

impl ContextManager {
    /// Saves what the engine switched and applied and the originals. Called after a step
    /// whose engine gave actions, each of which changes what is switched or applied, so the
    /// memory changed: it is not compared with the one published. Two buffers in turn, like
    /// the mission's memory: the one published two saves ago is filled in place once no
    /// reader holds it.
    pub(super) fn save_memory(&mut self) {
        let mut next = self.spare.take().unwrap_or_default();
        self.show_originals();
        // Copied first only if a reader (a tool, a recorder's tap) still holds it.
        self.fill(Arc::make_mut(&mut next));
        self.spare = Some(self.memory.swap(next));
    }

    fn fill(&self, memory: &mut ContextMemory) {
        let rules = self.rules.get();
        // The same text is the same path (comparing paths walks their components).
        if memory.rules.as_path().as_os_str() != rules.as_path().as_os_str() {
            memory.rules = (*rules).clone();
        }
        if let Some(engine) = &self.engine {
            engine.save_into(&mut memory.engine);
        }
        // What the contexts changed, in address order; one whose config form could not be
        // made (see `show_originals`) is left out.
        fill_named(&mut memory.original_values, self.targets.shown());
        fill_named(&mut memory.original_links, &self.original_links);
        fill_named(&mut memory.original_runs, &self.original_runs);
    }

    /// Brings the config form of each original up to date: converting a value (through RON
    /// text) costs more than the rest of a save, and an original that a context puts back
    /// and takes again is the same value.
    fn show_originals(&mut self) {
        let handles = &self.handles;
        self.targets.show(|target, value| {
            let handle = handles.get(target)?;
            handle.type_info().to_dynamic(value).ok()
        });
    }

    /// Goes on from `state/memory` if it is about the same rules file: the engine takes over
    /// the switches and effects, and the originals come back to be restored when their
    /// contexts end. Targets the rules no longer mention are looked up so they can be.
    pub(super) async fn resume_memory(&mut self, ctx: &Context) {
        let memory = self.memory.get();
        let rules = self.rules.get();
        if *memory == ContextMemory::default() {
            return;
        }
        if memory.rules != *rules {
            // What the other rules changed stays as they left it: say so, for a person to see.
            tracing::warn!(
                kept = %memory.rules,
                rules = %rules,
                "state/memory is of another rules file: not used; values its contexts set stay as they are"
            );
            return;
        }
        for (target, value) in &memory.original_values {
            if !self.handles.contains_key(target) {
                if let Ok(handle) = ctx.blackboard().expr_handle(target).await {
                    self.handles.insert(target.clone(), handle);
                }
            }
            let restored = self
                .handles
                .get(target)
                .map(|h| h.type_info().from_ron(value.clone()));
            match restored {
                Some(Ok(value)) => {
                    self.targets.entry(target).original = Some(value);
                }
                _ => {
                    tracing::warn!(%target, "state/memory: the value from before the context cannot be restored here")
                }
            }
        }
        self.original_links
            .extend(memory.original_links.iter().cloned());
        self.original_runs
            .extend(memory.original_runs.iter().cloned());
        if let Some(engine) = self.engine.as_mut() {
            engine.resume(&memory.engine);
        }
        let active: Vec<&str> = memory.engine.active.iter().map(|(c, _)| &**c).collect();
        tracing::info!(?active, "context manager resumed from state/memory");
    }
}

/// Makes `out` list `items` (name, value), keeping the entries it already holds alike.
fn fill_named<'a, V: Clone + PartialEq + 'a>(
    out: &mut Vec<(Arc<str>, V)>,
    items: impl IntoIterator<Item = (&'a Arc<str>, &'a V)>,
) {
    fill_in_place(
        out,
        items,
        |(name, value), (item, v)| same_name(name, item) && value == *v,
        |_, _| {},
        |(item, v)| (item.clone(), v.clone()),
    );
}
