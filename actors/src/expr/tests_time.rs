//! Tests of expression origins (`elapsed`, `held` and `age` counting from an action's start)
//! and of lists (`min`, `max`, `len` over a list of numbers).

use super::tests::{env, eval, Fixture};
use super::*;

#[test]
fn lists_of_numbers_have_min_max_and_len() {
    assert_eq!(eval("min(s/out/list)"), Value::Num(1.0));
    assert_eq!(eval("max(s/out/list)"), Value::Num(2.0));
    assert_eq!(eval("len(s/out/list)"), Value::Num(2.0));
    assert_eq!(eval("min(s/out/list) < 1.5"), Value::Bool(true));
    assert_eq!(
        eval("min(a/out/x, a/out/y)"),
        Value::Num(-2.0),
        "the numeric form stays"
    );
}

#[test]
fn the_min_of_an_empty_list_is_an_evaluation_error_not_a_panic() {
    let mut f = Fixture::new();
    let id = f.set.add("min(s/out/list) < 1", &env(), None).unwrap();
    f.put("s/out/list", Vec::<f64>::new(), 0);
    let t = f.at(0);
    f.set.evaluate(t);
    assert!(f.set.value(id).unwrap().is_err());
}

#[test]
fn elapsed_counts_from_the_origin_and_wakes_at_its_comparison() {
    let mut f = Fixture::new();
    let id = f
        .set
        .add("elapsed() >= 2", &env(), Some(&Ty::Bool))
        .unwrap();
    let start = f.at(1000);
    f.set.set_origin(id, Some(start));
    let t = f.at(1500);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(false));
    assert_eq!(
        f.set.next_deadline(),
        Some(f.at(3001)),
        "2 s after the origin, plus the slack"
    );
    let t = f.at(3001);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(id), Some(true));
}

#[test]
fn an_origin_forgets_held_windows_and_floors_age() {
    let mut f = Fixture::new();
    let held = f
        .set
        .add("held(b/out/ok, 2s)", &env(), Some(&Ty::Bool))
        .unwrap();
    let age = f
        .set
        .add("age(a/out/x) > 1", &env(), Some(&Ty::Bool))
        .unwrap();
    f.put("b/out/ok", true, 0);
    f.put("a/out/x", 1.0, 0);
    let t = f.at(0);
    f.set.evaluate(t);
    // An action starts at 5 s: the condition held for 5 s already, the write is 5 s old.
    let start = f.at(5000);
    f.set.set_origin(held, Some(start));
    f.set.set_origin(age, Some(start));
    let t = f.at(5000);
    f.set.evaluate(t);
    assert_eq!(
        f.set.bool(held),
        Some(false),
        "the window opens at the start"
    );
    assert_eq!(f.set.bool(age), Some(false), "age counts from the start");
    let saved = f.set.held_states(held);
    assert_eq!(saved, vec![Some(start)]);
    let t = f.at(7000);
    f.set.evaluate(t);
    assert_eq!(f.set.bool(held), Some(true));
    assert_eq!(f.set.bool(age), Some(true));
    // Restoring the held state of a restarted owner keeps the window.
    let mut g = Fixture::new();
    g.t0 = f.t0;
    let again = g
        .set
        .add("held(b/out/ok, 2s)", &env(), Some(&Ty::Bool))
        .unwrap();
    g.set.set_origin(again, Some(start));
    g.set.restore_held_states(again, &saved);
    g.put("b/out/ok", true, 6000);
    let t = g.at(7000);
    g.set.evaluate(t);
    assert_eq!(g.set.bool(again), Some(true));
}
