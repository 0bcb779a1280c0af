//! The text plan language: net structure of each construct, and errors.
mod common;

use common::*;
use petrel_plans::{
    compile_text, compile_to_pnml, load_plan, parse_pnml, simulate, Plan, PlanStatus, Script,
};

fn compile(src: &str, rules: Option<&str>) -> Plan {
    compile_text(src, "t.plan", "t", rules.map(|r| (r, "t.er"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Places as `label(tokens)`, transitions as `label: inputs -> outputs`.
fn structure(p: &Plan) -> (Vec<String>, Vec<String>) {
    let places = p
        .places()
        .iter()
        .map(|pl| format!("{}({})", pl.label, pl.initial))
        .collect();
    let name = |e: &petrel_plans::Edge| p.places()[e.place].label.clone();
    let trans = p
        .transitions()
        .iter()
        .map(|t| {
            let ins: Vec<_> = t.inputs.iter().map(name).collect();
            let outs: Vec<_> = t.outputs.iter().map(name).collect();
            format!("{}: {} -> {}", t.label, ins.join(","), outs.join(","))
        })
        .collect();
    (places, trans)
}

fn error(src: &str, rules: Option<&str>) -> String {
    compile_text(src, "t.plan", "t", rules.map(|r| (r, "t.er")))
        .unwrap_err()
        .to_string()
}

#[test]
fn linear() {
    let (places, trans) = structure(&compile("a; b_1_2; c", None));
    assert_eq!(
        places,
        [
            "init(1)",
            "a.exec(0)",
            "X2(0)",
            "b_1_2.exec(0)",
            "X4(0)",
            "c.exec(0)",
            "goal(0)"
        ]
    );
    assert_eq!(
        trans,
        [
            "a.start: init -> a.exec",
            "a.end: a.exec -> X2",
            "b_1_2.start: X2 -> b_1_2.exec",
            "b_1_2.end: b_1_2.exec -> X4",
            "c.start: X4 -> c.exec",
            "c.end: c.exec -> goal",
        ]
    );
}

#[test]
fn timed_action() {
    let (places, trans) = structure(&compile("a|30; b", None));
    assert_eq!(
        places[..8],
        [
            "init(1)",
            "X1(0)",
            "X2(0)",
            "a.exec(0)",
            "X4(0)",
            "wait_30.exec(0)",
            "X6(0)",
            "X7(0)"
        ]
    );
    assert_eq!(
        trans,
        [
            "[]: init -> X1,X2",
            "a.start: X1 -> a.exec",
            "a.end: a.exec -> X4",
            "wait_30.start: X2 -> wait_30.exec",
            "wait_30.end: wait_30.exec -> X6",
            "wait_30.interrupt []: wait_30.exec,X4 -> X7",
            "a.interrupt []: a.exec,X6 -> X7",
            "[]: X4,X6 -> X7",
            "b.start: X7 -> b.exec",
            "b.end: b.exec -> goal",
        ]
    );
}

#[test]
fn timed_action_whichever_finishes_first_interrupts_the_other() {
    let p = compile("a|30; b", None);
    let run = |script: &str| {
        let mut out = Vec::new();
        simulate(&p, &Script::parse(script, "s").unwrap(), 100, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    };
    let fast = run("finish a 1\nfinish wait_30 5");
    assert!(
        fast.contains(r#""calls":["a.end"]"#) && fast.contains(r#""calls":["wait_30.interrupt"]"#),
        "{fast}"
    );
    let slow = run("finish a 9\nfinish wait_30 3");
    assert!(
        slow.contains(r#""calls":["wait_30.end"]"#) && slow.contains(r#""calls":["a.interrupt"]"#),
        "{slow}"
    );
    assert!(
        slow.ends_with("{\"result\":\"goal\",\"step\":9}\n"),
        "{slow}"
    );
}

#[test]
fn conditional() {
    let (places, trans) = structure(&compile("A_5;\n< phi ? B; C : (not phi) ? D >; E", None));
    assert_eq!(places.last().unwrap(), "goal(0)");
    assert_eq!(
        trans,
        [
            "A_5.start: init -> A_5.exec",
            "A_5.end: A_5.exec -> X2",
            "[phi]: X2 -> X3",
            "B.start: X3 -> B.exec",
            "B.end: B.exec -> X5",
            "C.start: X5 -> C.exec",
            "C.end: C.exec -> X7",
            "[(not phi)]: X2 -> X8",
            "D.start: X8 -> D.exec",
            "D.end: D.exec -> X10",
            " : X7 -> X11",
            " : X10 -> X11",
            "E.start: X11 -> E.exec",
            "E.end: E.exec -> goal",
        ]
    );
}

#[test]
fn blocks_parallel_labels_and_jumps() {
    let (_, trans) = structure(&compile(
        "a; LABEL_top; { b }; < again ? GOTO_LABEL_top : done ? { c } || { d; e } >",
        None,
    ));
    assert_eq!(
        trans,
        [
            "a.start: init -> a.exec",
            "a.end: a.exec -> X2",
            "b.start: X2 -> b.exec",
            "b.end: b.exec -> X4",
            "[again]: X4 -> X5",
            " : X5 -> X2",
            "[done]: X4 -> X6",
            "[]: X6 -> X7,X8",
            "c.start: X7 -> c.exec",
            "c.end: c.exec -> X10",
            "d.start: X8 -> d.exec",
            "d.end: d.exec -> X12",
            "e.start: X12 -> e.exec",
            "e.end: e.exec -> X14",
            "[]: X10,X14 -> X15",
            " : X15 -> goal",
        ]
    );
}

#[test]
fn timed_action_inside_a_conditional_is_not_parallel() {
    let (_, trans) = structure(&compile("< c ? a|5 : (not c) ? b >", None));
    assert!(
        trans.contains(&"wait_5.interrupt []: wait_5.exec,X5 -> X8".to_string()),
        "{trans:#?}"
    );
}

#[test]
fn plan_jumps_restart_and_fail() {
    let p = compile("a; < ok ? b : (not ok) ? fail_plan >", None);
    let (places, trans) = structure(&p);
    assert!(places.contains(&"fail(0)".to_string()));
    assert!(trans.contains(&" : X6 -> fail".to_string()), "{trans:#?}");
    assert_eq!(p.fail_places().len(), 1);
    let (_, trans) = structure(&compile("a; restart_plan", None));
    assert_eq!(trans.last().unwrap(), " : X2 -> init");
}

#[test]
fn execution_rules() {
    let rules = "# rules\n*if* (and personhere closetotarget) *during* goto *do* skip_action\n\
                 *if* (and personhere (not closetotarget)) *during* goto *do* say_away; wait_free; restart_action\n\
                 *if* action_failed *during* say *do* restart_plan\n\
                 *if* lost *during* say *do* fail_plan\n\
                 *if* done *during* goto_home *do* goal\n";
    let (_, trans) = structure(&compile("goto_printer; say_hello; goto_home", Some(rules)));
    assert_eq!(
        trans[6..],
        [
            "goto_printer.interrupt [(and personhere closetotarget)]: goto_printer.exec -> X7",
            " : X7 -> X2",
            "goto_home.interrupt [(and personhere closetotarget)]: goto_home.exec -> X8",
            " : X8 -> goal",
            "goto_printer.interrupt [(and personhere (not closetotarget))]: goto_printer.exec -> X9",
            "say_away.start: X9 -> say_away.exec",
            "say_away.end: say_away.exec -> X11",
            "wait_free.start: X11 -> wait_free.exec",
            "wait_free.end: wait_free.exec -> X13",
            " : X13 -> init",
            "goto_home.interrupt [(and personhere (not closetotarget))]: goto_home.exec -> X14",
            "say_away.start: X14 -> say_away.exec",
            "say_away.end: say_away.exec -> X16",
            "wait_free.start: X16 -> wait_free.exec",
            "wait_free.end: wait_free.exec -> X18",
            " : X18 -> X4",
            "say_hello.fail: say_hello.exec -> X19",
            " : X19 -> init",
            "say_hello.interrupt [lost]: say_hello.exec -> X20",
            " : X20 -> fail",
            "goto_home.interrupt [done]: goto_home.exec -> X22",
            " : X22 -> goal",
        ]
    );
    // A rule for an action the plan does not have (a typo) is refused where it names it.
    let typo = error(
        "goto_A; goto_B",
        Some("*if* blocked *during* goto *do* skip_action\n*if* action_failed *during*  goot *do* fail_plan\n"),
    );
    assert_eq!(
        typo,
        "t.er:2:30: `*during* goot`: the plan has no action `goot` (nor `goot_...`); its actions: goto_A, goto_B"
    );
    // Each rule applies to every occurrence it names: a net that rules would grow past a
    // million transitions is refused at the rule that passes it (a thousand rules over a
    // 20,000-step plan ran out of memory). 20,000 actions make 40,000 transitions, and each
    // rule adds 4 per occurrence: the 13th passes.
    let plan = (0..20_000)
        .map(|i| format!("a_{i}"))
        .collect::<Vec<_>>()
        .join("; ");
    let rule = "*if* c *during* a *do* b; skip_action\n";
    let refused = error(&plan, Some(&rule.repeat(20)));
    assert!(
        refused.starts_with("t.er:13:17: the net would pass 1000000 transitions with this rule (20000 occurrences of the actions it names, 4 transitions each, after 1000000 already)"),
        "{refused}"
    );
    let twelve = compile(&plan, Some(&rule.repeat(12)));
    assert_eq!(twelve.transitions().len(), 1_000_000);
}

#[test]
fn inline_rule() {
    let (_, trans) = structure(&compile("a; b ! *if* stuck *do* c; skip_action !; d", None));
    assert_eq!(
        trans[6..],
        [
            "b.interrupt [stuck]: b.exec -> X7",
            "c.start: X7 -> c.exec",
            "c.end: c.exec -> X9",
            " : X9 -> X4"
        ]
    );
}

#[test]
fn files_load_and_compile_to_jarp_pnml() {
    let l = load_plan(&fixture("delivery.plan"), Some(&fixture("delivery.er"))).unwrap();
    assert_eq!(l.plan.name(), "delivery");
    assert!(l
        .plan
        .transitions()
        .iter()
        .any(|t| t.label == "goto_desk.interrupt [blocked]"));
    assert!(l
        .plan
        .transitions()
        .iter()
        .any(|t| t.label == "goto_home.interrupt [(and personhere closetotarget)]"));
    let pnml = compile_to_pnml(&fixture("delivery.plan"), Some(&fixture("delivery.er"))).unwrap();
    let back = parse_pnml(&pnml, "delivery.pnml", "delivery").unwrap();
    assert_eq!(back.transitions().len(), l.plan.transitions().len());
    // Laid out left to right: init first column, goal further right.
    let x = |label: &str| {
        back.places()[back.place_by_label(label).unwrap()]
            .position
            .unwrap()
            .x
    };
    assert!(x("init") < x("goto_desk.exec") && x("goto_desk.exec") < x("goal"));
    let mut out = Vec::new();
    // With the default 2 steps both branches of the timed action would end in
    // the same step and block (PNPgen's structure); let the timer be slower.
    let status = simulate(
        &back,
        &Script::parse("finish wait_60 10", "s").unwrap(),
        100,
        &mut out,
    )
    .unwrap();
    assert_eq!(status, PlanStatus::Goal);
}

#[test]
fn syntax_errors_have_line_and_column() {
    assert_eq!(
        error("a;\nb c", None),
        "t.plan:2:3: unexpected 'c'; expected ';' or the end of the plan"
    );
    assert_eq!(
        error("a|x", None),
        "t.plan:1:3: unexpected 'x'; expected a whole number of seconds after '|' (0 to 4294967295)"
    );
    assert_eq!(
        error("{ a; b", None),
        "t.plan:1:7: unexpected end of input; expected '}' closing the '{' at 1:1"
    );
    assert_eq!(
        error("a; < (and x ? b >", None),
        "t.plan:1:13: bad condition: expected ')'"
    );
    assert_eq!(
        error("a; < x ? b ; c", None),
        "t.plan:1:15: unexpected end of input; expected ';', ':' or '>'"
    );
    assert_eq!(
        error("a; GOTO_LABEL_nowhere", None),
        "t.plan:1:4: no LABEL_nowhere in the plan"
    );
    assert_eq!(
        error("a; GOTO_LABEL_x; b", None),
        "t.plan:1:18: unreachable: only a LABEL_x may follow a jump"
    );
    assert_eq!(
        error("  \n# nothing\n", None),
        "t.plan:3:1: empty plan; expected at least one action"
    );
    assert_eq!(error("a; $", None), "t.plan:1:4: unexpected character '$'");
    assert_eq!(
        error("a; LABEL_x; b; LABEL_x", None),
        "t.plan:1:16: label 'LABEL_x' defined twice"
    );
    // A repeated block is written out: a label in it would be defined once per repeat.
    assert_eq!(
        error("a; { b; { LABEL_x; d } } * 3; GOTO_LABEL_x", None),
        "t.plan:1:11: label 'LABEL_x' is inside '{ ... } * 3', which writes the block out 3 times: the label would be defined 3 times (put it before the block, or loop with a label and a goto)"
    );
    // Once is not a repeat: compiles (a failure panics).
    compile("a; { LABEL_x; b } * 1; GOTO_LABEL_x", None);
    assert_eq!(
        error("a", Some("*if* x *during* a *do* b; skip_action; c")),
        "t.er:1:40: 'c' follows the end of the recovery"
    );
    assert_eq!(
        error("a ! *if* x *do* b", None),
        "t.plan:1:3: inline rule without its closing '!'"
    );
}

#[test]
fn a_block_repeats_n_times() {
    let p = compile("{ a; b } * 2; c", None);
    let (_, trans) = structure(&p);
    let starts: Vec<&String> = trans.iter().filter(|t| t.contains(".start")).collect();
    assert_eq!(starts.len(), 5, "{trans:?}");
    let glued = compile("{ a }*3", None);
    assert_eq!(
        structure(&glued)
            .1
            .iter()
            .filter(|t| t.starts_with("a.start"))
            .count(),
        3
    );
    assert!(error("{ a } * 0", None).contains("expected a number of times from 1 to 1000"));
    assert!(error("{ a } * x", None).contains("'x'"));
    // An empty block was a plan that reached its goal doing nothing.
    assert_eq!(
        error("a; { }; b", None),
        "t.plan:1:4: empty block '{ }'; expected at least one action inside"
    );
    // Nested repeats multiply: refused at the '*' that goes over, before anything is built.
    let huge = error("{ { { say_a } * 1000 } * 1000 } * 1000", None);
    assert!(
        huge.contains("t.plan:1:26")
            && huge.contains("writes out 1000000 steps; a plan may have at most 100000"),
        "{huge}"
    );
    // Written out, or in repeats that are each under the limit, a plan is counted whole: a
    // 17-million-action plan ran the analysis out of memory.
    let long = vec!["a"; 100_001].join("; ");
    let refused = error(&long, None);
    let column = 100_000 * 3 + 1;
    assert!(
        refused.starts_with(&format!("t.plan:1:{column}: the plan passes 100000 steps")),
        "{refused}"
    );
    let repeats = vec!["{ a; b } * 1000"; 51].join("; ");
    let refused = error(&repeats, None);
    assert!(
        refused.contains("the plan passes 100000 steps")
            && refused.contains("split it into sub-plans"),
        "{refused}"
    );
    // At the limit, it compiles.
    let at_limit = compile(&vec!["a"; 100_000].join("; "), None);
    assert_eq!(at_limit.transitions().len(), 200_000);
    assert_eq!(
        structure(&compile("{ { a } * 100 } * 100", None))
            .1
            .iter()
            .filter(|t| t.starts_with("a.start"))
            .count(),
        10_000
    );
}
