//! Structured fuzzing (proptest): generators that build inputs the way users write them —
//! nesting, sizes, unicode, numbers at the edges — for the expression language (parsed,
//! type-checked and evaluated over property values such as NaN, ±inf and the extremes),
//! text plans (compiled, checked and simulated) and agent configs (parsed and built). Each
//! must answer with a value or an error, never a panic.
//!
//! `cargo test` runs a fixed number of cases; `cargo test --test properties -- --ignored` runs
//! a long campaign (`PROPTEST_CASES` overrides both).

use std::sync::Arc;
use std::time::Duration;

use petrel::actors::expr::{never_true, parse, ExprSet, Ty, TypeEnv};
use petrel::actors::{AnyValue, ConfigFile, Pose2, TypeInfo};
use proptest::prelude::*;
use proptest::test_runner::Config;

/// Numbers as users (and broken generators) write them, edges first.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("0".to_string()),
        Just("-0.0".to_string()),
        Just("1e308".to_string()),
        Just("-1e308".to_string()),
        Just("1e-308".to_string()),
        Just("1e400".to_string()),
        Just("9223372036854775807".to_string()),
        Just("99999999999999999999999".to_string()),
        Just("500ms".to_string()),
        Just("1e20s".to_string()),
        any::<i32>().prop_map(|n| n.to_string()),
        any::<f64>()
            .prop_filter("finite", |x| x.is_finite())
            .prop_map(|x| format!("{x:?}")),
    ]
}

/// Leaves of an expression: numbers, booleans, strings (unicode), properties of every type.
fn leaf() -> impl Strategy<Value = String> {
    prop_oneof![
        number(),
        Just("true".to_string()),
        Just("false".to_string()),
        "\\PC{0,6}".prop_map(|s| format!("{:?}", s)),
        Just("a/out/x".to_string()),
        Just("a/out/n".to_string()),
        Just("b/out/ok".to_string()),
        Just("m/params/name".to_string()),
        Just("s/out/list".to_string()),
        Just("loc/out/pose.theta".to_string()),
        Just("loc/out/pose".to_string()),
        Just("petrel://r1/a/out/x".to_string()),
        Just("elapsed()".to_string()),
    ]
}

/// Expressions nested up to a few levels, over every operator and function.
fn expression() -> impl Strategy<Value = String> {
    leaf().prop_recursive(6, 64, 3, |inner| {
        let op = prop_oneof![
            Just("+"),
            Just("-"),
            Just("*"),
            Just("/"),
            Just("<"),
            Just("<="),
            Just(">"),
            Just("=="),
            Just("!="),
            Just(" and "),
            Just(" or "),
            Just(" && "),
        ];
        prop_oneof![
            (inner.clone(), op, inner.clone()).prop_map(|(a, op, b)| format!("{a} {op} {b}")),
            inner.clone().prop_map(|a| format!("({a})")),
            inner.clone().prop_map(|a| format!("-{a}")),
            inner.clone().prop_map(|a| format!("not {a}")),
            inner.clone().prop_map(|a| format!("abs({a})")),
            inner.clone().prop_map(|a| format!("len({a})")),
            (inner.clone(), number()).prop_map(|(a, d)| format!("held({a}, {d})")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("min({a}, {b})")),
            prop::collection::vec(inner.clone(), 1..4)
                .prop_map(|xs| format!("max({})", xs.join(", "))),
            (inner.clone(), inner.clone(), inner.clone())
                .prop_map(|(a, b, c)| format!("clamp({a}, {b}, {c})")),
            Just("age(a/out/x)".to_string()),
        ]
    })
}

/// Property values at the edges of their types.
fn edge_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE),
        Just(0.0),
        Just(-0.0),
        any::<f64>(),
    ]
}

fn env() -> TypeEnv {
    let mut env = TypeEnv::new();
    env.insert("a/out/x", Ty::Num)
        .insert("a/out/n", Ty::Num)
        .insert("b/out/ok", Ty::Bool)
        .insert("m/params/name", Ty::Str)
        .insert("petrel://r1/a/out/x", Ty::Num);
    let pose: AnyValue = Arc::new(Pose2::default());
    env.insert_property("loc/out/pose", TypeInfo::of::<Pose2>(), &pose);
    let list: AnyValue = Arc::new(vec![1.0]);
    env.insert_property("s/out/list", TypeInfo::of::<Vec<f64>>(), &list);
    env
}

/// Parses, checks and evaluates `src` with properties set to `x` (numbers), `n` (an integer)
/// and lists holding `x`, at two instants; any answer is fine, a panic is not.
fn evaluate(src: &str, x: f64, n: i64, secs: u64) {
    if let Ok(ast) = parse(src) {
        let _ = never_true(src, &ast);
    }
    let mut set = ExprSet::new();
    let Ok(id) = set.add(src, &env(), None) else {
        return;
    };
    let t0 = tokio::time::Instant::now();
    let values: [(&str, TypeInfo, AnyValue); 7] = [
        ("a/out/x", TypeInfo::of::<f64>(), Arc::new(x)),
        ("petrel://r1/a/out/x", TypeInfo::of::<f64>(), Arc::new(x)),
        ("a/out/n", TypeInfo::of::<i64>(), Arc::new(n)),
        ("b/out/ok", TypeInfo::of::<bool>(), Arc::new(x > 0.0)),
        (
            "m/params/name",
            TypeInfo::of::<String>(),
            Arc::new("dock".to_string()),
        ),
        (
            "loc/out/pose",
            TypeInfo::of::<Pose2>(),
            Arc::new(Pose2::new(x, x, x)),
        ),
        (
            "s/out/list",
            TypeInfo::of::<Vec<f64>>(),
            Arc::new(vec![x, -x]),
        ),
    ];
    for (path, info, value) in &values {
        if let Some(p) = set.property(path) {
            set.update(p, *info, value, t0);
        }
    }
    set.evaluate(t0);
    set.evaluate(t0 + Duration::from_secs(secs));
    let _ = set.value(id);
    let _ = set.next_deadline();
}

/// Text plans: actions, timed actions, sequences, blocks, conditionals, labels and jumps.
fn text_plan() -> impl Strategy<Value = String> {
    let action = prop_oneof![
        "[a-c]{1,2}(_[0-9])?".prop_map(|s| s.to_string()),
        "[a-c]\\|[0-9]{1,3}".prop_map(|s| s.to_string()),
        Just("robot_1#goto_8_2".to_string()),
        Just("wait_5".to_string()),
        Just("GOTO_LABEL_top".to_string()),
        Just("LABEL_top".to_string()),
    ];
    action.prop_recursive(5, 48, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..5).prop_map(|xs| xs.join("; ")),
            inner.clone().prop_map(|a| format!("{{ {a} }}")),
            (inner.clone(), 1u32..4).prop_map(|(a, n)| format!("{{ {a} }} * {n}")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("<c ? {a} : {b}>")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("{a} || {b}")),
        ]
    })
}

/// Agent configs with numbers at the edges in values, capacities and supervision.
fn config() -> impl Strategy<Value = String> {
    (number(), number(), any::<u64>(), 0u32..3, "\\PC{0,8}").prop_map(
        |(period, factor, capacity, strategy, name)| {
            let strategy = ["one_for_one", "one_for_all", "rest_for_one"][strategy as usize];
            format!(
                r#"Agent(name: {name:?}, supervision: (strategy: {strategy}, max_restarts: {capacity}),
  modules: [
    (name: "c", type: "demo.counter", values: {{"params/period_ms": {period}}}),
    (name: "s", type: "demo.scale", values: {{"params/factor": {factor}}}, links: {{"in/value": "c/out/value"}}),
    (name: "p", type: "demo.producer", capacities: {{"out/items": {capacity}}}),
  ])"#
            )
        },
    )
}

fn cases(n: u32) -> Config {
    Config {
        cases: std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|c| c.parse().ok())
            .unwrap_or(n),
        failure_persistence: None,
        ..Config::default()
    }
}

fn registry() -> petrel::actors::ModuleRegistry {
    petrel::Petrel::new().registry().clone()
}

fn properties(n: u32) {
    let mut runner = proptest::test_runner::TestRunner::new(cases(n));
    let inputs = (expression(), edge_value(), any::<i64>(), 0u64..100_000);
    runner
        .run(&inputs, |(src, x, n, secs)| {
            evaluate(&src, x, n, secs);
            let _ = petrel::plans::parse_condition(&src);
            Ok(())
        })
        .unwrap();
    runner
        .run(&text_plan(), |text| {
            if let Ok(plan) = petrel::plans::compile_text(&text, "f.plan", "f", None) {
                let options = petrel::plans::CheckOptions { max_states: 2_000 };
                let _ = petrel::plans::check_with(&plan, &options);
                let script = petrel::plans::Script::parse("", "empty").unwrap();
                let _ = petrel::plans::simulate(&plan, &script, 50, &mut Vec::new());
            }
            Ok(())
        })
        .unwrap();
    let types = registry();
    runner
        .run(&config(), |text| {
            if let Ok(file) = ConfigFile::parse("fuzz.ron", &text) {
                let _ = file.build(&types);
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn structured_inputs_get_answers_not_panics() {
    properties(256);
}

#[test]
#[ignore = "a long campaign: cargo test --test properties -- --ignored"]
fn structured_inputs_get_answers_not_panics_long() {
    properties(50_000);
}
