//! Tests of the whole language through [`ExprSet`].

use std::sync::Arc;
use std::time::Duration;

use tokio::time::Instant;

use super::*;
use crate::types::Pose2;
use crate::value::{AnyValue, TypeInfo};

pub(super) fn env() -> TypeEnv {
    let mut env = TypeEnv::new();
    env.insert("a/out/x", Ty::Num)
        .insert("a/out/y", Ty::Num)
        .insert("b/out/ok", Ty::Bool)
        .insert("m/params/name", Ty::Str)
        .insert("petrel://r1/a/out/x", Ty::Num);
    let pose: AnyValue = Arc::new(Pose2::default());
    env.insert_property("loc/out/pose", TypeInfo::of::<Pose2>(), &pose);
    env.insert_property(
        "s/out/list",
        TypeInfo::of::<Vec<f64>>(),
        &(Arc::new(vec![1.0]) as AnyValue),
    );
    env
}

/// A set fed with x = 3, y = -2, ok = true, name = "dock", pose (1, 2, 0.5).
pub(super) struct Fixture {
    pub set: ExprSet,
    pub t0: Instant,
}

impl Fixture {
    pub fn new() -> Self {
        Fixture {
            set: ExprSet::new(),
            t0: Instant::now(),
        }
    }

    pub fn put<T: crate::PropertyType>(&mut self, path: &str, v: T, at_ms: u64) {
        if let Some(p) = self.set.property(path) {
            let v: AnyValue = Arc::new(v);
            self.set.update(
                p,
                TypeInfo::of::<T>(),
                &v,
                self.t0 + Duration::from_millis(at_ms),
            );
        }
    }

    pub fn feed(&mut self) {
        self.put("a/out/x", 3.0, 0);
        self.put("petrel://r1/a/out/x", 3.0, 0);
        self.put("a/out/y", -2_i64, 0);
        self.put("b/out/ok", true, 0);
        self.put("m/params/name", "dock".to_string(), 0);
        self.put("loc/out/pose", Pose2::new(1.0, 2.0, 0.5), 0);
        self.put("s/out/list", vec![1.0, 2.0], 0);
    }

    pub fn at(&mut self, ms: u64) -> Instant {
        self.t0 + Duration::from_millis(ms)
    }
}

pub(super) fn eval(src: &str) -> Value {
    let mut f = Fixture::new();
    let id = f
        .set
        .add(src, &env(), None)
        .unwrap_or_else(|e| panic!("{src}: {e}"));
    f.feed();
    let now = f.at(0);
    f.set.evaluate(now);
    f.set
        .value(id)
        .unwrap()
        .clone()
        .unwrap_or_else(|e| panic!("{src}: {e}"))
}

pub(super) fn err(src: &str) -> ExprError {
    ExprSet::new()
        .add(src, &env(), Some(&Ty::Bool))
        .expect_err(src)
}

#[test]
fn every_construct_evaluates() {
    let cases: &[(&str, Value)] = &[
        ("1 + 2 * 3", Value::Num(7.0)),
        ("(1 + 2) * 3", Value::Num(9.0)),
        ("10 - 4 - 3", Value::Num(3.0)),
        ("8 / 4 / 2", Value::Num(1.0)),
        ("-a/out/x + 1", Value::Num(-2.0)),
        ("- -2", Value::Num(2.0)),
        ("a/out/x * a/out/y", Value::Num(-6.0)),
        ("a/out/x / a/out/y", Value::Num(-1.5)),
        ("petrel://r1/a/out/x", Value::Num(3.0)),
        ("abs(a/out/y)", Value::Num(2.0)),
        ("min(4, a/out/x, 5)", Value::Num(3.0)),
        ("max(a/out/y, -7)", Value::Num(-2.0)),
        ("clamp(a/out/x, 0, 1)", Value::Num(1.0)),
        ("clamp(a/out/y, 0, 1)", Value::Num(0.0)),
        ("clamp(5, 1, 3)", Value::Num(3.0)),
        ("loc/out/pose.y", Value::Num(2.0)),
        ("loc/out/pose.theta * 2", Value::Num(1.0)),
        ("1500ms + 2s", Value::Num(3.5)),
        ("a/out/x > 2", Value::Bool(true)),
        ("a/out/x >= 3 && a/out/x <= 3", Value::Bool(true)),
        ("a/out/x < 3 || a/out/x != 3", Value::Bool(false)),
        ("a/out/x == 3 and b/out/ok", Value::Bool(true)),
        ("not b/out/ok or true", Value::Bool(true)),
        ("!b/out/ok", Value::Bool(false)),
        ("not a/out/x > 5", Value::Bool(true)),
        ("true and false or true", Value::Bool(true)),
        ("true or false and false", Value::Bool(true)),
        ("m/params/name == \"dock\"", Value::Bool(true)),
        ("m/params/name != \"do\\\"ck\"", Value::Bool(true)),
        ("b/out/ok == false", Value::Bool(false)),
        ("age(a/out/x) == 0", Value::Bool(true)),
        ("age(s/out/list) < 1", Value::Bool(true)),
    ];
    for (src, want) in cases {
        assert_eq!(&eval(src), want, "{src}");
    }
}

#[test]
fn struct_fields_keep_full_precision() {
    let mut f = Fixture::new();
    let id = f.set.add(
        "loc/out/pose.x == 0.1 and loc/out/pose.y == 123456.789012345",
        &env(),
        None,
    );
    let id = id.unwrap();
    f.put("loc/out/pose", Pose2::new(0.1, 123456.789012345, 0.0), 0);
    let t = f.at(0);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(true), "{:?}", f.set.value(id));
}

#[test]
fn precedence_shows_in_the_tree() {
    let ast = parse("not a/b < 1 + 2 * 3 and c/d").unwrap();
    let AstKind::Bin(BinOp::And, lhs, _) = ast.kind else {
        panic!("and at the top: {ast:?}")
    };
    let AstKind::Not(cmp) = lhs.kind else {
        panic!("not above <")
    };
    let AstKind::Bin(BinOp::Lt, _, sum) = cmp.kind else {
        panic!("< above +")
    };
    assert!(matches!(sum.kind, AstKind::Bin(BinOp::Add, _, _)));
    assert_eq!(
        properties(&parse("age(a/b) + a/b.x - c/d").unwrap()),
        vec!["a/b", "c/d"]
    );
}

#[test]
fn parse_errors_have_positions_and_say_what_was_expected() {
    let cases: &[(&str, (u32, u32), &str)] = &[
        ("a/out/x >", (1, 10), "expected a value, found the end"),
        ("a/out/x > 1 > 2", (1, 13), "comparisons do not chain"),
        ("(a/out/x > 1", (1, 13), "expected `)`"),
        ("foo > 1", (1, 1), "unknown name `foo`"),
        ("b/out/ok\n  and ok", (2, 7), "unknown name `ok`"),
        ("loc/out/pose.", (1, 14), "expected a field name"),
        ("a/out/x 1", (1, 9), "unexpected number `1`"),
        ("a/out/x > 3km", (1, 12), "unknown unit `km`"),
        ("a/out/x ^ 2", (1, 9), "unexpected character `^`"),
    ];
    for (src, (line, col), msg) in cases {
        let e = err(src);
        assert_eq!((e.line, e.column), (*line, *col), "{src}: {e}");
        assert!(e.message.contains(msg), "{src}: {e}");
    }
}

#[test]
fn type_errors_have_positions() {
    let cases: &[(&str, (u32, u32), &str)] = &[
        (
            "loc/out/pose > 1",
            (1, 1),
            "must be a number, found a Pose2",
        ),
        (
            "loc/out/pose == 1",
            (1, 1),
            "not a Pose2; compare its fields",
        ),
        (
            "a/out/x == \"x\"",
            (1, 1),
            "cannot compare a number with a string",
        ),
        (
            "loc/out/pose.z > 1",
            (1, 1),
            "Pose2 has no field `z`; its fields are theta, x, y",
        ),
        ("a/out/x.v > 1", (1, 1), "field access `.v` on a number"),
        (
            "1 and b/out/ok",
            (1, 1),
            "left operand of `and` must be a boolean",
        ),
        (
            "b/out/ok and not 2",
            (1, 18),
            "operand of `not` must be a boolean",
        ),
        (
            "a/out/x + b/out/ok > 1",
            (1, 11),
            "right operand of `+` must be a number",
        ),
        ("x/out/nope > 1", (1, 1), "unknown property `x/out/nope`"),
        (
            "a/out/x + 1",
            (1, 1),
            "the expression must be a boolean, found a number",
        ),
        ("held(b/out/ok, a/out/x)", (1, 16), "must be a literal"),
        (
            "held(a/out/x, 2s)",
            (1, 6),
            "condition of `held` must be a boolean",
        ),
        ("age(a/out/x + 1) > 2", (1, 5), "takes a property"),
        ("abs(1, 2) > 0", (1, 1), "`abs` takes 1 argument"),
        (
            "min(1) > 0",
            (1, 1),
            "a list of numbers or at least 2 numbers",
        ),
        ("clamp(1, 2) > 0", (1, 1), "`clamp` takes 3 arguments"),
        (
            "s/out/list > 0",
            (1, 1),
            "must be a number, found a list of numbers",
        ),
        (
            "len(a/out/x) > 0",
            (1, 5),
            "`len` takes a list, found a number",
        ),
    ];
    for (src, (line, col), msg) in cases {
        let e = err(src);
        assert_eq!((e.line, e.column), (*line, *col), "{src}: {e}");
        assert!(e.message.contains(msg), "{src}: {e}");
    }
    assert_eq!(
        err("x/out/nope > 1").to_string(),
        "1:1: unknown property `x/out/nope`"
    );
}

#[test]
fn held_needs_the_condition_true_for_the_whole_duration_on_a_fake_clock() {
    let mut f = Fixture::new();
    let id = f
        .set
        .add("held(b/out/ok, 2s)", &env(), Some(&Ty::Bool))
        .unwrap();
    f.put("b/out/ok", true, 0);
    let t = f.at(0);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(false));
    assert_eq!(
        f.set.next_deadline(),
        Some(f.at(2000)),
        "wake when the window closes"
    );
    let t = f.at(1500);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(false));
    f.put("b/out/ok", false, 1600);
    let t = f.at(1600);
    f.set.evaluate(t);
    assert_eq!(f.set.next_deadline(), None);
    f.put("b/out/ok", true, 1700);
    let t = f.at(1700);
    f.set.evaluate(t);
    let t = f.at(3000);
    assert_eq!(
        f.set.evaluate(t),
        vec![],
        "only 1.3 s since it became true again"
    );
    let t = f.at(3700);
    assert_eq!(f.set.evaluate(t), vec![id]);
    assert_eq!(f.set.bool(id), Some(true));
}

#[test]
fn age_counts_from_the_last_write_and_sets_a_deadline() {
    let mut f = Fixture::new();
    let id = f
        .set
        .add("age(a/out/x) > 500ms", &env(), Some(&Ty::Bool))
        .unwrap();
    f.put("a/out/x", 1.0, 100);
    let t = f.at(200);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(false));
    assert_eq!(f.set.next_deadline(), Some(f.at(601)));
    let t = f.at(601);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(true));
}

#[test]
fn evaluation_is_incremental() {
    let mut f = Fixture::new();
    let e = env();
    let on_x = f.set.add("a/out/x > 2", &e, None).unwrap();
    let on_y = f.set.add("a/out/y < 0", &e, None).unwrap();
    let both = f.set.add("a/out/x + a/out/y", &e, None).unwrap();
    assert_eq!(
        f.set.properties().count(),
        2,
        "a property read twice is one property"
    );
    f.feed();
    let t = f.at(0);
    assert_eq!(f.set.evaluate(t).len(), 3);
    assert_eq!(f.set.total_evaluations(), 3);
    let t = f.at(1);
    assert_eq!(
        f.set.evaluate(t),
        vec![],
        "nothing changed: nothing evaluated"
    );
    assert_eq!(f.set.total_evaluations(), 3);
    f.put("a/out/x", 4.0, 2);
    let t = f.at(2);
    assert_eq!(
        f.set.evaluate(t),
        vec![both],
        "x > 2 still true: only the sum changed"
    );
    assert_eq!(f.set.evaluations(on_x), 2);
    assert_eq!(f.set.evaluations(on_y), 1, "y's expression did not read x");
    assert_eq!(f.set.evaluations(both), 2);
    assert_eq!(f.set.value(both), Some(&Ok(Value::Num(2.0))));
}

#[test]
fn unread_properties_and_failed_adds_leave_no_trace() {
    let mut set = ExprSet::new();
    assert!(set.add("a/out/x > 1 and x/y", &env(), None).is_err());
    assert_eq!(
        set.properties().count(),
        0,
        "a rejected expression registers nothing"
    );
    let id = set.add("a/out/x > 1", &env(), None).unwrap();
    set.evaluate(Instant::now());
    assert!(matches!(set.value(id), Some(Err(m)) if m.contains("not read yet")));
    assert_eq!(set.bool(id), None);
}

#[test]
fn contradicting_comparisons_can_never_be_true() {
    let never =
        |src: &str| super::never_true(src, &parse(src).unwrap()).map(|e| (e.column, e.message));
    assert_eq!(
        never("a/out/v > 5 and a/out/v < 3"),
        Some((
            1,
            "`a/out/v > 5` and `a/out/v < 3` cannot both be true".into()
        ))
    );
    assert_eq!(
        never("b/out/m == 1 && x/out/y > 0 && 2 == b/out/m"),
        Some((
            1,
            "`b/out/m == 1` and `2 == b/out/m` cannot both be true".into()
        ))
    );
    assert_eq!(
        never("held(p/out/pose.x >= 2, 1s) and p/out/pose.x < 2").map(|(c, _)| c),
        Some(6),
        "held(c) needs c; fields are operands"
    );
    assert!(
        never("not (a/out/v <= 5 or a/out/v >= 3)").is_some(),
        "v > 5 and v < 3"
    );
    assert!(never("(a/out/v > 5 and a/out/v < 3) or (a/out/v > 9 and a/out/v < -1)").is_some());
    // What may hold is never reported.
    for ok in [
        "a/out/v > 5 and a/out/v < 6",
        "a/out/v >= 3 and a/out/v <= 3",
        "a/out/v > 5 or a/out/v < 3",
        "a/out/v > 5 and b/out/v < 3",
        "a/out/v != 3 and a/out/v == 3 or true",
        "not (a/out/v > 5 and a/out/v < 3)",
        "a/out/v > -1 and -a/out/v > 3",
        "abs(a/out/v) > 5 and abs(a/out/v) < 3",
    ] {
        assert_eq!(never(ok), None, "{ok}");
    }
}

#[test]
fn durations_are_bounded_where_they_are_written() {
    let e = err("held(b/out/ok, 100000000000000000000s)");
    assert!(
        e.to_string()
            .contains("the duration of `held` must be between 0 and 1e9 s"),
        "{e}"
    );
    assert!(e.to_string().starts_with("1:16:"), "at the duration: {e}");
    // A comparison with an age beyond any run is fine: it just never flips.
    assert_eq!(
        eval("age(a/out/x) > 9223372036854775807"),
        Value::Bool(false)
    );
}

#[test]
fn arithmetic_that_leaves_the_numbers_cannot_be_evaluated() {
    // a/out/x = 3, a/out/y = -2; `z` is fed 0 and infinity below.
    let mut env = env();
    env.insert("z/out/v", Ty::Num);
    let failing = [
        ("a/out/x / z/out/v", 0.0, "division by zero (3 / 0)"),
        (
            "(a/out/x - 3) / z/out/v > 1",
            0.0,
            "division by zero (0 / 0)",
        ),
        (
            "z/out/v * z/out/v",
            1e300,
            "1e300 * 1e300 is not a finite number",
        ),
        (
            "z/out/v - z/out/v",
            f64::INFINITY,
            "inf - inf is not a finite number",
        ),
        (
            "clamp(a/out/x, z/out/v, 1)",
            2.0,
            "clamp(x, lo, hi): lo (2) is above hi (1)",
        ),
    ];
    for (src, z, message) in failing {
        let mut f = Fixture::new();
        let id = f.set.add(src, &env, None).unwrap();
        f.feed();
        f.put("z/out/v", z, 0);
        let now = f.at(0);
        f.set.evaluate(now);
        let result = f.set.value(id).unwrap();
        assert!(
            result.as_ref().is_err_and(|e| e.contains(message)),
            "{src} with z = {z}: {result:?}"
        );
    }
    // An infinity read from a property (a laser's "no return") still computes.
    let mut f = Fixture::new();
    let id = f.set.add("z/out/v * 2 > a/out/x", &env, None).unwrap();
    f.feed();
    f.put("z/out/v", f64::INFINITY, 0);
    let now = f.at(0);
    f.set.evaluate(now);
    assert_eq!(f.set.value(id).unwrap(), &Ok(Value::Bool(true)));
    // A constant divisor of 0 is refused before anything runs.
    let e = err("a/out/x / 0 > 1");
    assert!(e.message.contains("division by zero"), "{e}");
    assert_eq!((e.line, e.column), (1, 11));
}

#[test]
fn errors_quote_at_most_80_characters_with_control_characters_escaped() {
    assert_eq!(quoted("a/out/x > 1"), "a/out/x > 1");
    assert_eq!(quoted("a\u{0}b\nc"), "a\\u{0}b\\nc");
    let long = "x".repeat(200_000);
    assert_eq!(quoted(&long), format!("{}…", "x".repeat(80)));
}
