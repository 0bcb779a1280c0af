//! The blackboard: one actor per agent owning the registry of properties, links and queues.
//!
//! Structure changes (link, unlink, set from a tool, snapshot) are messages to the actor, so
//! they apply one at a time in a single place. Values do not go through the actor: modules hold
//! direct handles to the cells (see [`crate::handle`]).

mod error;
mod registry;
mod team;

use std::collections::HashMap;
use std::sync::Arc;

use ractor::{Actor, ActorProcessingErr, ActorRef, RpcReplyPort};

use crate::cell::Signal;
use crate::config::ModuleConfig;
use crate::handle::{AnyHandle, PropertyHandle};
use crate::module_types::ModuleType;
use crate::ports::Handle;
use crate::types::PropertyType;
use crate::value::{AnyValue, TypeInfo};

pub use error::BlackboardError;
pub use registry::{GraphLink, GraphNode, ModuleGraph, Registry, TapFilter, WatchedTap};
pub use team::{AgentListing, ModuleListing, PropertyListing};

/// What a (re)starting module instance needs from the blackboard.
pub(crate) struct Binding {
    pub handles: HashMap<String, Handle>,
    pub signal: Arc<Signal>,
}

type Reply<T> = RpcReplyPort<Result<T, BlackboardError>>;

pub(crate) enum BlackboardMsg {
    Bind(String, Reply<Binding>),
    Link(String, String, Reply<()>),
    Unlink(String, Reply<()>),
    Set {
        key: String,
        type_info: TypeInfo,
        value: AnyValue,
        runtime: bool,
        reply: Reply<()>,
    },
    SetRon(String, ron::Value, Reply<()>),
    Get(String, Reply<(TypeInfo, AnyValue)>),
    Endpoint(String, Reply<Arc<crate::cell::Endpoint>>),
    Latest(String, Reply<AnyHandle>),
    AnyHandle(String, Reply<AnyHandle>),
    Snapshot(Reply<String>),
    LinkOf(String, Reply<Option<String>>),
    CheckLink(String, String, Reply<()>),
    FeedbackCycle(String, Reply<Option<Vec<String>>>),
    AddModule(
        Box<ModuleConfig>,
        ModuleType,
        RpcReplyPort<Result<(), String>>,
    ),
    RemoveModule(String, Reply<()>),
    Signals(Reply<Vec<Arc<Signal>>>),
    Team(team::TeamRequest),
}

struct BlackboardActor;

impl Actor for BlackboardActor {
    type Msg = BlackboardMsg;
    type State = Registry;
    type Arguments = Registry;

    async fn pre_start(
        &self,
        _me: ActorRef<Self::Msg>,
        registry: Registry,
    ) -> Result<Registry, ActorProcessingErr> {
        tracing::info!(
            agent = registry.agent(),
            modules = registry.modules().len(),
            "blackboard started"
        );
        Ok(registry)
    }

    async fn handle(
        &self,
        _me: ActorRef<Self::Msg>,
        msg: Self::Msg,
        reg: &mut Registry,
    ) -> Result<(), ActorProcessingErr> {
        // A reply port whose caller gave up is not the blackboard's failure: ignore send errors.
        match msg {
            BlackboardMsg::Bind(module, reply) => {
                let binding = reg
                    .handles(&module)
                    .zip(reg.module(&module))
                    .map(|(handles, m)| Binding {
                        handles,
                        signal: m.signal.clone(),
                    });
                let _ = reply.send(
                    binding.ok_or_else(|| reg.key_of(&format!("{module}/enabled")).unwrap_err()),
                );
            }
            BlackboardMsg::Link(from, to, reply) => {
                let result = reg.link(&from, &to);
                match &result {
                    Ok(()) => tracing::info!(agent = reg.agent(), %from, %to, "linked"),
                    Err(e) => {
                        tracing::warn!(agent = reg.agent(), %from, %to, error = %e, "link refused")
                    }
                }
                let _ = reply.send(result);
            }
            BlackboardMsg::Unlink(from, reply) => {
                let result = reg.unlink(&from);
                tracing::info!(agent = reg.agent(), %from, ok = result.is_ok(), "unlinked");
                let _ = reply.send(result);
            }
            BlackboardMsg::Set {
                key,
                type_info,
                value,
                runtime,
                reply,
            } => {
                let result = if runtime {
                    reg.set_runtime(&key, type_info, value)
                } else {
                    reg.set(&key, type_info, value)
                };
                let _ = reply.send(result);
            }
            BlackboardMsg::SetRon(key, value, reply) => {
                let _ = reply.send(reg.set_from_ron_live(&key, value));
            }
            BlackboardMsg::Get(key, reply) => {
                let _ = reply.send(reg.get(&key));
            }
            BlackboardMsg::Endpoint(key, reply) => {
                let _ = reply.send(reg.endpoint(&key));
            }
            BlackboardMsg::Latest(key, reply) => {
                let _ = reply.send(reg.any_handle(&key, true));
            }
            BlackboardMsg::AnyHandle(key, reply) => {
                let _ = reply.send(reg.any_handle(&key, false));
            }
            BlackboardMsg::AddModule(config, module_type, reply) => {
                let result = reg.add_module(&config, &module_type);
                tracing::info!(agent = reg.agent(), module = %config.name, ok = result.is_ok(), "module added");
                let _ = reply.send(result);
            }
            BlackboardMsg::RemoveModule(module, reply) => {
                let result = reg.remove_module(&module);
                tracing::info!(agent = reg.agent(), %module, ok = result.is_ok(), "module removed");
                let _ = reply.send(result);
            }
            BlackboardMsg::CheckLink(from, to, reply) => {
                let _ = reply.send(reg.check_link(&from, &to).map(drop));
            }
            BlackboardMsg::LinkOf(address, reply) => {
                let result = reg
                    .key_of(&address)
                    .map(|key| reg.link_of(&key).map(str::to_string));
                let _ = reply.send(result);
            }
            BlackboardMsg::Signals(reply) => {
                let _ = reply.send(Ok(reg.signals()));
            }
            BlackboardMsg::Team(request) => team::handle(reg, request),
            BlackboardMsg::FeedbackCycle(module, reply) => {
                let _ = reply.send(Ok(reg.feedback_cycle(&module)));
            }
            BlackboardMsg::Snapshot(reply) => {
                let _ = reply.send(Ok(crate::snapshot::write(reg)));
            }
        }
        // Before the caller hears back: a module added here is tapped before it starts.
        reg.announce_taps();
        Ok(())
    }
}

/// A handle to an agent's blackboard actor; cheap to clone.
#[derive(Clone)]
pub struct Blackboard {
    actor: ActorRef<BlackboardMsg>,
    agent: Arc<str>,
    remote: Arc<crate::team::RemoteLinks>,
    /// Carries writes to other agents' properties, once the agent joined its team.
    writer: Arc<parking_lot::RwLock<Option<Arc<dyn crate::team::RemoteWriter>>>>,
    /// The runtime the blackboard actor was started on: the agent's own thread, if it has one
    /// (see [`spawn_beside`](Blackboard::spawn_beside)).
    runtime: tokio::runtime::Handle,
    /// Counts the modules added and removed (see [`modules_changed`](Blackboard::modules_changed)).
    modules_changed: Arc<std::sync::atomic::AtomicU64>,
}

impl Blackboard {
    /// Starts the blackboard actor owning `registry`.
    pub async fn spawn(
        registry: Registry,
    ) -> Result<(Blackboard, tokio::task::JoinHandle<()>), BlackboardError> {
        let remote = registry.remote_links();
        let modules_changed = registry.modules_changed();
        let agent = Arc::from(registry.agent());
        let (actor, join) = Actor::spawn(None, BlackboardActor, registry)
            .await
            .map_err(|_| BlackboardError::Stopped)?;
        let writer = Arc::default();
        Ok((
            Blackboard {
                actor,
                agent,
                remote,
                writer,
                runtime: tokio::runtime::Handle::current(),
                modules_changed,
            },
            join,
        ))
    }

    /// Spawns `future` beside the agent's modules: on the agent's own thread when it has one
    /// (`scheduler: agent_thread`), else on the runtime the blackboard was started on.
    ///
    /// For a task that follows the agent's writes (a recorder reading what its modules
    /// write): a module's write then wakes it on the writing thread, a same-thread wake rather
    /// than a cross-thread one. The task must never block, and it ends (cancelled) when the
    /// agent's thread does, at [`Agent::shutdown`](crate::Agent::shutdown).
    pub fn spawn_beside<F>(&self, future: F) -> tokio::task::JoinHandle<F::Output>
    where
        F: std::future::Future + Send + 'static,
        F::Output: Send + 'static,
    {
        self.runtime.spawn(future)
    }

    /// How many times a module was added or removed (including the runtime's own): one
    /// atomic load, for a caller that keeps something per module to know when to look again.
    pub(crate) fn modules_changed(&self) -> u64 {
        self.modules_changed
            .load(std::sync::atomic::Ordering::Acquire)
    }

    async fn call<T: Send + 'static>(
        &self,
        msg: impl FnOnce(Reply<T>) -> BlackboardMsg,
    ) -> Result<T, BlackboardError> {
        match self.actor.call(msg, None).await {
            Ok(ractor::rpc::CallResult::Success(result)) => result,
            _ => Err(BlackboardError::Stopped),
        }
    }

    /// The name of the agent whose blackboard this is.
    pub fn agent(&self) -> &str {
        &self.agent
    }

    pub(crate) async fn bind(&self, module: &str) -> Result<Binding, BlackboardError> {
        self.call(|r| BlackboardMsg::Bind(module.to_string(), r))
            .await
    }

    /// The wake-up signals of the agent's modules (see [`Context::settle_agent`]).
    pub(crate) async fn signals(&self) -> Result<Vec<Arc<Signal>>, BlackboardError> {
        self.call(BlackboardMsg::Signals).await
    }

    /// Links `from` to `to` while running; readers of `from` see `to` from their next read.
    pub async fn link(&self, from: &str, to: &str) -> Result<(), BlackboardError> {
        self.call(|r| BlackboardMsg::Link(from.to_string(), to.to_string(), r))
            .await
    }

    /// Whether `from` could be linked to `to` as the links stand now (see
    /// [`Registry::check_link`]): for checks made before a link is, such as a plan binding's.
    pub async fn check_link(&self, from: &str, to: &str) -> Result<(), BlackboardError> {
        self.call(|r| BlackboardMsg::CheckLink(from.to_string(), to.to_string(), r))
            .await
    }

    /// Where `address` links to (`module/path`), or `None` if it is not linked.
    pub async fn link_of(&self, address: &str) -> Result<Option<String>, BlackboardError> {
        self.call(|r| BlackboardMsg::LinkOf(address.to_string(), r))
            .await
    }

    /// Removes the link of `from`.
    pub async fn unlink(&self, from: &str) -> Result<(), BlackboardError> {
        self.call(|r| BlackboardMsg::Unlink(from.to_string(), r))
            .await
    }

    /// Sets a property (e.g. a parameter, or a module's `enabled`) to a typed value. A full
    /// address naming another agent (`petrel://robot2/planner/params/speed`) is a remote
    /// write, carried by the agent's team where the owner allows it.
    pub async fn set<T: PropertyType>(
        &self,
        address: &str,
        value: T,
    ) -> Result<(), BlackboardError> {
        if let Some(url) = self.other_agent(address) {
            return self.set_remote(url, &value).await;
        }
        self.set_any(address, Arc::new(value), TypeInfo::of::<T>(), false)
            .await
    }

    /// Sets a runtime-owned property (`stats/...`); for the supervisor.
    pub(crate) async fn set_runtime<T: PropertyType>(
        &self,
        address: &str,
        value: T,
    ) -> Result<(), BlackboardError> {
        self.set_any(address, Arc::new(value), TypeInfo::of::<T>(), true)
            .await
    }

    async fn set_any(
        &self,
        address: &str,
        value: AnyValue,
        type_info: TypeInfo,
        runtime: bool,
    ) -> Result<(), BlackboardError> {
        let key = address.to_string();
        self.call(|reply| BlackboardMsg::Set {
            key,
            type_info,
            value,
            runtime,
            reply,
        })
        .await
    }

    /// Sets a property from RON text, checking it against the property's type and range, as a
    /// person's write while the agent runs (`petrel set`, the console): a parameter its module
    /// reads only when it starts is refused.
    pub async fn set_text(&self, address: &str, ron_text: &str) -> Result<(), BlackboardError> {
        let value = parse_set_text(ron_text).map_err(|reason| BlackboardError::BadValue {
            key: address.to_string(),
            expected: "a RON value",
            reason,
        })?;
        self.call(|r| BlackboardMsg::SetRon(address.to_string(), value, r))
            .await
    }

    /// The current value of a property, if it has type `T`.
    pub async fn get<T: PropertyType>(&self, address: &str) -> Result<Arc<T>, BlackboardError> {
        let (ti, value) = self
            .call(|r| BlackboardMsg::Get(address.to_string(), r))
            .await?;
        value
            .downcast::<T>()
            .map_err(|_| BlackboardError::BadValue {
                key: address.to_string(),
                expected: T::TYPE_NAME,
                reason: format!("the property is a {}", ti.name()),
            })
    }

    /// The current value of a property as RON text.
    pub async fn get_text(&self, address: &str) -> Result<String, BlackboardError> {
        let (ti, value) = self
            .call(|r| BlackboardMsg::Get(address.to_string(), r))
            .await?;
        ti.to_ron(&value)
            .map_err(|reason| BlackboardError::BadValue {
                key: address.into(),
                expected: ti.name(),
                reason,
            })
    }

    /// A direct handle to a value property, for tools, tests and benchmarks that drive or watch
    /// a running agent: reads and writes skip the actor, like a module's own handles.
    pub async fn handle<T: PropertyType>(
        &self,
        address: &str,
    ) -> Result<PropertyHandle<T>, BlackboardError> {
        let ep = self
            .call(|r| BlackboardMsg::Endpoint(address.to_string(), r))
            .await?;
        if !ep.type_info().is::<T>() {
            return Err(BlackboardError::BadValue {
                key: address.to_string(),
                expected: T::TYPE_NAME,
                reason: format!("the property is a {}", ep.type_info().name()),
            });
        }
        Ok(PropertyHandle::new(ep))
    }

    /// Like [`any_handle`](Blackboard::any_handle), and for a queue a read handle to its
    /// latest item (version = items pushed since it was first asked for, write time = push
    /// time): what expressions read, so `min(robot/out/laserScan.ranges)` works. A queue
    /// whose item type has no known default and that has no item yet is refused.
    pub async fn expr_handle(&self, address: &str) -> Result<AnyHandle, BlackboardError> {
        self.call(|r| BlackboardMsg::Latest(address.to_string(), r))
            .await
    }

    /// An untyped direct handle to a value property (see [`AnyHandle`]).
    pub async fn any_handle(&self, address: &str) -> Result<AnyHandle, BlackboardError> {
        self.call(|r| BlackboardMsg::AnyHandle(address.to_string(), r))
            .await
    }

    /// The shortest cycle of links through `module` (see [`Registry::feedback_cycle`]).
    pub(crate) async fn feedback_cycle(
        &self,
        module: &str,
    ) -> Result<Option<Vec<String>>, BlackboardError> {
        self.call(|r| BlackboardMsg::FeedbackCycle(module.to_string(), r))
            .await
    }

    /// The whole blackboard as a RON agent config (values, links, queue capacities).
    pub async fn snapshot(&self) -> Result<String, BlackboardError> {
        self.call(BlackboardMsg::Snapshot).await
    }

    pub(crate) async fn add_module(
        &self,
        config: ModuleConfig,
        module_type: ModuleType,
    ) -> Result<(), String> {
        match self
            .actor
            .call(
                |r| BlackboardMsg::AddModule(Box::new(config), module_type, r),
                None,
            )
            .await
        {
            Ok(ractor::rpc::CallResult::Success(result)) => result,
            _ => Err(BlackboardError::Stopped.to_string()),
        }
    }

    pub(crate) async fn remove_module(&self, module: &str) -> Result<(), BlackboardError> {
        self.call(|r| BlackboardMsg::RemoveModule(module.to_string(), r))
            .await
    }

    /// Stops the blackboard actor.
    pub(crate) fn stop(&self) {
        self.actor.stop(None);
    }
}
/// A value as a person writes it to set a property (RON, as in a config), read before its
/// property's type is known: why it is no value at all, if it is none. `petrel set` asks this
/// before it reaches the agent (bad input), and the agent the same when it is reached another
/// way.
pub fn parse_set_text(ron_text: &str) -> Result<ron::Value, String> {
    let value: ron::Value = ron::from_str(ron_text).map_err(|e| match e.code {
        // ron's own text names its options, which a person setting a value cannot use.
        ron::Error::ExceededRecursionLimit => {
            "nested too deeply (lists or structures within each other)".to_string()
        }
        // Text without its quotes (a path, words): say how to write it.
        _ if looks_like_unquoted_text(ron_text) => {
            let text = ron_text.trim();
            format!("{e}: text takes double quotes: `\"{text}\"`, in a shell '\"{text}\"'")
        }
        _ => e.to_string(),
    })?;
    // RON reads a bare word as a unit value: text takes quotes.
    let word = ron_text.trim();
    if value == ron::Value::Unit && !word.is_empty() && word != "()" {
        return Err(format!(
            "`{word}` is a bare word, which is no value (text takes double quotes: `\"{word}\"`, in a shell '\"{word}\"')"
        ));
    }
    Ok(value)
}

/// Whether `text` that is no RON starts as no RON value does (a quote, a bracket, a number,
/// a word such as `true` or `Some`): a path or words meant as text.
fn looks_like_unquoted_text(text: &str) -> bool {
    text.trim_start().starts_with(|c: char| {
        matches!(c, '/' | '.' | '~') || c.is_alphabetic() && !c.is_ascii_uppercase()
    })
}
