//! The pure rule engine, driven by hand: values and times are given, actions asserted.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use petrel_actors::expr::Value;
use petrel_actors::{AnyValue, Pose2, PropertyType, TypeInfo};
use petrel_contexts::{Action, Engine, EngineMemory, LoadedRules, Schema};
use tokio::time::Instant;

struct Props(HashMap<String, (TypeInfo, AnyValue)>);

fn prop<T: PropertyType>(v: T) -> (TypeInfo, AnyValue) {
    (TypeInfo::of::<T>(), Arc::new(v))
}

/// A small agent: sensors `speed/out/v` (f64), `loc/out/q` (f64), `hw/out/pose` (Pose2);
/// targets `cam/params/deblur` (bool), `oa/params/maxSpeed` (f64), `mapper/in/pose` (Pose2),
/// `nav/params/mode` (string), `cam/params/exposure` (i64, as is `cam/out/frames`), modules
/// `cam`, `oa`, `mapper`, `rec` (with `enabled`).
fn schema() -> Props {
    let mut m = HashMap::new();
    m.insert("speed/out/v".into(), prop(0.0));
    m.insert("loc/out/q".into(), prop(1.0));
    m.insert("hw/out/pose".into(), prop(Pose2::default()));
    m.insert("loc/out/pose".into(), prop(Pose2::default()));
    m.insert("cam/params/deblur".into(), prop(false));
    m.insert("oa/params/maxSpeed".into(), prop(1.0));
    m.insert("mapper/in/pose".into(), prop(Pose2::default()));
    m.insert("nav/params/mode".into(), prop(String::from("normal")));
    m.insert("cam/params/exposure".into(), prop(10_i64));
    m.insert("cam/out/frames".into(), prop(0_i64));
    for module in ["cam", "oa", "mapper", "rec", "nav"] {
        m.insert(format!("{module}/enabled"), prop(true));
    }
    Props(m)
}

impl Schema for Props {
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)> {
        self.0.get(path).cloned()
    }

    fn refuses(&self, _path: &str, _value: &AnyValue) -> Option<String> {
        None
    }
}

fn engine(rules: &str) -> Engine {
    let loaded =
        LoadedRules::parse(Path::new("rules.ron"), rules).unwrap_or_else(|e| panic!("{e:?}"));
    Engine::build(&loaded, &schema()).unwrap_or_else(|e| {
        panic!(
            "{}",
            e.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("\n")
        )
    })
}

fn errors(rules: &str) -> Vec<String> {
    let loaded = LoadedRules::parse(Path::new("rules.ron"), rules).unwrap();
    match Engine::build(&loaded, &schema()) {
        Ok(_) => panic!("rules should be rejected"),
        Err(e) => e.iter().map(ToString::to_string).collect(),
    }
}

/// Feeds `value` to `path` at `t0 + ms` and steps.
fn at(e: &mut Engine, t0: Instant, ms: u64, path: &str, value: f64) -> Vec<Action> {
    let now = t0 + Duration::from_millis(ms);
    e.update(
        path,
        TypeInfo::of::<f64>(),
        &(Arc::new(value) as AnyValue),
        now,
    );
    e.step(now)
}

fn set(target: &str, value: Value, context: &str) -> Action {
    Action::Set {
        target: target.into(),
        value,
        context: context.into(),
    }
}

const DEBLUR: &str = r#"Contexts(contexts: [(name: "fast", when: "speed/out/v > 0.6", until: "speed/out/v < 0.4",
    set: {"cam/params/deblur": "true"})])"#;

#[test]
fn hysteresis_stops_flapping_around_a_threshold() {
    let mut e = engine(DEBLUR);
    let t0 = Instant::now();
    assert_eq!(
        at(&mut e, t0, 0, "speed/out/v", 0.7),
        [
            Action::Activated("fast".into()),
            set("cam/params/deblur", Value::Bool(true), "fast")
        ]
    );
    for (k, v) in [0.59, 0.61, 0.55, 0.62, 0.45, 0.58].into_iter().enumerate() {
        assert_eq!(
            at(&mut e, t0, 10 * (k as u64 + 1), "speed/out/v", v),
            [],
            "no flapping at {v}"
        );
    }
    assert_eq!(
        at(&mut e, t0, 100, "speed/out/v", 0.39),
        [
            Action::Deactivated("fast".into()),
            Action::Restore("cam/params/deblur".into())
        ]
    );
    assert_eq!(e.active().count(), 0);
}

#[test]
fn min_dwell_holds_a_state_for_its_duration() {
    let mut e = engine(
        r#"Contexts(contexts: [(name: "lost", when: "loc/out/q < 0.3", min_dwell_ms: 1000,
        relink: {"mapper/in/pose": "hw/out/pose"})])"#,
    );
    let t0 = Instant::now();
    assert_eq!(
        at(&mut e, t0, 0, "loc/out/q", 0.1)[0],
        Action::Activated("lost".into())
    );
    assert_eq!(
        at(&mut e, t0, 500, "loc/out/q", 0.9),
        [],
        "recovered, but the dwell is not over"
    );
    let later = e.step(t0 + Duration::from_millis(1000));
    assert_eq!(
        later,
        [
            Action::Deactivated("lost".into()),
            Action::RestoreLink("mapper/in/pose".into())
        ]
    );
}

#[test]
fn held_waits_for_a_condition_to_last() {
    let mut e = engine(
        r#"Contexts(contexts: [(name: "cruise", when: "held(speed/out/v > 0.5, 2s)", set: {"nav/params/mode": "\"cruise\""})])"#,
    );
    let t0 = Instant::now();
    assert_eq!(at(&mut e, t0, 0, "speed/out/v", 0.8), []);
    assert_eq!(e.step(t0 + Duration::from_millis(1999)), []);
    let actions = e.step(t0 + Duration::from_millis(2000));
    assert_eq!(
        actions[1],
        set("nav/params/mode", Value::Str("cruise".into()), "cruise")
    );
}

#[test]
fn priorities_resolve_shared_targets_and_the_original_comes_back_last() {
    let mut e = engine(
        r#"Contexts(contexts: [
            (name: "rough", when: "speed/out/v > 0.1", priority: 1, set: {"oa/params/maxSpeed": "0.5"}),
            (name: "danger", when: "loc/out/q < 0.2", priority: 5, set: {"oa/params/maxSpeed": "0.1"}, disable: ["rec"]),
        ])"#,
    );
    let t0 = Instant::now();
    let num = Value::Num;
    assert_eq!(
        at(&mut e, t0, 0, "speed/out/v", 1.0)[1],
        set("oa/params/maxSpeed", num(0.5), "rough")
    );
    let both = at(&mut e, t0, 10, "loc/out/q", 0.1);
    assert_eq!(
        both[1..],
        [
            set("oa/params/maxSpeed", num(0.1), "danger"),
            set("rec/enabled", Value::Bool(false), "danger")
        ]
    );
    assert_eq!(e.active().collect::<Vec<_>>(), ["danger", "rough"]);
    let back = at(&mut e, t0, 20, "loc/out/q", 0.9);
    assert_eq!(
        back[1..],
        [
            Action::Restore("rec/enabled".into()),
            set("oa/params/maxSpeed", num(0.5), "rough")
        ]
    );
    assert_eq!(
        at(&mut e, t0, 30, "speed/out/v", 0.0)[1],
        Action::Restore("oa/params/maxSpeed".into())
    );
}

#[test]
fn continuous_expressions_follow_their_inputs_while_active() {
    let mut e = engine(
        r#"Contexts(contexts: [(name: "rough", when: "speed/out/v >= 0", set: {"oa/params/maxSpeed": "clamp(1.2 - 0.8 * speed/out/v, 0.2, 1.0)"})])"#,
    );
    let t0 = Instant::now();
    let values: Vec<Action> = [0.0, 0.5, 0.9, 2.0]
        .iter()
        .enumerate()
        .flat_map(|(k, v)| at(&mut e, t0, k as u64, "speed/out/v", *v))
        .collect();
    let sets: Vec<f64> = values
        .iter()
        .filter_map(|a| match a {
            Action::Set {
                value: Value::Num(n),
                ..
            } => Some((n * 1000.0).round() / 1000.0),
            _ => None,
        })
        .collect();
    assert_eq!(sets, [1.0, 0.8, 0.48, 0.2]);
}

#[test]
fn sticky_effects_stay_and_start_stop_are_undone_otherwise() {
    let mut e = engine(
        r#"Contexts(contexts: [
            (name: "dock", when: "loc/out/q < 0.5", sticky: true, set: {"nav/params/mode": "\"docked\""}),
            (name: "record", when: "speed/out/v > 1", start: ["rec"], stop: ["nav"]),
        ])"#,
    );
    let t0 = Instant::now();
    at(&mut e, t0, 0, "loc/out/q", 0.1);
    assert_eq!(
        at(&mut e, t0, 10, "loc/out/q", 0.9)[1],
        Action::Release("nav/params/mode".into()),
        "sticky: not restored"
    );
    let started = at(&mut e, t0, 20, "speed/out/v", 2.0);
    assert_eq!(
        started[1..],
        [
            Action::Run {
                module: "nav".into(),
                start: false,
                context: "record".into()
            },
            Action::Run {
                module: "rec".into(),
                start: true,
                context: "record".into()
            },
        ]
    );
    let undone = at(&mut e, t0, 30, "speed/out/v", 0.0);
    assert_eq!(
        undone[1..],
        [
            Action::RestoreRun("nav".into()),
            Action::RestoreRun("rec".into())
        ]
    );
}

#[test]
fn evaluation_is_incremental() {
    let mut e = engine(
        r#"Contexts(contexts: [
            (name: "a", when: "speed/out/v > 1"),
            (name: "b", when: "loc/out/q < 0.5"),
        ])"#,
    );
    let t0 = Instant::now();
    at(&mut e, t0, 0, "speed/out/v", 0.0);
    at(&mut e, t0, 0, "loc/out/q", 1.0);
    let before = e.evaluations();
    for k in 1..=10 {
        at(&mut e, t0, k, "speed/out/v", k as f64 / 10.0);
    }
    assert_eq!(
        e.evaluations() - before,
        10,
        "only the rule reading speed/out/v was evaluated"
    );
}

#[test]
fn bad_rules_are_reported_with_positions() {
    let e = errors(
        r#"Contexts(contexts: [
    (name: "a", when: "hw/out/pose > 1.0", set: {"oa/params/maxSpeed": "speed/out/vv * 2"}),
    (name: "b", when: "false", set: {"nope/params/x": "1"}),
    (name: "c", when: "speed/out/v > 0.5", priority: 2, set: {"oa/params/maxSpeed": "0.3"}),
    (name: "d", when: "speed/out/v > 0.7", priority: 2, set: {"oa/params/maxSpeed": "0.2"}, relink: {"mapper/in/pose": "speed/out/v"}),
    (name: "e", when: "speed/out/v >", enable: ["ghost"]),
    (name: "f", when: "loc/out/q < 0.2 and speed/out/v > 1 and loc/out/q > 0.5"),
])"#,
    );
    let expected = [
        "rules.ron:2:24: error: context `a`: in `hw/out/pose > 1.0`: the left operand of `>` must be a number, found a Pose2",
        "rules.ron:2:73: error: context `a`: in `speed/out/vv * 2`: unknown property `speed/out/vv`",
        "rules.ron:3:39: error: context `b`: unknown property `nope/params/x`",
        "rules.ron:5:121: error: context `d`: cannot relink `mapper/in/pose` (Pose2) to `speed/out/v` (f64): the types differ",
        "rules.ron:6:37: error: context `e`: in `speed/out/v >`: expected a value, found the end",
        "rules.ron:6:50: error: context `e`: unknown module `ghost`",
        "rules.ron:5:12: error: contexts `c` and `d` both change the oa/params/maxSpeed with priority 2: give them different priorities",
        "rules.ron:3:12: error: context `b` can never hold: its `when` is always false",
        "rules.ron:7:24: error: context `f` can never hold: `loc/out/q < 0.2` and `loc/out/q > 0.5` cannot both be true",
    ];
    assert_eq!(e, expected);
}

#[test]
fn a_name_given_twice_is_reported_where_the_second_is_and_both_are_checked() {
    let e = errors(
        r#"Contexts(contexts: [
    (name: "a", when: "speed/out/v > 0.5"),
    (name: "a", when: "speed/out/v > 0.7", set: {"nope/params/x": "1", "nav/params/mode": "\"x\" + 1"}),
])"#,
    );
    let expected = [
        "rules.ron:3:12: error: duplicate context name `a`: a context of that name comes before; give this one another name",
        "rules.ron:3:92: error: context `a`: in `\"x\" + 1`: the left operand of `+` must be a number, found a string",
        "rules.ron:3:51: error: context `a`: unknown property `nope/params/x`",
    ];
    assert_eq!(e, expected);
}

#[test]
fn an_integer_is_set_only_from_what_gives_whole_numbers() {
    // Whole by construction: i64 properties, whole constants, + - * and min/max/abs/len.
    engine(
        r#"Contexts(contexts: [
    (name: "a", when: "speed/out/v > 1", set: {"cam/params/exposure": "max(cam/out/frames * 2 - 1, 3)"}),
])"#,
    );
    let e = errors(
        r#"Contexts(contexts: [
    (name: "a", when: "speed/out/v > 1", set: {"cam/params/exposure": "cam/out/frames + speed/out/v * 2"}),
    (name: "b", when: "speed/out/v > 2", set: {"cam/params/exposure": "cam/out/frames / 2"}),
    (name: "c", when: "speed/out/v > 3", set: {"cam/params/exposure": "abs(hw/out/pose.x)"}),
    (name: "d", when: "speed/out/v > 4", set: {"cam/params/exposure": "cam/out/frames + elapsed()"}),
])"#,
    );
    let expected = [
        "rules.ron:2:49: error: context `a`: `cam/params/exposure` takes whole numbers (an i64), but `cam/out/frames + speed/out/v * 2` may give a fraction: `speed/out/v` is an f64",
        "rules.ron:3:49: error: context `b`: `cam/params/exposure` takes whole numbers (an i64), but `cam/out/frames / 2` may give a fraction: `cam/out/frames / 2` divides",
        "rules.ron:4:49: error: context `c`: `cam/params/exposure` takes whole numbers (an i64), but `abs(hw/out/pose.x)` may give a fraction: `hw/out/pose.x` may hold a fraction",
        "rules.ron:5:49: error: context `d`: `cam/params/exposure` takes whole numbers (an i64), but `cam/out/frames + elapsed()` may give a fraction: `elapsed()` counts seconds, with fractions",
    ];
    assert_eq!(e, expected);
}

#[test]
fn a_reload_keeps_what_stays_and_undoes_what_removed_rules_did() {
    let mut old = engine(
        r#"Contexts(contexts: [
            (name: "fast", when: "speed/out/v > 1", set: {"cam/params/deblur": "true"}),
            (name: "lost", when: "loc/out/q < 0.5", set: {"oa/params/maxSpeed": "0.2"}, relink: {"mapper/in/pose": "hw/out/pose"}),
        ])"#,
    );
    let t0 = Instant::now();
    at(&mut old, t0, 0, "speed/out/v", 2.0);
    at(&mut old, t0, 0, "loc/out/q", 0.1);
    assert_eq!(old.active().collect::<Vec<_>>(), ["fast", "lost"]);

    // `fast` stays as it was; `lost` is gone.
    let mut new = engine(
        r#"Contexts(contexts: [(name: "fast", when: "speed/out/v > 1", set: {"cam/params/deblur": "true"})])"#,
    );
    new.adopt(old);
    assert_eq!(new.active().collect::<Vec<_>>(), ["fast"]);
    let actions = at(&mut new, t0, 10, "speed/out/v", 2.0);
    assert_eq!(
        actions,
        [
            Action::Deactivated("lost".into()),
            Action::Restore("oa/params/maxSpeed".into()),
            Action::RestoreLink("mapper/in/pose".into()),
        ],
        "no second activation of `fast`, and its deblur is left as applied"
    );
    assert_eq!(at(&mut new, t0, 20, "speed/out/v", 2.5), []);
}

#[test]
fn a_switch_is_explained_by_what_its_conditions_read() {
    let e = engine(
        r#"Contexts(contexts: [
            (name: "fast", when: "speed/out/v > 1", until: "speed/out/v < 0.5 or loc/out/q < 0.1"),
            (name: "lost", when: "loc/out/q < 0.5", set: {"oa/params/maxSpeed": "speed/out/v * 0.5"}),
        ])"#,
    );
    let names = |c| {
        e.condition_reads(c)
            .into_iter()
            .map(|(_, p)| p)
            .collect::<Vec<_>>()
    };
    assert_eq!(names("fast"), ["speed/out/v", "loc/out/q"]);
    assert_eq!(names("lost"), ["loc/out/q"], "not what its effects read");
    assert!(names("nope").is_empty());
}

#[test]
fn a_reload_applies_the_changed_set_values_of_a_context_that_stays_active() {
    let mut old = engine(
        r#"Contexts(contexts: [(name: "slow", when: "speed/out/v > 1", set: {"oa/params/maxSpeed": "0.3"})])"#,
    );
    let t0 = Instant::now();
    at(&mut old, t0, 0, "speed/out/v", 2.0);
    let mut new = engine(
        r#"Contexts(contexts: [(name: "slow", when: "speed/out/v > 1", set: {"oa/params/maxSpeed": "0.1"})])"#,
    );
    new.adopt(old);
    // Nothing the rules read changes: the reload alone must bring the new value.
    let actions = new.step(t0 + Duration::from_millis(10));
    assert_eq!(
        actions,
        [set("oa/params/maxSpeed", Value::Num(0.1), "slow")]
    );
}

#[test]
fn a_restarted_engine_goes_on_from_its_memory() {
    let mut old = engine(DEBLUR);
    let t0 = Instant::now();
    assert_eq!(
        at(&mut old, t0, 0, "speed/out/v", 0.7),
        [
            Action::Activated("fast".into()),
            set("cam/params/deblur", Value::Bool(true), "fast")
        ]
    );
    let mut memory = EngineMemory::default();
    old.save_into(&mut memory);
    // Kept in `state/memory`, so it must survive a snapshot's text form.
    let text = ron::to_string(&memory).unwrap();
    let memory: EngineMemory = ron::from_str(&text).unwrap();

    // Between the thresholds: a fresh engine would not switch `fast` on, a resumed one keeps
    // it on without a second activation, and undoes its effect when it ends.
    let mut fresh = engine(DEBLUR);
    assert_eq!(at(&mut fresh, t0, 10, "speed/out/v", 0.5), []);
    assert_eq!(fresh.active().count(), 0);
    let mut new = engine(DEBLUR);
    new.resume(&memory);
    assert_eq!(at(&mut new, t0, 10, "speed/out/v", 0.5), []);
    assert_eq!(new.active().collect::<Vec<_>>(), ["fast"]);
    assert_eq!(
        at(&mut new, t0, 20, "speed/out/v", 0.3),
        [
            Action::Deactivated("fast".into()),
            Action::Restore("cam/params/deblur".into())
        ]
    );
}
