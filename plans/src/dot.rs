//! Graphviz output.

use std::fmt::Write;

use crate::model::Plan;

fn q(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// The plan as a Graphviz `digraph`, left to right: places are circles
/// (double for goal places, red for fail places, tokens shown as `(n)`),
/// transitions are boxes labelled with their label, arcs of weight > 1
/// carry their weight.
pub fn to_dot(plan: &Plan) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "digraph {} {{\n  rankdir=LR;", q(plan.name()));
    for (i, p) in plan.places().iter().enumerate() {
        let mut label = p.label.clone();
        if p.initial > 0 {
            let _ = write!(label, " ({})", p.initial);
        }
        let shape = if p.goal > 0 { "doublecircle" } else { "circle" };
        let color = if p.fail > 0 { ", color=red" } else { "" };
        let _ = writeln!(
            out,
            "  p{i} [shape={shape}{color}, label={}, tooltip={}];",
            q(&label),
            q(&p.id)
        );
    }
    for (i, t) in plan.transitions().iter().enumerate() {
        let _ = writeln!(
            out,
            "  t{i} [shape=box, height=0.2, label={}, tooltip={}];",
            q(&t.label),
            q(&t.id)
        );
        for e in &t.inputs {
            let w = if e.weight > 1 {
                format!(" [label=\"{}\"]", e.weight)
            } else {
                String::new()
            };
            let _ = writeln!(out, "  p{} -> t{i}{w};", e.place);
        }
        for e in &t.outputs {
            let w = if e.weight > 1 {
                format!(" [label=\"{}\"]", e.weight)
            } else {
                String::new()
            };
            let _ = writeln!(out, "  t{i} -> p{}{w};", e.place);
        }
    }
    out.push_str("}\n");
    out
}
