//! An agent's modules and the links between them as a graph, for pictures (`petrel graph`).

use petgraph::graph::{DiGraph, NodeIndex};
use std::collections::{HashMap, HashSet};

use super::Registry;
use crate::url::PropertyUrl;

/// A node of a [`ModuleGraph`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GraphNode {
    /// A module of this agent.
    Module {
        /// Instance name.
        name: String,
        /// Module type, e.g. `nav.mapper`.
        type_name: String,
    },
    /// A module of another agent that a link reads from.
    Remote {
        /// The other agent's name.
        agent: String,
        /// The module's name there.
        module: String,
    },
}

/// An edge of a [`ModuleGraph`]: data flows from the module owning `source` to the one owning
/// `reader`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GraphLink {
    /// The linked property's path in the reading module (`in/pose`).
    pub reader: String,
    /// The path read, in the source module (`out/estimatedPose`).
    pub source: String,
    /// A queue link (a stream of items) rather than a value.
    pub queue: bool,
    /// A link to another agent's property, carried by the team transport.
    pub remote: bool,
}

/// Modules as nodes, links as edges from the module read to the module reading.
pub type ModuleGraph = DiGraph<GraphNode, GraphLink>;

/// The modules on a cycle of links, as of a generation of the links and of the modules.
pub(crate) struct Cyclic {
    links: u64,
    modules: u64,
    names: HashSet<String>,
}

impl Registry {
    /// Whether some cycle of links passes through `module`.
    fn on_a_cycle(&self, module: &str) -> bool {
        let links = self.links.generation();
        let modules = self
            .modules_changed
            .load(std::sync::atomic::Ordering::Acquire);
        let mut cyclic = self.cyclic.lock();
        let current = cyclic
            .as_ref()
            .is_some_and(|c| c.links == links && c.modules == modules);
        if !current {
            let graph = self.module_graph();
            let mut names = HashSet::new();
            for component in petgraph::algo::tarjan_scc(&graph) {
                let looped =
                    component.len() > 1 || component.iter().any(|&n| graph.contains_edge(n, n));
                for n in component.into_iter().filter(|_| looped) {
                    if let GraphNode::Module { name, .. } = &graph[n] {
                        names.insert(name.clone());
                    }
                }
            }
            *cyclic = Some(Cyclic {
                links,
                modules,
                names,
            });
        }
        cyclic.as_ref().is_some_and(|c| c.names.contains(module))
    }

    /// The agent's modules and links as a graph (the runtime's own `_...` modules left out).
    pub fn module_graph(&self) -> ModuleGraph {
        let mut graph = ModuleGraph::new();
        let mut nodes: HashMap<(Option<String>, String), NodeIndex> = HashMap::new();
        for module in self.order.iter().filter(|m| !m.starts_with('_')) {
            let node = graph.add_node(GraphNode::Module {
                name: module.clone(),
                type_name: self.modules[module].type_name.clone(),
            });
            nodes.insert((None, module.clone()), node);
        }
        for (key, entry) in &self.entries {
            let Some(target) = self.link_of(key) else {
                continue;
            };
            let (reader_module, reader) = key.split_once('/').expect("keys are module/path");
            let Some(&to) = nodes.get(&(None, reader_module.to_string())) else {
                continue;
            };
            let remote = entry.remote.is_some();
            let (agent, module, source) = match PropertyUrl::parse(target) {
                Ok(url) => (
                    url.agent().filter(|_| remote).map(str::to_string),
                    url.module().to_string(),
                    url.path().to_string(),
                ),
                Err(_) => continue,
            };
            let from =
                *nodes
                    .entry((agent.clone(), module.clone()))
                    .or_insert_with(|| match &agent {
                        Some(agent) => graph.add_node(GraphNode::Remote {
                            agent: agent.clone(),
                            module: module.clone(),
                        }),
                        None => graph.add_node(GraphNode::Module {
                            type_name: self.module_type(&module).unwrap_or("").to_string(),
                            name: module.clone(),
                        }),
                    });
            let link = GraphLink {
                reader: reader.to_string(),
                source,
                queue: entry.decl.kind.is_queue(),
                remote,
            };
            graph.add_edge(from, to, link);
        }
        graph
    }

    /// The shortest cycle of links that leads from `module`'s outputs back to its inputs, as
    /// `writer/out/x → reader/in/y` steps, or `None` when no link cycle passes through it.
    ///
    /// Asked by every module whose wake-ups chain further than the loop watch allows: in a
    /// chain of thousands of linked modules, every one past the limit. The modules on some
    /// cycle are worked out once per change of the links or modules (strongly connected
    /// components), so a module on none is answered without building the graph; building it
    /// per question made the start of a 2,000-module chain take seconds.
    pub fn feedback_cycle(&self, module: &str) -> Option<Vec<String>> {
        if !self.on_a_cycle(module) {
            return None;
        }
        let graph = self.module_graph();
        let start = graph
            .node_indices()
            .find(|&n| matches!(&graph[n], GraphNode::Module { name, .. } if name == module))?;
        let name = |n: NodeIndex| match &graph[n] {
            GraphNode::Module { name, .. } => name.clone(),
            GraphNode::Remote { agent, module } => format!("{agent}/{module}"),
        };
        // Breadth first from `start`, remembering the edge that reached each module first.
        let mut reached_by: HashMap<NodeIndex, petgraph::graph::EdgeIndex> = HashMap::new();
        let mut frontier = std::collections::VecDeque::from([start]);
        while let Some(at) = frontier.pop_front() {
            for edge in graph.edges(at) {
                use petgraph::visit::EdgeRef;
                let next = edge.target();
                if reached_by.contains_key(&next) {
                    continue;
                }
                reached_by.insert(next, edge.id());
                if next == start {
                    let mut steps = Vec::new();
                    let mut to = start;
                    loop {
                        let id = reached_by[&to];
                        let (from, _) = graph.edge_endpoints(id)?;
                        let link = &graph[id];
                        steps.push(format!(
                            "{}/{} → {}/{}",
                            name(from),
                            link.source,
                            name(to),
                            link.reader
                        ));
                        to = from;
                        if to == start {
                            break;
                        }
                    }
                    steps.reverse();
                    return Some(steps);
                }
                frontier.push_back(next);
            }
        }
        None
    }
}
