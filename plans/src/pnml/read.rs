//! Reading PNML.
//!
//! Only `place`, `transition`, `arc` and the JARP `comment` children of the
//! first `net` (or of its `page`s) matter; `graphics` is read for positions,
//! `toolspecific` is ignored. Editor style (`p1`/`t1` ids, explicit zero
//! markings and weights) and generator style (`n0...` ids, no
//! `initialMarking` for empty places, arcs without inscription) are both
//! accepted; values may use the PIPE form `Default,N`.

use roxmltree::{Document, Node};

use crate::build::{ArcEnd, RawArc, RawNet, RawPlace, RawTransition};
use crate::error::PlanError;
use crate::model::{Comment, Plan, Position};

/// Parses PNML text into a plan.
///
/// `file` names the source in errors; `default_name` is the plan name when
/// no `PLAN NAME:` comment gives one (the loader passes the file name up to
/// its first dot). Sub-plans are not resolved here (see [`crate::load_plan`]).
pub fn parse_pnml(text: &str, file: &str, default_name: &str) -> Result<Plan, PlanError> {
    super::depth::check_depth(text, file)?;
    let doc = Document::parse(text).map_err(|e| {
        let pos = e.pos();
        PlanError::Xml {
            file: file.to_string(),
            line: pos.row,
            column: pos.col,
            message: e.to_string(),
        }
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "pnml" {
        return Err(pnml_error(
            file,
            root,
            root.tag_name().name(),
            "expected the root element <pnml>".into(),
        ));
    }
    // PNML's namespace, if the file names one (editors such as PIPE and JARP name none).
    if let Some(ns) = root.tag_name().namespace() {
        if !ns.starts_with("http://www.pnml.org/") {
            return Err(pnml_error(
                file,
                root,
                "pnml",
                format!("namespace '{ns}' is not PNML's (http://www.pnml.org/version-2009/grammar/pnml)"),
            ));
        }
    }
    let mut nets = children(root, "net");
    let net = nets
        .next()
        .ok_or_else(|| pnml_error(file, root, "pnml", "no <net> element".into()))?;
    if let Some(second) = nets.next() {
        return Err(pnml_error(file, second, "net", "a second <net>: a plan file holds one net (put each plan in a file of its own; a sub-plan is an action named after its file)".into()));
    }
    let mut raw = RawNet {
        name: default_name.to_string(),
        ..RawNet::default()
    };
    let mut ids = Ids::default();
    read_nodes(net, &mut raw, file, &mut ids)?;
    ids.check_arcs(&doc, file)?;
    for c in &raw.comments {
        if let Some(name) = c.text.trim().strip_prefix("PLAN NAME:") {
            raw.name = name.trim().to_string();
            break;
        }
    }
    Plan::build(raw, file).map_err(|e| {
        // The builder knows no lines: the node its error names is found here.
        e.located(|id| {
            let node =
                (doc.descendants()).find(|n| n.is_element() && n.attribute("id") == Some(id))?;
            Some(place_of(node))
        })
    })
}

/// An error about the element `n` (`element` says which: `arc 'a3'`), at its line and column.
fn pnml_error(file: &str, n: Node, element: &str, message: String) -> PlanError {
    let (line, column) = place_of(n);
    PlanError::Pnml {
        file: file.to_string(),
        line,
        column,
        element: element.to_string(),
        message,
    }
}

/// Reads the nodes of `net` and of its pages, in document order. Pages may nest; they are
/// walked with an explicit stack, not by recursion.
fn read_nodes(net: Node, raw: &mut RawNet, file: &str, ids: &mut Ids) -> Result<(), PlanError> {
    let mut stack = vec![net.children()];
    while let Some(children) = stack.last_mut() {
        match children.next() {
            None => {
                stack.pop();
            }
            Some(n) if n.tag_name().name() == "page" => stack.push(n.children()),
            Some(n) if n.is_element() => {
                ids.note(n, file)?;
                read_node(n, raw, file)?
            }
            Some(_) => {}
        }
    }
    Ok(())
}

/// The ids of a net's nodes and arcs with where they are written, so that a duplicate id or an
/// arc to nowhere is reported at its line (the plan builder knows no lines). Positions are
/// byte offsets, turned into lines only for an error: finding a line walks the text from its
/// start, which for every node of a 100,000-place net took minutes.
#[derive(Default)]
struct Ids {
    /// Node and arc ids: kind and offset of the first.
    seen: std::collections::HashMap<String, (&'static str, usize)>,
    /// Arcs: id, source, target, offset.
    arcs: Vec<(String, String, String, usize)>,
}

impl Ids {
    fn note(&mut self, n: Node, file: &str) -> Result<(), PlanError> {
        let kind = match n.tag_name().name() {
            "place" => "place",
            "transition" => "transition",
            "arc" => "arc",
            _ => return Ok(()),
        };
        let Some(id) = n.attribute("id").filter(|id| !id.is_empty()) else {
            return Ok(()); // reported by `read_node`
        };
        let at = n.range().start;
        if let Some((first, first_at)) = self.seen.get(id) {
            let first_line = n.document().text_pos_at(*first_at).row;
            return Err(pnml_error(
                file,
                n,
                &format!("{kind} '{id}'"),
                format!("duplicate id: {first} '{id}' at line {first_line} has it already"),
            ));
        }
        self.seen.insert(id.to_string(), (kind, at));
        if kind == "arc" {
            let end = |a| n.attribute(a).unwrap_or("").to_string();
            self.arcs
                .push((id.to_string(), end("source"), end("target"), at));
        }
        Ok(())
    }

    /// Every arc joins a place and a transition of the net.
    fn check_arcs(&self, doc: &Document, file: &str) -> Result<(), PlanError> {
        for (id, source, target, at) in &self.arcs {
            for (which, end) in [("source", source), ("target", target)] {
                let node = self.seen.get(end.as_str()).map(|(kind, _)| *kind);
                if !matches!(node, Some("place" | "transition")) && !end.is_empty() {
                    let pos = doc.text_pos_at(*at);
                    return Err(PlanError::Pnml {
                        file: file.to_string(),
                        line: pos.row,
                        column: pos.col,
                        element: format!("arc '{id}'"),
                        message: format!("{which} '{end}' is not a place or transition id"),
                    });
                }
            }
        }
        Ok(())
    }
}

/// Reads one place, transition, arc or comment (other elements are ignored).
fn read_node(n: Node, raw: &mut RawNet, file: &str) -> Result<(), PlanError> {
    {
        let id = || n.attribute("id").unwrap_or("").to_string();
        let need_id = |kind: &str| -> Result<String, PlanError> {
            match n.attribute("id") {
                Some(id) if !id.is_empty() => Ok(id.to_string()),
                _ => Err(pnml_error(file, n, kind, "missing 'id' attribute".into())),
            }
        };
        match n.tag_name().name() {
            "place" => {
                let id = need_id("place")?;
                let initial = match value(n, &["initialMarking", "value"]) {
                    Some(v) => count(&v).ok_or_else(|| {
                        let message = format!("initial marking '{v}' {}", not_a_count(&v));
                        pnml_error(file, n, &format!("place '{id}'"), message)
                    })?,
                    None => 0,
                };
                let label = value(n, &["name", "value"]).unwrap_or_default();
                raw.places.push(RawPlace {
                    id,
                    label,
                    initial,
                    position: position(n),
                });
            }
            "transition" => {
                let id = need_id("transition")?;
                let label = value(n, &["name", "value"]).unwrap_or_default();
                raw.transitions.push(RawTransition {
                    id,
                    label,
                    position: position(n),
                });
            }
            "arc" => {
                let element = format!("arc '{}'", id());
                let attr = |a: &str| {
                    n.attribute(a).map(str::to_string).ok_or_else(|| {
                        pnml_error(file, n, &element, format!("missing '{a}' attribute"))
                    })
                };
                let (source, target) = (attr("source")?, attr("target")?);
                let weight = match value(n, &["inscription", "value"]) {
                    Some(v) => count(&v).filter(|w| *w > 0).ok_or_else(|| {
                        let message = match count(&v) {
                            Some(_) => format!(
                                "weight '{v}' is not a positive number (expected N or Default,N)"
                            ),
                            None => format!("weight '{v}' {}", not_a_count(&v)),
                        };
                        pnml_error(file, n, &element, message)
                    })?,
                    None => 1,
                };
                let arc = RawArc {
                    id: Some(raw.name(&id())),
                    source: ArcEnd::Named(raw.name(&source)),
                    target: ArcEnd::Named(raw.name(&target)),
                    weight,
                };
                raw.arcs.push(arc);
            }
            "comment" => {
                let text = value(n, &["text", "value"]).unwrap_or_default();
                raw.comments.push(Comment {
                    text,
                    position: position(n),
                });
            }
            _ => {}
        }
    }
    Ok(())
}

/// The line and column where element `n` starts.
fn place_of(n: Node) -> (u32, u32) {
    let pos = n.document().text_pos_at(n.range().start);
    (pos.row, pos.col)
}

fn children<'a, 'i>(n: Node<'a, 'i>, tag: &'static str) -> impl Iterator<Item = Node<'a, 'i>> {
    n.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// The text at a child path, e.g. `name/value`; standard PNML's `text`
/// stands for PNP's `value`.
fn value(n: Node, path: &[&'static str; 2]) -> Option<String> {
    let parent = children(n, path[0]).next()?;
    let leaf = children(parent, path[1])
        .next()
        .or_else(|| children(parent, "text").next())?;
    Some(leaf.text().unwrap_or("").to_string())
}

/// `N` or PIPE's `Default,N`.
fn count(v: &str) -> Option<u32> {
    let v = v.trim();
    let v = v.rsplit_once(',').map_or(v, |(_, n)| n.trim());
    if v.is_empty() {
        return Some(0);
    }
    v.parse().ok()
}

/// Why `v`, which [`count`] refused, is not a count: too large, or no number at all.
fn not_a_count(v: &str) -> String {
    let digits = v
        .trim()
        .rsplit_once(',')
        .map_or(v.trim(), |(_, n)| n.trim());
    match !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
        true => format!("is too large (at most {})", u32::MAX),
        false => "is not a number (expected N or Default,N)".to_string(),
    }
}

fn position(n: Node) -> Option<Position> {
    let p = children(n, "graphics")
        .next()
        .and_then(|g| children(g, "position").next())?;
    let x = p.attribute("x")?.trim().parse().ok()?;
    let y = p.attribute("y")?.trim().parse().ok()?;
    Some(Position { x, y })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts() {
        assert_eq!(count("1"), Some(1));
        assert_eq!(count(" Default,2 "), Some(2));
        assert_eq!(count(""), Some(0));
        assert_eq!(count("x"), None);
        assert_eq!(
            not_a_count("4294967296"),
            "is too large (at most 4294967295)"
        );
        assert_eq!(
            not_a_count("Default,99999999999"),
            "is too large (at most 4294967295)"
        );
        assert!(not_a_count("-1").starts_with("is not a number"));
    }

    #[test]
    fn generator_style_and_pages() {
        let text = r#"<pnml><net id="x"><page id="pg">
            <place id="n0"><name><value>init</value></name><initialMarking><value>Default,1</value></initialMarking></place>
            <transition id="n1"><name><value>a.start</value></name></transition>
            <place id="n2"><name><text>a.exec</text></name></place>
            <arc id="n3" source="n0" target="n1"/><arc id="n4" source="n1" target="n2"><inscription><value>2</value></inscription></arc>
            </page></net></pnml>"#;
        let p = parse_pnml(text, "mem", "gen").unwrap();
        assert_eq!(p.name(), "gen");
        assert_eq!(p.places()[0].initial, 1);
        assert_eq!(p.places()[1].initial, 0);
        assert_eq!(p.places()[1].label, "a.exec");
        assert_eq!(p.transitions()[0].outputs[0].weight, 2);
    }
}
