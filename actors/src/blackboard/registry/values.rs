//! Reading and setting property values through the registry (tools, configs, snapshots,
//! contexts): type and range checks, links followed, queues read as their latest item; and
//! queue capacities.

use std::sync::Arc;

use super::{Entry, Registry, MAX_QUEUE_CAPACITY};
use crate::blackboard::error::BlackboardError;
use crate::cell::Endpoint;
use crate::ports::Handle;
use crate::types::FilePath;
use crate::value::{AnyValue, TypeInfo};

impl Registry {
    /// Sets a property from a config value, checking its type.
    pub fn set_from_ron(
        &mut self,
        address: &str,
        value: ron::Value,
    ) -> Result<(), BlackboardError> {
        let key = self.key_of(address)?;
        let ti = self.entries[&key].decl.type_info;
        let value = match ti.from_ron(value.clone()) {
            Ok(v) => v,
            Err(reason) => {
                // Say what a value looks like, from the property's current one.
                let example = self.get(&key).ok().and_then(|(_, v)| ti.to_ron(&v).ok());
                let reason = match example {
                    Some(example) => crate::value::config_value_error(
                        &reason,
                        &crate::value::value_example(ti.name(), &example),
                        &value,
                    ),
                    None => reason,
                };
                return Err(BlackboardError::BadValue {
                    key: key.clone(),
                    expected: ti.name(),
                    reason,
                });
            }
        };
        self.set(&key, ti, value)
    }

    /// Sets a property to a value of type `type_info`.
    pub(crate) fn set(
        &self,
        address: &str,
        type_info: TypeInfo,
        value: AnyValue,
    ) -> Result<(), BlackboardError> {
        let key = self.check_set(address, &value)?;
        self.write_key(key, type_info, value)
    }

    /// Whether a checked write (a person's `petrel set`, a rule's) would take `value` for the
    /// property at `address` (its kind and range; the type is the caller's): for checks made
    /// before a run, such as a context rule's constant `set`. Returns the property's key.
    pub fn check_set(&self, address: &str, value: &AnyValue) -> Result<String, BlackboardError> {
        let key = self.key_of(address)?;
        let decl = &self.entries[&key].decl;
        crate::handle::WriteRule::check(
            &key,
            decl.kind,
            decl.range.as_ref(),
            decl.shape.as_ref(),
            &decl.doc,
            value,
        )?;
        Ok(key)
    }

    /// [`check_set`](Self::check_set) for a write while the agent runs (a person's `petrel
    /// set`, a context rule's, a plan binding's), which also refuses a parameter its module
    /// reads only when it starts ([`Ports::read_at_start`](crate::Ports::read_at_start)).
    pub fn check_live_set(
        &self,
        address: &str,
        value: &AnyValue,
    ) -> Result<String, BlackboardError> {
        let key = self.check_set(address, value)?;
        match self.entries[&key].decl.read_at_start {
            true => Err(BlackboardError::ReadAtStart { key }),
            false => Ok(key),
        }
    }

    /// [`set_from_ron`](Self::set_from_ron) for a person's write while the agent runs (`petrel
    /// set`, the console): a parameter read only at start is refused before its value is read.
    pub fn set_from_ron_live(
        &mut self,
        address: &str,
        value: ron::Value,
    ) -> Result<(), BlackboardError> {
        let key = self.key_of(address)?;
        if self.entries[&key].decl.read_at_start {
            return Err(BlackboardError::ReadAtStart { key });
        }
        let value = match self.entries[&key].decl.type_info.is::<FilePath>() {
            true => live_file_path(&key, value)?,
            false => value,
        };
        self.set_from_ron(&key, value)
    }

    /// Sets any value property, including runtime-owned `stats/...`.
    pub(crate) fn set_runtime(
        &self,
        address: &str,
        type_info: TypeInfo,
        value: AnyValue,
    ) -> Result<(), BlackboardError> {
        self.write_key(self.key_of(address)?, type_info, value)
    }

    /// [`set_runtime`](Registry::set_runtime) for a key already resolved (an entry's key).
    fn write_key(
        &self,
        key: String,
        type_info: TypeInfo,
        value: AnyValue,
    ) -> Result<(), BlackboardError> {
        let entry = &self.entries[&key];
        if entry.decl.type_info != type_info {
            return Err(BlackboardError::BadValue {
                key,
                expected: entry.decl.type_info.name(),
                reason: format!("got a {}", type_info.name()),
            });
        }
        match &entry.handle {
            // A value set on a linked property goes to its target, like writing through a symlink.
            Handle::Value(ep) => {
                ep.write(value);
                Ok(())
            }
            _ => Err(BlackboardError::NotSettable {
                key,
                kind: entry.decl.kind,
            }),
        }
    }

    /// Like [`get`](Registry::get), and for a queue its latest item (what expressions read).
    pub fn get_or_latest(&self, address: &str) -> Result<(TypeInfo, AnyValue), BlackboardError> {
        let ep = self.endpoint_or_latest(address)?;
        Ok((ep.type_info(), ep.value()))
    }

    /// The current value of a property (of its link target, if linked).
    pub fn get(&self, address: &str) -> Result<(TypeInfo, AnyValue), BlackboardError> {
        let key = self.key_of(address)?;
        match &self.entries[&key].handle {
            Handle::Value(ep) => Ok((ep.type_info(), ep.value())),
            _ => Err(BlackboardError::NotAValue {
                kind: self.entries[&key].decl.kind,
                key,
            }),
        }
    }

    /// An untyped handle to the value property at `address` ([`endpoint`](Registry::endpoint)),
    /// or with `latest`, to a queue's latest item ([`endpoint_or_latest`](Registry::endpoint_or_latest)),
    /// carrying what a write through it must respect.
    pub(crate) fn any_handle(
        &self,
        address: &str,
        latest: bool,
    ) -> Result<crate::AnyHandle, BlackboardError> {
        let ep = match latest {
            true => self.endpoint_or_latest(address)?,
            false => self.endpoint(address)?,
        };
        let decl = &self.entries[&self.key_of(address)?].decl;
        let rule = crate::handle::WriteRule {
            kind: decl.kind,
            range: decl.range,
            doc: decl.doc.clone(),
            read_at_start: decl.read_at_start,
            shape: decl.shape.clone(),
        };
        Ok(crate::AnyHandle {
            ep,
            plain: rule.kind.settable()
                && rule.range.is_none()
                && rule.shape.is_none()
                && !rule.read_at_start,
            rule: Arc::new(rule),
        })
    }

    /// The endpoint of a value property.
    pub(crate) fn endpoint(&self, address: &str) -> Result<Arc<Endpoint>, BlackboardError> {
        let key = self.key_of(address)?;
        match &self.entries[&key].handle {
            Handle::Value(ep) => Ok(ep.clone()),
            _ => Err(BlackboardError::NotAValue {
                kind: self.entries[&key].decl.kind,
                key,
            }),
        }
    }

    /// Like [`endpoint`](Registry::endpoint), and for a queue (output, or input read through
    /// its link) its latest item as a value (see `QueueCore::latest`): what expressions read.
    pub(crate) fn endpoint_or_latest(
        &self,
        address: &str,
    ) -> Result<Arc<Endpoint>, BlackboardError> {
        let key = self.key_of(address)?;
        let queue = match &self.entries[&key].handle {
            Handle::QueueOut(core) => Some(core.clone()),
            Handle::QueueIn(reader) => Some(reader.source()),
            _ => None,
        };
        if let Some(core) = queue {
            return core
                .latest(crate::types::sample_of(core.type_info))
                .ok_or_else(|| BlackboardError::BadValue {
                    key: key.clone(),
                    expected: core.type_info.name(),
                    reason: "this queue has no item yet and its item type has no known default: its latest item cannot be read as a value until one is pushed".into(),
                });
        }
        match &self.entries[&key].handle {
            Handle::Value(ep) => Ok(ep.clone()),
            _ => Err(BlackboardError::NotSettable {
                kind: self.entries[&key].decl.kind,
                key,
            }),
        }
    }

    /// Sets the capacity of an output queue: 1 to 2^20 (1,048,576) items.
    pub fn set_capacity(&mut self, address: &str, capacity: usize) -> Result<(), BlackboardError> {
        let key = self.key_of(address)?;
        let entry = &self.entries[&key];
        // An input's own queue holds what another agent (a remote link) or a replay feeds it;
        // a local link reads the output queue, whose capacity is the one that counts then.
        let core = match (&entry.handle, &entry.own_queue) {
            (Handle::QueueOut(core), _) => core,
            (Handle::QueueIn(_), Some(own)) => own,
            _ => {
                return Err(BlackboardError::BadValue {
                    key,
                    expected: "a queue",
                    reason: "only queues have a capacity".into(),
                })
            }
        };
        if !(1..=MAX_QUEUE_CAPACITY).contains(&capacity) {
            return Err(BlackboardError::OutOfRange {
                key,
                value: capacity.to_string(),
                range: format!("a capacity in 1..={MAX_QUEUE_CAPACITY}"),
                doc: "items a queue holds until every reader has taken them; 0 could hold nothing"
                    .into(),
            });
        }
        core.set_capacity(capacity);
        Ok(())
    }

    /// The capacity of queue input `entry`'s own queue (what a remote link or a replay feeds
    /// it), when a config changed it from the default.
    pub(crate) fn input_capacity(entry: &Entry) -> Option<usize> {
        let own = entry.own_queue.as_ref()?;
        (own.capacity() != crate::queue::DEFAULT_CAPACITY).then(|| own.capacity())
    }
}

/// A file path a person sets while the agent runs: made absolute against the agent's working
/// directory (so a later reload or restart reads the same file), and refused unless it names a
/// regular file. Without this a typo was taken in silence and found only when the module next
/// read it: at a reload, or at a restart after a crash, which then failed again and again.
/// An empty path (none) and values that are not text (refused by the type) pass unchanged.
fn live_file_path(key: &str, value: ron::Value) -> Result<ron::Value, BlackboardError> {
    let ron::Value::String(text) = &value else {
        return Ok(value);
    };
    let path = FilePath::from(text.as_str());
    if path.is_empty() {
        return Ok(value);
    }
    let cwd = std::env::current_dir().unwrap_or_default();
    let path = path.resolved_against(&cwd);
    match crate::files::regular_file(path.as_path()) {
        Ok(_) => Ok(ron::Value::String(path.to_string())),
        Err(problem) => Err(BlackboardError::BadValue {
            key: key.to_string(),
            expected: "the path of a file",
            reason: format!(
                "`{path}`: {problem} (a relative path is taken from the agent's working directory, {})",
                cwd.display()
            ),
        }),
    }
}
