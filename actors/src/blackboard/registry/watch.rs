//! Tap watches: a recorder taps the properties it wants, those there now and those declared
//! later (modules added while running, runtime statistics), each before anything can write it.

use std::collections::HashSet;

use tokio::sync::mpsc;

use super::{Handle, Registry};
use crate::team::Tap;

/// A tap a watch made on a property: its `module/path` key and the tap.
pub struct WatchedTap {
    /// `module/path`.
    pub key: String,
    /// The tap, made when the property was declared (or when the watch began).
    pub tap: Tap,
}

/// Which properties a watch wants, by `module/path` key.
pub type TapFilter = Box<dyn Fn(&str) -> bool + Send>;

pub(crate) struct TapWatch {
    wants: TapFilter,
    tx: mpsc::UnboundedSender<WatchedTap>,
    /// The keys already considered (tapped or not wanted); always a subset of the entries.
    seen: HashSet<String>,
}

impl Registry {
    /// Starts a watch: taps what `wants` now, and from then on what is declared.
    pub(crate) fn watch_taps(&mut self, wants: TapFilter) -> mpsc::UnboundedReceiver<WatchedTap> {
        let (tx, rx) = mpsc::unbounded_channel();
        self.tap_watches.push(TapWatch {
            wants,
            tx,
            seen: HashSet::new(),
        });
        self.announce_taps();
        rx
    }

    /// Taps, for each watch, the properties declared since it last looked. The blackboard
    /// runs it after every structure change, before answering, so a module added while
    /// running is tapped before the supervisor starts it. Cheap when nothing was declared:
    /// entries are only ever added or removed, one request at a time, so an unchanged count
    /// means nothing new.
    pub(crate) fn announce_taps(&mut self) {
        let mut watches = std::mem::take(&mut self.tap_watches);
        watches.retain_mut(|w| {
            if w.seen.len() == self.entries.len() {
                return !w.tx.is_closed();
            }
            // A removed module's keys may come back as new properties under the same name.
            w.seen.retain(|k| self.entries.contains_key(k));
            for (key, entry) in &self.entries {
                if !w.seen.insert(key.clone()) {
                    continue;
                }
                let own_data = match entry.handle {
                    Handle::Value(_) => self.link_of(key).is_none(),
                    Handle::QueueOut(_) => true,
                    // Recorded at their source (the items of the queue they read).
                    Handle::QueueIn(_) => false,
                };
                if !own_data || !(w.wants)(key) {
                    continue;
                }
                let Ok(tap) = self.tap(key) else { continue };
                let tap = WatchedTap {
                    key: key.clone(),
                    tap,
                };
                if w.tx.send(tap).is_err() {
                    return false;
                }
            }
            true
        });
        self.tap_watches = watches;
    }
}
