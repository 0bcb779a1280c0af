//! The catalogue of module types an agent can instantiate: name → factory, description and
//! declared properties. `petrel modules` lists it; configs name its entries.

use std::collections::BTreeMap;
use std::future::Future;
use std::pin::Pin;

use ractor::{Actor, ActorCell, ActorRef};
use tokio::task::JoinHandle;

use crate::blackboard::Registry;
use crate::module::{CheckProblem, Module, Unrecoverable};
use crate::module_actor::{declare_builtins, ModuleActor, ModuleArgs, RunLoop};
use crate::ports::{Ports, PropertyDecl};

type SpawnResult = Result<(ActorCell, JoinHandle<()>), SpawnFailure>;

/// Why a module instance could not start.
pub(crate) struct SpawnFailure {
    pub reason: String,
    /// The module said a restart cannot fix it ([`crate::Unrecoverable`]).
    pub unrecoverable: bool,
}
type SpawnFuture = Pin<Box<dyn Future<Output = SpawnResult> + Send>>;

/// A registered module type.
#[derive(Clone, Copy)]
pub struct ModuleType {
    name: &'static str,
    description: &'static str,
    declare: fn(&str) -> Ports,
    check: fn(&Registry, &str) -> Vec<CheckProblem>,
    spawn: fn(ModuleArgs, ActorCell) -> SpawnFuture,
}

impl ModuleType {
    /// The type for module implementation `M`.
    pub fn of<M: Module>() -> Self {
        ModuleType {
            name: M::TYPE,
            description: M::DESCRIPTION,
            declare: |name| {
                let mut ports = Ports::fresh(name);
                declare_builtins(&mut ports);
                drop(M::declare(&mut ports));
                ports
            },
            check: |registry, name| {
                let Some(handles) = registry.handles(name) else {
                    return Vec::new();
                };
                let mut ports = Ports::bound(name, handles);
                declare_builtins(&mut ports);
                let module = M::declare(&mut ports);
                if !ports.errors.is_empty() {
                    return Vec::new(); // the registry reports declaration errors itself
                }
                module.check(&crate::module::AgentView::new(registry))
            },
            spawn: |args, supervisor| {
                Box::pin(async move {
                    // Unnamed: ractor's actor names are process-global, and two agents (or
                    // tests) may run modules of the same name side by side.
                    Actor::spawn_linked(None, ModuleActor::<M>::new(), args, supervisor)
                        .await
                        .map(|(actor, join): (ActorRef<RunLoop>, _)| (actor.get_cell(), join))
                        .map_err(|e| match e {
                            ractor::SpawnErr::StartupFailed(reason) => SpawnFailure {
                                unrecoverable: reason.downcast_ref::<Unrecoverable>().is_some(),
                                reason: reason.to_string(),
                            },
                            other => SpawnFailure {
                                reason: other.to_string(),
                                unrecoverable: false,
                            },
                        })
                })
            },
        }
    }

    /// The name configs use.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// One line saying what it does.
    pub fn description(&self) -> &'static str {
        self.description
    }

    /// Its properties (including the runtime's `enabled` and `stats/...`), in declaration order.
    pub fn properties(&self) -> Vec<PropertyDecl> {
        (self.declare)("describe").decls
    }

    /// A fresh declaration of an instance called `name`.
    pub(crate) fn declare(&self, name: &str) -> Ports {
        (self.declare)(name)
    }

    /// What [`Module::check`] finds in the values `registry` holds for instance `name` (nothing
    /// runs: the instance is declared over those values and asked).
    pub fn check(&self, registry: &Registry, name: &str) -> Vec<CheckProblem> {
        (self.check)(registry, name)
    }

    pub(crate) fn spawn(&self, args: ModuleArgs, supervisor: ActorCell) -> SpawnFuture {
        (self.spawn)(args, supervisor)
    }
}

/// Module types by name.
#[derive(Clone, Default)]
pub struct ModuleRegistry {
    types: BTreeMap<&'static str, ModuleType>,
}

impl ModuleRegistry {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds module type `M` (replacing any type of the same name).
    pub fn register<M: Module>(&mut self) -> &mut Self {
        self.types.insert(M::TYPE, ModuleType::of::<M>());
        self
    }

    /// The type called `name`.
    pub fn get(&self, name: &str) -> Option<&ModuleType> {
        self.types.get(name)
    }

    /// Every type, by name.
    pub fn types(&self) -> impl Iterator<Item = &ModuleType> {
        self.types.values()
    }

    /// Up to three registered names within a few edits of `name`, closest first, for
    /// "did you mean" hints.
    pub fn nearest(&self, name: &str) -> Vec<&'static str> {
        let limit = (name.len() / 4).max(2);
        let mut scored: Vec<(usize, &'static str)> = self
            .types
            .keys()
            .map(|k| (strsim::levenshtein(name, k), *k))
            .filter(|(d, _)| *d <= limit)
            .collect();
        scored.sort();
        scored.into_iter().take(3).map(|(_, k)| k).collect()
    }
}
