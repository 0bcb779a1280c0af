//! Module instances added and removed while the agent runs, configured values and links, and
//! the runtime's own `_supervisor/events` queue.

use std::path::PathBuf;
use std::sync::Arc;

use super::{BlackboardError, Entry, ModuleEntry, Registry, EVENTS_CAPACITY};
use crate::config::{describe, ModuleConfig};
use crate::module_types::ModuleType;
use crate::ports::{Handle, PropertyDecl, PropertyKind};
use crate::queue::QueueCore;
use crate::types::FilePath;
use crate::value::TypeInfo;

impl Registry {
    /// Sets the values and queue capacities `m` configures; returns what failed, by config key.
    /// File paths (properties of type [`FilePath`]) that are relative are resolved against
    /// `base_dir(key)`, the directory of the config file that gives the value.
    pub(crate) fn apply_values<'a>(
        &mut self,
        m: &'a ModuleConfig,
        base_dir: &dyn Fn(&str) -> PathBuf,
    ) -> Vec<(&'a str, BlackboardError)> {
        let mut failed = Vec::new();
        for (path, value) in &m.values {
            let address = format!("{}/{path}", m.name);
            let declared = self.get(&address).ok().map(|(ti, _)| ti);
            let value = match (declared, value) {
                (Some(ti), ron::Value::String(s)) if ti.is::<FilePath>() => {
                    let resolved = FilePath::from(s.as_str()).resolved_against(&base_dir(path));
                    ron::Value::String(resolved.to_string())
                }
                _ => value.clone(),
            };
            if let Err(e) = self.set_from_ron(&address, value) {
                failed.push((path.as_str(), e));
            }
        }
        for (path, capacity) in &m.capacities {
            if let Err(e) = self.set_capacity(&format!("{}/{path}", m.name), *capacity) {
                failed.push((path.as_str(), e));
            }
        }
        failed
    }

    /// Creates the links `m` configures; returns what failed, by config key.
    pub(crate) fn apply_links<'a>(
        &mut self,
        m: &'a ModuleConfig,
    ) -> Vec<(&'a str, BlackboardError)> {
        let mut failed = Vec::new();
        for (path, target) in &m.links {
            if let Err(e) = self.link_target(&format!("{}/{path}", m.name), target) {
                failed.push((path.as_str(), e));
            }
        }
        failed
    }

    /// Declares a new module instance while the agent runs, with its values and links; on any
    /// error nothing is added and every problem is returned.
    pub(crate) fn add_module(
        &mut self,
        m: &ModuleConfig,
        module_type: &ModuleType,
    ) -> Result<(), String> {
        if m.name.starts_with('_') {
            return Err(format!(
                "module name `{}`: names starting with `_` are reserved for the runtime",
                m.name
            ));
        }
        self.declare(&m.name, module_type.name(), module_type.declare(&m.name))
            .map_err(|e| e.to_string())?;
        // No config file here: relative file paths are taken from the working directory.
        let mut failed = self.apply_values(m, &|_| PathBuf::from("."));
        failed.extend(self.apply_links(m));
        if failed.is_empty() {
            self.settings.add_module(m);
            return Ok(());
        }
        let errors: Vec<String> = failed
            .into_iter()
            .map(|(path, e)| describe(&m.name, path, e))
            .collect();
        let _ = self.remove_module(&m.name);
        Err(errors.join("; "))
    }

    /// Removes a module instance and its properties; refused while other properties link into it.
    pub(crate) fn remove_module(&mut self, module: &str) -> Result<(), BlackboardError> {
        if !self.order.iter().any(|m| m == module) {
            return Err(self.key_of(&format!("{module}/enabled")).unwrap_err());
        }
        let prefix = format!("{module}/");
        let links = self.links.linked_into(&prefix);
        if !links.is_empty() {
            return Err(BlackboardError::InUse {
                module: module.into(),
                links,
            });
        }
        self.entries.retain(|k, _| !k.starts_with(&prefix));
        self.links.remove_prefix(&prefix);
        self.remote.remove_module(module);
        self.forget_outbox(module);
        self.order.retain(|m| m != module);
        self.remove_module_entry(module);
        self.settings.remove_module(module);
        Ok(())
    }

    /// Declares the runtime's own `_supervisor/events` queue (see [`crate::supervision`]).
    pub(crate) fn declare_events(&mut self) {
        use crate::supervision::{SupervisorEvent, EVENTS_MODULE, EVENTS_PATH};
        let key = format!("{EVENTS_MODULE}/{EVENTS_PATH}");
        let type_info = TypeInfo::of::<SupervisorEvent>();
        let decl = PropertyDecl {
            path: EVENTS_PATH.to_string(),
            kind: PropertyKind::QueueOut,
            type_info,
            default: None,
            doc: "failures, restarts and give-ups of this agent's modules".into(),
            capacity: Some(EVENTS_CAPACITY),
            range: None,
            read_at_start: false,
            shape: None,
        };
        let handle = Handle::QueueOut(QueueCore::new(&key, type_info, EVENTS_CAPACITY));
        self.entries.insert(
            key,
            Entry {
                decl,
                handle,
                remote: None,
                own_queue: None,
            },
        );
        let entry = ModuleEntry {
            type_name: "runtime.supervisor".into(),
            signal: Arc::default(),
        };
        self.insert_module(EVENTS_MODULE, entry);
    }

    /// The writer of `_supervisor/events`.
    pub(crate) fn events_writer(&self) -> crate::QueueWriter<crate::supervision::SupervisorEvent> {
        use crate::supervision::{EVENTS_MODULE, EVENTS_PATH};
        match self
            .entries
            .get(&format!("{EVENTS_MODULE}/{EVENTS_PATH}"))
            .map(|e| &e.handle)
        {
            Some(Handle::QueueOut(core)) => crate::QueueWriter::new(core.clone(), Arc::default()),
            // Only reachable if `declare_events` was not called: events then go nowhere.
            _ => crate::QueueWriter::new(
                QueueCore::new(
                    "_supervisor/events",
                    TypeInfo::of::<crate::supervision::SupervisorEvent>(),
                    1,
                ),
                Arc::default(),
            ),
        }
    }
}
