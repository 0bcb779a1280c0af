//! PNML reading and writing, in both styles, and load errors.
mod common;

use common::*;
use petrel_plans::{load_plan, parse_pnml, write_pnml, Atom, CallKind, Cond, PlanError};

#[test]
fn editor_style_loads_with_positions_and_name_from_file() {
    let l = load_plan(&fixture("editor_three.pnml"), None).unwrap();
    let p = &l.plan;
    assert_eq!(p.name(), "editor_three");
    let labels: Vec<_> = p
        .places()
        .iter()
        .map(|p| (p.id.as_str(), p.label.as_str(), p.initial))
        .collect();
    assert_eq!(
        labels,
        [("p1", "azione1.ex", 0), ("p2", "goal", 0), ("p3", "P", 1)]
    );
    assert_eq!(p.places()[0].exec, Some(0));
    assert_eq!(p.executables()[0].name, "azione1");
    assert_eq!(p.goal_places(), [(1, 1)]);
    assert_eq!(
        p.places()[2].position.map(|q| (q.x, q.y)),
        Some((100.0, 60.0))
    );
    let t = &p.transitions()[1];
    assert_eq!((t.id.as_str(), t.label.as_str()), ("t2", "azione1.end"));
    assert_eq!(t.inputs[0].place, 0);
    assert_eq!(t.outputs[0].place, 1);
    assert_eq!(p.output_transitions(2), [0]);
}

#[test]
fn plan_name_comment_wins() {
    let l = load_plan(&fixture("editor_patrol.pnml"), None).unwrap();
    assert_eq!(l.plan.name(), "patrol_demo");
    assert_eq!(l.plan.conditions(), ["battery_low"]);
}

#[test]
fn generator_style_loads() {
    let l = load_plan(&fixture("generator_seq.pnml"), None).unwrap();
    let p = &l.plan;
    assert_eq!(p.name(), "generator_seq");
    assert_eq!(p.places().len(), 5);
    assert_eq!(
        p.places().iter().map(|p| p.initial).collect::<Vec<_>>(),
        [1, 0, 0, 0, 0]
    );
    assert!(p.transitions().iter().all(|t| t.inputs[0].weight == 1));
    let names: Vec<_> = p.executables().iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["goto_kitchen", "say_hello"]);
    assert_eq!(p.transitions()[1].guard, Cond::Atom(Atom::Finished(0)));
}

#[test]
fn pipe_values_and_weights() {
    let text = pnml(
        &[("a", 0), ("b", 0)],
        &["T"],
        &[("n0", "t0", 2), ("t0", "n1", 3)],
    )
    .replace("<value>2</value>", "<value>Default,2</value>");
    let p = parse_pnml(&text, "m.pnml", "m").unwrap();
    assert_eq!(p.transitions()[0].inputs[0].weight, 2);
    assert_eq!(p.transitions()[0].outputs[0].weight, 3);
}

#[test]
fn write_then_read_keeps_the_net() {
    for f in [
        "editor_three.pnml",
        "editor_patrol.pnml",
        "generator_seq.pnml",
        "parent.pnml",
    ] {
        let a = load_plan(&fixture(f), None).unwrap().plan;
        let text = write_pnml(&a);
        assert!(text.contains("<position x="), "{f}: JARP needs positions");
        let b = parse_pnml(&text, "again.pnml", "x").unwrap();
        assert_eq!(b.places().len(), a.places().len());
        for (x, y) in a.places().iter().zip(b.places()) {
            assert_eq!(
                (&x.id, &x.label, x.initial, x.goal),
                (&y.id, &y.label, y.initial, y.goal)
            );
            assert!(y.position.is_some());
        }
        assert_eq!(b.transitions().len(), a.transitions().len(), "{f}");
        for (x, y) in a.transitions().iter().zip(b.transitions()) {
            assert_eq!(
                (&x.id, &x.label, &x.inputs, &x.outputs, &x.guard),
                (&y.id, &y.label, &y.inputs, &y.outputs, &y.guard)
            );
        }
        if f == "editor_patrol.pnml" {
            assert_eq!(b.name(), "patrol_demo");
        }
    }
}

#[test]
fn writer_escapes_text() {
    let p = net(&[("a&amp;b &lt;é&gt;", 1)], &["[x] T"], &[("n0", "t0", 1)]);
    let text = write_pnml(&p);
    assert!(text.contains("a&amp;b &lt;&#233;&gt;"));
    assert_eq!(
        parse_pnml(&text, "e", "e").unwrap().places()[0].label,
        "a&b <é>"
    );
}

#[test]
fn bare_calls_resolve_to_execution_places() {
    let p = net(
        &[("P", 1), ("x.ex", 0), ("y.exec", 0), ("goal", 0)],
        &["start", "end", "[c] interrupt x.fail"],
        &[
            ("n0", "t0", 1),
            ("t0", "n1", 1),
            ("t0", "n2", 1),
            ("n1", "t1", 1),
            ("n2", "t1", 1),
            ("t1", "n3", 1),
            ("n1", "t2", 1),
            ("t2", "n3", 1),
        ],
    );
    let calls = |t: usize| -> Vec<(String, CallKind)> {
        p.transitions()[t]
            .calls
            .iter()
            .map(|c| (p.executables()[c.exec].name.clone(), c.kind))
            .collect()
    };
    assert_eq!(
        calls(0),
        [("x".into(), CallKind::Start), ("y".into(), CallKind::Start)]
    );
    assert_eq!(
        calls(1),
        [("x".into(), CallKind::End), ("y".into(), CallKind::End)]
    );
    assert_eq!(
        p.transitions()[1].guard,
        Cond::And(vec![
            Cond::Atom(Atom::Finished(0)),
            Cond::Atom(Atom::Finished(1))
        ])
    );
    assert_eq!(
        calls(2),
        [
            ("x".into(), CallKind::Interrupt),
            ("x".into(), CallKind::Fail)
        ]
    );
    assert!(p.transitions()[2].explicit_guard);
}

#[test]
fn default_guards() {
    let p = net(
        &[("a.ex", 1)],
        &["a.end", "a.fail", "a.end [ok]", "a.interrupt", "[] a.end"],
        &[],
    );
    let g: Vec<_> = p.transitions().iter().map(|t| t.guard.clone()).collect();
    assert_eq!(g[0], Cond::Atom(Atom::Finished(0)));
    assert_eq!(g[1], Cond::Atom(Atom::Failed(0)));
    assert_eq!(g[2], Cond::Atom(Atom::External(0)));
    assert_eq!(g[3], Cond::True);
    assert_eq!(g[4], Cond::True);
}

#[test]
fn guard_atoms_resolve() {
    let p = net(
        &[("a.ex", 1)],
        &["[or b.finished (not b.failed) (AND x y.z)]"],
        &[],
    );
    let b = p.executable("b").unwrap();
    assert_eq!(
        p.transitions()[0].guard,
        Cond::Or(vec![
            Cond::Atom(Atom::Finished(b)),
            Cond::Not(Box::new(Cond::Atom(Atom::Failed(b)))),
            Cond::And(vec![
                Cond::Atom(Atom::External(0)),
                Cond::Atom(Atom::External(1))
            ]),
        ])
    );
    assert_eq!(p.conditions(), ["x", "y.z"]);
}

#[test]
fn malformed_xml_names_file_line_and_column() {
    let e = load_plan(&fixture("malformed.pnml"), None).unwrap_err();
    assert!(matches!(e, PlanError::Xml { line: 6, .. }), "{e:?}");
    let msg = e.to_string();
    assert!(msg.contains("malformed.pnml:6:"), "{msg}");
    assert!(msg.contains("malformed XML"), "{msg}");
}

#[test]
fn arc_between_two_places() {
    let text = pnml(&[("a", 1), ("b", 0)], &[], &[("n0", "n1", 1)]);
    let msg = parse_pnml(&text, "two.pnml", "two")
        .unwrap_err()
        .to_string();
    assert_eq!(
        msg,
        "two.pnml:4:1: arc 'a0': joins two places ('n0' -> 'n1'); an arc must join a place and a transition"
    );
}

#[test]
fn arc_to_unknown_node() {
    let text = pnml(&[("a", 1)], &[], &[("n0", "zz", 1)]);
    let msg = parse_pnml(&text, "u.pnml", "u").unwrap_err().to_string();
    assert_eq!(
        msg,
        "u.pnml:3:1: arc 'a0': target 'zz' is not a place or transition id"
    );
}

#[test]
fn unparsable_guard_names_transition_and_label() {
    let text = pnml(&[("a", 1)], &["go.end [and x (or y]"], &[("n0", "t0", 1)]);
    let e = parse_pnml(&text, "g.pnml", "g").unwrap_err();
    assert!(
        matches!(&e, PlanError::Guard { id, label, .. } if id == "t0" && label == "go.end [and x (or y]")
    );
    assert_eq!(e.to_string(), "g.pnml:3:1: transition 't0' with label 'go.end [and x (or y]': bad guard: column 12: expected ')'");
}

#[test]
fn unknown_function_in_label() {
    let text = pnml(&[("a", 1)], &["go.stop"], &[("n0", "t0", 1)]);
    let msg = parse_pnml(&text, "f.pnml", "f").unwrap_err().to_string();
    assert_eq!(
        msg,
        "f.pnml:3:1: transition 't0' with label 'go.stop': unknown function 'stop' in 'go.stop'; expected start, end, interrupt, interr, resume, res or fail"
    );
}

#[test]
fn other_structural_errors() {
    let dup = pnml(&[("a", 1), ("b", 0)], &[], &[]).replace("\"n1\"", "\"n0\"");
    let e = parse_pnml(&dup, "d", "d").unwrap_err().to_string();
    assert!(
        e.contains("place 'n0' at line ") && e.contains("duplicate id: place 'n0' at line "),
        "{e}"
    );
    // An arc id taken twice (it was read as a second arc), a second net (it was ignored) and
    // another format's namespace (it was read as PNML) are refused too.
    let arcs = pnml(
        &[("a", 1)],
        &["go.start"],
        &[("n0", "t0", 1), ("n0", "t0", 1)],
    )
    .replace("\"a1\"", "\"a0\"");
    let e = parse_pnml(&arcs, "a", "a").unwrap_err().to_string();
    assert!(e.contains("duplicate id: arc 'a0'"), "{e}");
    let two = pnml(&[("a", 1)], &[], &[]).replace("</pnml>", "<net id=\"m\"/></pnml>");
    let e = parse_pnml(&two, "n", "n").unwrap_err().to_string();
    assert!(e.contains("a second <net>"), "{e}");
    let other = "<pnml xmlns=\"http://example.com/not-pnml\"><net id=\"n\"/></pnml>";
    let e = parse_pnml(other, "x", "x").unwrap_err().to_string();
    assert!(
        e.contains("namespace 'http://example.com/not-pnml' is not PNML's"),
        "{e}"
    );
    let bad = pnml(&[("a", 1)], &[], &[]).replace("<value>1</value>", "<value>lots</value>");
    let e = parse_pnml(&bad, "m", "m").unwrap_err().to_string();
    // At the place's line, like every PNML error.
    let line = bad.lines().position(|l| l.contains("<place")).unwrap() + 1;
    assert!(
        e.starts_with(&format!("m:{line}:"))
            && e.contains("place 'n0': initial marking 'lots' is not a number"),
        "{e}"
    );
    assert!(parse_pnml("<foo/>", "r", "r")
        .unwrap_err()
        .to_string()
        .contains("expected the root element <pnml>"));
    assert!(parse_pnml("<pnml/>", "r", "r")
        .unwrap_err()
        .to_string()
        .contains("no <net> element"));
    let e = load_plan(&fixture("nope.pnml"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("nope.pnml: cannot read"), "{e}");
}
