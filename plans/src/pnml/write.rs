//! Writing PNML that JARP opens: every node gets `graphics` (position and
//! size) and a name with an offset, every arc an inscription. Text outside
//! ASCII is written as character references, so the ISO-8859-1 declaration
//! JARP expects is always true.

use std::fmt::Write;

use crate::model::{Plan, Position};

fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // XML 1.0 allows no other control character, not even as a reference: write its
            // visible stand-in (U+2400 + code, e.g. ␁), so the file stays well-formed.
            c if c.is_ascii_control() && !matches!(c, '\t' | '\n' | '\r') => {
                let _ = write!(out, "&#{};", 0x2400 + c as u32);
            }
            c if c.is_ascii() => out.push(c),
            c => {
                let _ = write!(out, "&#{};", c as u32);
            }
        }
    }
    out
}

/// A node without a position goes on a grid, in document order.
fn pos(p: Option<Position>, index: usize, row: usize) -> (i64, i64) {
    match p {
        Some(p) => (p.x.round() as i64, p.y.round() as i64),
        None => (
            60 + 80 * (index as i64 % 12),
            60 + 160 * (index as i64 / 12) + 80 * row as i64,
        ),
    }
}

fn node(out: &mut String, tag: &str, id: &str, xy: (i64, i64), size: (u32, u32), label: &str) {
    let _ = write!(
        out,
        "    <{tag} id=\"{}\">\n      <graphics>\n        <position x=\"{}\" y=\"{}\" />\n        <size width=\"{}\" height=\"{}\" />\n      </graphics>\n      <name>\n        <value>{}</value>\n        <graphics>\n          <offset x=\"0\" y=\"-20\" />\n        </graphics>\n      </name>\n",
        esc(id), xy.0, xy.1, size.0, size.1, esc(label)
    );
}

/// Writes a plan as PNML (JARP style), keeping ids, labels, markings,
/// weights, positions and comments. Arc ids are renumbered `a1...`.
pub fn write_pnml(plan: &Plan) -> String {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>\n\n<pnml>\n  <!--generator: petrel-plans-->\n");
    out.push_str(
        "  <net id=\"n1\" type=\"PTNet\">\n    <name>\n      <value>P/T net</value>\n    </name>\n",
    );
    for (i, p) in plan.places().iter().enumerate() {
        node(
            &mut out,
            "place",
            &p.id,
            pos(p.position, i, 0),
            (32, 32),
            &p.label,
        );
        let _ = write!(out, "      <initialMarking>\n        <value>{}</value>\n      </initialMarking>\n    </place>\n", p.initial);
    }
    for (i, t) in plan.transitions().iter().enumerate() {
        node(
            &mut out,
            "transition",
            &t.id,
            pos(t.position, i, 1),
            (48, 8),
            &t.label,
        );
        out.push_str("    </transition>\n");
    }
    let mut n = 0;
    for t in plan.transitions() {
        let arcs = t
            .inputs
            .iter()
            .map(|e| (e, true))
            .chain(t.outputs.iter().map(|e| (e, false)));
        for (e, input) in arcs {
            n += 1;
            let place = &plan.places()[e.place].id;
            let (s, d) = if input {
                (place, &t.id)
            } else {
                (&t.id, place)
            };
            let _ = write!(
                out,
                "    <arc id=\"a{n}\" source=\"{}\" target=\"{}\">\n      <inscription>\n        <value>{}</value>\n      </inscription>\n    </arc>\n",
                esc(s), esc(d), e.weight
            );
        }
    }
    for (i, c) in plan.comments().iter().enumerate() {
        let (x, y) = c.position.map_or((10, 10 + 20 * i as i64), |p| {
            (p.x.round() as i64, p.y.round() as i64)
        });
        let _ = write!(
            out,
            "    <comment id=\"c{}\">\n      <graphics>\n        <position x=\"{x}\" y=\"{y}\" />\n        <size width=\"120\" height=\"13\" />\n      </graphics>\n      <text>\n        <value>{}</value>\n      </text>\n    </comment>\n",
            i + 1,
            esc(&c.text)
        );
    }
    out.push_str("  </net>\n</pnml>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::esc;

    #[test]
    fn escapes_markup_non_ascii_and_control_characters() {
        assert_eq!(esc("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(esc("café"), "caf&#233;");
        // U+0001 and U+001B would make the file ill-formed XML; DEL (U+007F) is allowed.
        assert_eq!(esc("x\u{1}y\u{1b}\t"), "x&#9217;y&#9243;\t");
        let doc = format!("<n>{}</n>", esc("go\u{1}\u{7}<home>"));
        let parsed = roxmltree::Document::parse(&doc).expect("well-formed");
        assert_eq!(
            parsed.root_element().text(),
            Some("go\u{2401}\u{2407}<home>")
        );
    }
}
