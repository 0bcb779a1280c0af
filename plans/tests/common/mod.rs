//! Shared helpers for the integration tests.
#![allow(dead_code)]

use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

use petrel_plans::{
    parse_pnml, step, CallKind, Environment, Plan, PlanState, PlanStatus, StepReport,
};

/// Path of a fixture.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// Builds generator-style PNML: places `(label, tokens)` get ids `n0..`,
/// transitions `t0..` by label, arcs `(source, target, weight)` by id.
pub fn pnml(places: &[(&str, u32)], transitions: &[&str], arcs: &[(&str, &str, u32)]) -> String {
    let mut s = String::from("<pnml><net id=\"net\">\n");
    for (i, (label, m)) in places.iter().enumerate() {
        s += &format!("<place id=\"n{i}\"><name><value>{label}</value></name>");
        if *m > 0 {
            s += &format!("<initialMarking><value>{m}</value></initialMarking>");
        }
        s += "</place>\n";
    }
    for (i, label) in transitions.iter().enumerate() {
        s += &format!("<transition id=\"t{i}\"><name><value>{label}</value></name></transition>\n");
    }
    for (i, (a, b, w)) in arcs.iter().enumerate() {
        s += &format!("<arc id=\"a{i}\" source=\"{a}\" target=\"{b}\">");
        if *w != 1 {
            s += &format!("<inscription><value>{w}</value></inscription>");
        }
        s += "</arc>\n";
    }
    s + "</net></pnml>\n"
}

/// Parses [`pnml`] output.
pub fn net(places: &[(&str, u32)], transitions: &[&str], arcs: &[(&str, &str, u32)]) -> Plan {
    parse_pnml(&pnml(places, transitions, arcs), "test.pnml", "test").expect("test net loads")
}

/// An environment with explicit answers that records everything.
#[derive(Default)]
pub struct TestEnv {
    pub conditions: HashMap<String, bool>,
    pub finished: HashSet<String>,
    pub failed: HashSet<String>,
    pub stepped: Vec<String>,
    pub calls: Vec<String>,
    pub asked: Vec<String>,
}

impl TestEnv {
    pub fn cond(mut self, name: &str, v: bool) -> Self {
        self.conditions.insert(name.into(), v);
        self
    }
}

impl Environment for TestEnv {
    fn condition(&mut self, name: &str) -> Option<bool> {
        self.asked.push(name.to_string());
        self.conditions.get(name).copied()
    }
    fn step_action(&mut self, name: &str) {
        self.stepped.push(name.to_string());
    }
    fn action_finished(&mut self, name: &str) -> bool {
        self.finished.contains(name)
    }
    fn action_failed(&mut self, name: &str) -> bool {
        self.failed.contains(name)
    }
    fn call(&mut self, name: &str, kind: CallKind) {
        self.calls.push(format!("{name}.{kind}"));
    }
}

/// Marked places by label, in document order.
pub fn marking(plan: &Plan, st: &PlanState) -> Vec<(String, u32)> {
    st.marked()
        .map(|(p, n)| (plan.places()[p].label.clone(), n))
        .collect()
}

/// Calls made in a step, as `name.kind`.
pub fn calls(r: &StepReport) -> Vec<String> {
    r.calls.iter().map(ToString::to_string).collect()
}

/// Steps once and returns the calls.
pub fn run(plan: &Plan, st: &mut PlanState, env: &mut TestEnv) -> Vec<String> {
    calls(&step(plan, st, env))
}

/// Status shortcut.
pub fn status(plan: &Plan, st: &PlanState) -> PlanStatus {
    st.status(plan)
}
