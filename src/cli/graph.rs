//! `petrel graph CONFIG`: the agent's modules and links as a Graphviz DOT picture.

use std::path::PathBuf;
use std::process::ExitCode;

use petgraph::dot::{Config, Dot};
use petrel_actors::{GraphLink, GraphNode, ModuleGraph, ModuleRegistry};

use super::{bad_input, load};

/// Prints the module graph of `config` (with `overlays`) as DOT on standard output.
pub(crate) fn graph(registry: &ModuleRegistry, config: &PathBuf, overlays: &[PathBuf]) -> ExitCode {
    let built = match load(config, overlays).and_then(|f| f.build(registry)) {
        Ok(built) => built,
        Err(errors) => return bad_input(&errors),
    };
    let dot = to_dot(built.agent(), &built.module_graph());
    super::stdout::say!("{dot}");
    ExitCode::SUCCESS
}

/// DOT for an agent's module graph: a box per module (name and type), a dashed box per other
/// agent's module, an edge per link labelled `source → reader`; queues drawn bold, remote
/// links dashed.
pub(crate) fn to_dot(agent: &str, graph: &ModuleGraph) -> String {
    let edge = |_: &ModuleGraph,
                e: <&ModuleGraph as petgraph::visit::IntoEdgeReferences>::EdgeRef| {
        edge_attributes(e.weight())
    };
    let node =
        |_: &ModuleGraph, (_, n): (petgraph::graph::NodeIndex, &GraphNode)| node_attributes(n);
    let body = Dot::with_attr_getters(
        graph,
        &[
            Config::NodeNoLabel,
            Config::EdgeNoLabel,
            Config::GraphContentOnly,
        ],
        &edge,
        &node,
    );
    format!(
        "digraph {} {{\n    rankdir=LR;\n    node [shape=box, fontname=\"Helvetica\"];\n    edge [fontname=\"Helvetica\", fontsize=10];\n{body:?}}}\n",
        quote(agent)
    )
}

fn node_attributes(node: &GraphNode) -> String {
    match node {
        GraphNode::Module { name, type_name } => {
            format!("label = {}", quote(&format!("{name}\n{type_name}")))
        }
        GraphNode::Remote { agent, module } => format!(
            "label = {}, style = dashed",
            quote(&format!("{agent}/{module}"))
        ),
    }
}

fn edge_attributes(link: &GraphLink) -> String {
    let label = quote(&format!("{} → {}", link.source, link.reader));
    let styles: Vec<&str> = [(link.queue, "bold"), (link.remote, "dashed")]
        .into_iter()
        .filter_map(|(on, style)| on.then_some(style))
        .collect();
    if styles.is_empty() {
        format!("label = {label}")
    } else {
        format!("label = {label}, style = \"{}\"", styles.join(","))
    }
}

/// A DOT quoted string: `"` and `\` escaped, newlines as DOT's centred line break.
fn quote(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modules_links_queues_and_remote_links_are_drawn_distinctly() {
        let mut g = ModuleGraph::new();
        let sensor = g.add_node(GraphNode::Module {
            name: "sensor".into(),
            type_name: "demo.signal".into(),
        });
        let filter = g.add_node(GraphNode::Module {
            name: "filter".into(),
            type_name: "demo.scale".into(),
        });
        let far = g.add_node(GraphNode::Remote {
            agent: "robot2".into(),
            module: "laser".into(),
        });
        let link = |source: &str, reader: &str, queue, remote| GraphLink {
            reader: reader.into(),
            source: source.into(),
            queue,
            remote,
        };
        g.add_edge(sensor, filter, link("out/value", "in/value", false, false));
        g.add_edge(far, filter, link("out/scan", "in/scan", true, true));
        let dot = to_dot("robot\"1", &g);
        assert!(dot.starts_with("digraph \"robot\\\"1\" {"), "{dot}");
        assert!(dot.contains("label = \"sensor\\ndemo.signal\""), "{dot}");
        assert!(
            dot.contains("2 [ label = \"robot2/laser\", style = dashed]"),
            "{dot}"
        );
        assert!(
            dot.contains("0 -> 1 [ label = \"out/value → in/value\"]"),
            "{dot}"
        );
        assert!(
            dot.contains("2 -> 1 [ label = \"out/scan → in/scan\", style = \"bold,dashed\"]"),
            "{dot}"
        );
        assert!(dot.trim_end().ends_with('}'));
    }
}
