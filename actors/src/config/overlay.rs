//! Overlays: a config (e.g. a snapshot) applied on top of another.

use super::ConfigFile;

impl ConfigFile {
    /// Applies `overlay` (e.g. a snapshot) on top: every field it writes replaces this
    /// config's (`supervision`, `groups`, `contexts`, `team`, `name`, `scheduler`, `step_budget`,
    /// `realtime_priority`, `long_steps_nice`, `clock_s`; per module
    /// `type` if given, `group`, `restart`, `watchdog_ms`, `shutdown_timeout_ms`, `long_steps`), while modules match by name
    /// and their `values`, `links` and `capacities` are merged key by key (a value the overlay
    /// gives replaces the base's link of that property, a link it gives the base's value);
    /// modules only it has are appended.
    pub fn overlay(&mut self, overlay: ConfigFile) {
        let source = self.sources.len();
        let wrote = |field: &str| overlay.written.contains(field);
        if overlay.config.team.is_some() {
            self.config.team = overlay.config.team.clone();
        }
        if overlay.config.record.is_some() {
            self.config.record = overlay.config.record.clone();
        }
        if wrote("supervision") {
            self.config.supervision = overlay.config.supervision.clone();
        }
        if wrote("groups") {
            self.config.groups = overlay.config.groups.clone();
        }
        if wrote("contexts") {
            self.config.contexts = overlay.config.contexts.clone();
        }
        if wrote("scheduler") {
            self.config.scheduler = overlay.config.scheduler;
        }
        if wrote("step_budget") {
            self.config.step_budget = overlay.config.step_budget;
        }
        if wrote("realtime_priority") {
            self.config.realtime_priority = overlay.config.realtime_priority;
        }
        if wrote("long_steps_nice") {
            self.config.long_steps_nice = overlay.config.long_steps_nice;
        }
        if wrote("clock_s") {
            self.config.clock_s = overlay.config.clock_s;
        }
        if wrote("name") && !overlay.config.name.is_empty() {
            self.config.name = overlay.config.name.clone();
        }
        for m in &overlay.config.modules {
            for key in m.values.keys() {
                self.value_sources
                    .insert((m.name.clone(), key.clone()), source);
            }
        }
        for m in overlay.config.modules {
            match self.config.modules.iter_mut().find(|b| b.name == m.name) {
                Some(base) => {
                    let wrote =
                        |field: &str| overlay.written.contains(&format!("{}/{field}", m.name));
                    // Left out: the base config's type stays.
                    if !m.type_name.is_empty() {
                        base.type_name = m.type_name;
                    }
                    if wrote("group") {
                        base.group = m.group;
                    }
                    if wrote("restart") {
                        base.restart = m.restart;
                    }
                    if wrote("watchdog_ms") {
                        base.watchdog_ms = m.watchdog_ms;
                    }
                    if wrote("shutdown_timeout_ms") {
                        base.shutdown_timeout_ms = m.shutdown_timeout_ms;
                    }
                    if wrote("long_steps") {
                        base.long_steps = m.long_steps;
                    }
                    // An input the overlay gives a value is no longer linked, and one it
                    // links has no value: its word is the last (a snapshot taken after
                    // `petrel unlink` holds the value of an input the base config linked).
                    for key in m.values.keys().filter(|k| !m.links.contains_key(*k)) {
                        base.links.remove(key);
                    }
                    for key in m.links.keys().filter(|k| !m.values.contains_key(*k)) {
                        base.values.remove(key);
                    }
                    base.values.extend(m.values);
                    base.links.extend(m.links);
                    base.capacities.extend(m.capacities);
                }
                None => self.config.modules.push(m),
            }
        }
        self.sources.extend(overlay.sources);
        self.written.extend(overlay.written);
    }
}
