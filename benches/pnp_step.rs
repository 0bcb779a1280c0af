//! `pnp_step`: the cost of one Petri Net Plan step must follow the marked
//! places, not the net size. A ring of `[]` transitions carries 10 tokens
//! spread around it; every step moves each token one place on, so the state
//! after a step looks like the state before and each iteration measures a
//! real step (10 transitions examined, 10 fired).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use petrel_plans::{parse_pnml, step, CallKind, Environment, Plan, PlanState};

/// Answers every condition true and ignores actions (the ring has none).
struct NoEnv;

impl Environment for NoEnv {
    fn condition(&mut self, _: &str) -> Option<bool> {
        Some(true)
    }
    fn step_action(&mut self, _: &str) {}
    fn action_finished(&mut self, _: &str) -> bool {
        true
    }
    fn action_failed(&mut self, _: &str) -> bool {
        false
    }
    fn call(&mut self, _: &str, _: CallKind) {}
}

fn ring(places: usize, tokens: usize) -> Plan {
    let mut s = String::with_capacity(places * 200);
    s.push_str("<pnml><net id=\"ring\">\n");
    for i in 0..places {
        let m = if i % (places / tokens) == 0 { 1 } else { 0 };
        s.push_str(&format!(
            "<place id=\"p{i}\"><name><value>P{i}</value></name><initialMarking><value>{m}</value></initialMarking></place>\n"
        ));
    }
    for i in 0..places {
        s.push_str(&format!(
            "<transition id=\"t{i}\"><name><value>[]</value></name></transition>\n"
        ));
        let next = (i + 1) % places;
        s.push_str(&format!(
            "<arc id=\"i{i}\" source=\"p{i}\" target=\"t{i}\"/>\n"
        ));
        s.push_str(&format!(
            "<arc id=\"o{i}\" source=\"t{i}\" target=\"p{next}\"/>\n"
        ));
    }
    s.push_str("</net></pnml>\n");
    parse_pnml(&s, "ring.pnml", "ring").expect("the synthetic ring loads")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("pnp_step");
    for (name, places) in [("step_1k", 1_000), ("step_100k", 100_000)] {
        let plan = ring(places, 10);
        let mut state = PlanState::new(&plan);
        let mut env = NoEnv;
        assert_eq!(step(&plan, &mut state, &mut env).fired.len(), 10);
        group.bench_function(name, |b| {
            b.iter(|| black_box(step(black_box(&plan), &mut state, &mut env)));
        });
        assert_eq!(state.marked().count(), 10, "the ring keeps its tokens");
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
