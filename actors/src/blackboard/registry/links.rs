//! The local links of one agent as a graph: an edge `from → to` for every linked property.
//!
//! A property links to at most one other, and a link that would close a cycle is refused, so the
//! graph is a forest of chains, each ending at an unlinked property (the one whose cell every
//! property of the chain reads). Only properties that take part in a link are nodes, so the
//! graph costs what is linked, not what is declared.

use std::collections::HashMap;

use petgraph::stable_graph::{NodeIndex, StableDiGraph};
use petgraph::visit::{Dfs, EdgeRef, IntoEdgeReferences, Reversed, Walker};
use petgraph::Direction;

#[derive(Default)]
pub(crate) struct LinkGraph {
    graph: StableDiGraph<String, ()>,
    nodes: HashMap<String, NodeIndex>,
    /// Counts the changes, for what is worked out from the links and kept (see
    /// `Registry::feedback_cycle`).
    generation: u64,
}

impl LinkGraph {
    /// Where `key` links to, if it is linked.
    pub fn target(&self, key: &str) -> Option<&str> {
        let node = *self.nodes.get(key)?;
        self.next(node).map(|n| self.graph[n].as_str())
    }

    /// The property at the end of `key`'s chain: `key` itself when it is not linked.
    pub fn end<'a>(&'a self, key: &'a str) -> &'a str {
        let Some(mut node) = self.nodes.get(key).copied() else {
            return key;
        };
        while let Some(next) = self.next(node) {
            node = next;
        }
        &self.graph[node]
    }

    /// The chain `from → to → … → from` that linking `from` to `to` would close, if any.
    pub fn cycle(&self, from: &str, to: &str) -> Option<Vec<String>> {
        if from == to {
            return Some(vec![from.to_string(), to.to_string()]);
        }
        let (&f, &t) = (self.nodes.get(from)?, self.nodes.get(to)?);
        if !petgraph::algo::has_path_connecting(&self.graph, t, f, None) {
            return None;
        }
        let mut chain = vec![from.to_string()];
        let mut at = t;
        loop {
            chain.push(self.graph[at].clone());
            if at == f {
                return Some(chain);
            }
            at = self.next(at).expect("a path from `to` to `from` exists");
        }
    }

    /// Counts the changes made so far.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Links `from` to `to`, or unlinks it with `None`. The caller has ruled out cycles.
    pub fn set(&mut self, from: &str, to: Option<&str>) {
        self.generation += 1;
        if let Some(&f) = self.nodes.get(from) {
            let old: Vec<_> = self
                .graph
                .edges_directed(f, Direction::Outgoing)
                .map(|e| (e.id(), e.target()))
                .collect();
            for (edge, target) in old {
                self.graph.remove_edge(edge);
                self.forget_if_alone(target);
            }
        }
        match to {
            Some(to) => {
                let (f, t) = (self.node(from), self.node(to));
                self.graph.add_edge(f, t, ());
            }
            None => {
                if let Some(&f) = self.nodes.get(from) {
                    self.forget_if_alone(f);
                }
            }
        }
    }

    /// `key` and every property whose chain passes through it: what a change of `key`'s link
    /// re-targets.
    pub fn through<'a>(&'a self, key: &'a str) -> Vec<&'a str> {
        match self.nodes.get(key) {
            None => vec![key],
            Some(&node) => Dfs::new(Reversed(&self.graph), node)
                .iter(Reversed(&self.graph))
                .map(|n| self.graph[n].as_str())
                .collect(),
        }
    }

    /// Properties outside `prefix` that link to a property under it, sorted.
    pub fn linked_into(&self, prefix: &str) -> Vec<String> {
        let mut found: Vec<String> = (&self.graph)
            .edge_references()
            .filter(|e| {
                !self.graph[e.source()].starts_with(prefix)
                    && self.graph[e.target()].starts_with(prefix)
            })
            .map(|e| self.graph[e.source()].clone())
            .collect();
        found.sort();
        found
    }

    /// Drops every property under `prefix` and its links.
    pub fn remove_prefix(&mut self, prefix: &str) {
        self.generation += 1;
        let gone: Vec<String> = self
            .nodes
            .keys()
            .filter(|k| k.starts_with(prefix))
            .cloned()
            .collect();
        for key in gone {
            if let Some(node) = self.nodes.remove(&key) {
                let neighbours: Vec<_> = self.graph.neighbors_undirected(node).collect();
                self.graph.remove_node(node);
                for n in neighbours {
                    self.forget_if_alone(n);
                }
            }
        }
    }

    fn next(&self, node: NodeIndex) -> Option<NodeIndex> {
        self.graph
            .neighbors_directed(node, Direction::Outgoing)
            .next()
    }

    fn node(&mut self, key: &str) -> NodeIndex {
        if let Some(&n) = self.nodes.get(key) {
            return n;
        }
        let n = self.graph.add_node(key.to_string());
        self.nodes.insert(key.to_string(), n);
        n
    }

    /// Removes a node that no link touches any more, so the graph stays as small as the links.
    fn forget_if_alone(&mut self, node: NodeIndex) {
        if self.graph.neighbors_undirected(node).next().is_none() {
            if let Some(key) = self.graph.remove_node(node) {
                self.nodes.remove(&key);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::LinkGraph;

    fn chain(links: &[(&str, &str)]) -> LinkGraph {
        let mut g = LinkGraph::default();
        for (from, to) in links {
            assert!(g.cycle(from, to).is_none(), "{from} -> {to}");
            g.set(from, Some(to));
        }
        g
    }

    #[test]
    fn chains_end_where_nothing_links_on() {
        let g = chain(&[("c/in", "b/out"), ("b/out", "a/out"), ("d/in", "b/out")]);
        assert_eq!(g.end("c/in"), "a/out");
        assert_eq!(g.end("d/in"), "a/out");
        assert_eq!(g.end("a/out"), "a/out");
        assert_eq!(g.end("unlinked"), "unlinked");
        assert_eq!(g.target("c/in"), Some("b/out"));
        assert_eq!(g.target("a/out"), None);
    }

    #[test]
    fn through_lists_everything_whose_chain_passes_a_property() {
        let g = chain(&[
            ("c/in", "b/out"),
            ("b/out", "a/out"),
            ("d/in", "b/out"),
            ("e/in", "x"),
        ]);
        let mut through = g.through("b/out");
        through.sort();
        assert_eq!(through, ["b/out", "c/in", "d/in"]);
        assert_eq!(g.through("c/in"), ["c/in"]);
        assert_eq!(g.through("lonely"), ["lonely"]);
    }

    #[test]
    fn a_link_that_closes_a_loop_is_named_with_its_chain() {
        let g = chain(&[("a", "b"), ("b", "c")]);
        assert_eq!(
            g.cycle("c", "a"),
            Some(vec!["c".into(), "a".into(), "b".into(), "c".into()])
        );
        assert_eq!(g.cycle("a", "a"), Some(vec!["a".into(), "a".into()]));
        assert_eq!(g.cycle("a", "c"), None, "relinking along the chain is fine");
    }

    #[test]
    fn unlinking_and_relinking_keep_the_graph_as_small_as_the_links() {
        let mut g = chain(&[("a", "b"), ("b", "c")]);
        g.set("a", Some("c"));
        assert_eq!(g.target("a"), Some("c"));
        assert_eq!(g.through("b"), ["b"]);
        g.set("b", None);
        g.set("a", None);
        assert_eq!(g.nodes.len(), 0);
        assert_eq!(g.graph.node_count(), 0);
    }

    #[test]
    fn removing_a_module_drops_its_links_and_reports_links_into_it() {
        let mut g = chain(&[
            ("m/in", "src/out"),
            ("src/in", "far/out"),
            ("x/in", "m/out"),
        ]);
        assert_eq!(g.linked_into("src/"), ["m/in"]);
        assert!(g.linked_into("x/").is_empty());
        g.remove_prefix("x/");
        assert_eq!(g.target("x/in"), None);
        assert!(g.linked_into("m/").is_empty());
        assert_eq!(g.end("m/in"), "src/out");
    }
}
