//! A deterministic scripted simulator.
//!
//! Script lines (blank lines are ignored; a word starting with `#` starts a comment, so names
//! may contain `#` anywhere else, as in `robot_0#pathLeft`; any name without spaces works):
//! * `finish A N`: `A.finished` is true once `A` was stepped `N` times since
//!   its last start (default 2 for unlisted actions; `-1` = never);
//! * `fail A N`: `A.failed` likewise (default never);
//! * `cond NAME FROM TO`: external condition `NAME` is true during steps
//!   `FROM..=TO` and false otherwise; unlisted conditions are false.
//!
//! Output, one JSON object per line: `{"step":0,"marking":{..}}`, then per
//! step `{"step":k,"calls":[..],"marking":{..}}` (`calls` always present, sub-plan
//! calls included; `marking` maps the top-level labels of marked places to
//! tokens, summed when several places share a label), and last
//! `{"result":"goal"|"fail"|"running","step":k}`.

use std::collections::{BTreeMap, HashMap};
use std::io::{self, Write};

use crate::error::PlanError;
use crate::exec::{step, Environment, PlanState, PlanStatus};
use crate::label::CallKind;
use crate::model::Plan;

/// The step limit the CLI uses when none is given.
pub const DEFAULT_MAX_STEPS: u64 = 100;

/// A parsed simulation script.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Script {
    finish: HashMap<String, i64>,
    fail: HashMap<String, i64>,
    conds: HashMap<String, Vec<(u64, u64)>>,
    /// Every name the script gives, with its line: `true` for an action.
    names: Vec<(bool, String, u32)>,
}

impl Script {
    /// Parses a script; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Script, PlanError> {
        let mut s = Script::default();
        for (i, line) in text.lines().enumerate() {
            let err = |message: String| PlanError::Script {
                file: file.to_string(),
                line: i as u32 + 1,
                message,
            };
            // A control character (a NUL) would show as nothing, or a space, in the message.
            if let Some((col, c)) = line
                .chars()
                .enumerate()
                .find(|(_, c)| c.is_control() && *c != '\t')
            {
                return Err(err(format!(
                    "column {}: unexpected character U+{:04X}",
                    col + 1,
                    u32::from(c)
                )));
            }
            let words = statement(line);
            match words.as_slice() {
                [] => {}
                [kw @ ("finish" | "fail"), name, n] => {
                    let n: i64 = n.parse().ok().filter(|n| *n >= -1).ok_or_else(|| {
                        err(format!("'{n}' is not a step count; expected a number >= 0, or -1 for never"))
                    })?;
                    let (map, other, other_kw) = match *kw {
                        "finish" => (&mut s.finish, &s.fail, "fail"),
                        _ => (&mut s.fail, &s.finish, "finish"),
                    };
                    // Both at a step: the action ends at the earlier one, and the other line
                    // never applies (with -1, never, either may stand beside the other).
                    if let Some(&m) = other.get(*name).filter(|&&m| m >= 0 && n >= 0) {
                        return Err(err(format!(
                            "'{kw} {name} {n}' and '{other_kw} {name} {m}': the action ends at the first, so the other never applies; keep one"
                        )));
                    }
                    if map.insert(name.to_string(), n).is_some() {
                        return Err(err(format!("'{kw} {name}' is given twice; keep one")));
                    }
                    s.names.push((true, name.to_string(), i as u32 + 1));
                }
                ["cond", name, from, to] => {
                    let num = |w: &str| w.parse::<u64>().map_err(|_| err(format!("'{w}' is not a step number")));
                    let (from, to) = (num(from)?, num(to)?);
                    if from > to {
                        return Err(err(format!("steps {from} to {to}: FROM comes after TO")));
                    }
                    s.conds.entry(name.to_string()).or_default().push((from, to));
                    s.names.push((false, name.to_string(), i as u32 + 1));
                }
                _ => {
                    return Err(err(format!(
                        "cannot read '{}'; expected 'finish ACTION N', 'fail ACTION N' or 'cond NAME FROM TO'", words.join(" ")
                    )))
                }
            }
        }
        Ok(s)
    }
}

impl Script {
    /// Checks that every action and condition the script names is one of `plan`'s (or of its
    /// sub-plans'): a misspelt name would silently never finish or never hold.
    pub fn check(&self, plan: &Plan, file: &str) -> Result<(), PlanError> {
        let mut actions = Vec::new();
        let mut conditions = Vec::new();
        let mut plans = vec![plan];
        while let Some(p) = plans.pop() {
            conditions.extend(p.conditions().iter().map(String::as_str));
            for e in p.executables() {
                actions.push(e.name.as_str());
                plans.extend(e.subplan.as_deref());
            }
        }
        for (is_action, name, line) in &self.names {
            let (known, what) = match is_action {
                true => (&actions, "action"),
                false => (&conditions, "condition"),
            };
            if !known.contains(&name.as_str()) {
                let mut listed = known.clone();
                listed.sort_unstable();
                listed.dedup();
                return Err(PlanError::Script {
                    file: file.to_string(),
                    line: *line,
                    message: format!(
                        "the plan has no {what} '{name}' (its {what}s: {})",
                        if listed.is_empty() {
                            "none".to_string()
                        } else {
                            listed.join(", ")
                        }
                    ),
                });
            }
        }
        Ok(())
    }
}

/// The words of a script line before its comment: the first word starting with `#` and the
/// rest of the line. Names never start with `#` (text-plan actions and condition atoms start
/// with a letter, a digit or `_`), but they may contain it, e.g. a robot prefix `robot_0#go`.
fn statement(line: &str) -> Vec<&str> {
    line.split_whitespace()
        .take_while(|w| !w.starts_with('#'))
        .collect()
}

/// The [`Environment`] the simulator runs a plan against.
#[derive(Debug, Clone)]
pub struct ScriptedEnv<'s> {
    script: &'s Script,
    step: u64,
    count: HashMap<String, i64>,
}

impl<'s> ScriptedEnv<'s> {
    /// An environment at step 0 with no action stepped yet.
    pub fn new(script: &'s Script) -> Self {
        ScriptedEnv {
            script,
            step: 0,
            count: HashMap::new(),
        }
    }

    /// Sets the number of the step about to be computed (for `cond` lines).
    pub fn set_step(&mut self, step: u64) {
        self.step = step;
    }

    fn reached(&self, name: &str, n: Option<&i64>) -> bool {
        match n {
            Some(&n) if n >= 0 => self.count.get(name).copied().unwrap_or(0) >= n,
            _ => false,
        }
    }
}

impl Environment for ScriptedEnv<'_> {
    fn condition(&mut self, name: &str) -> Option<bool> {
        let ranges = self.script.conds.get(name);
        Some(ranges.is_some_and(|r| r.iter().any(|&(a, b)| (a..=b).contains(&self.step))))
    }
    fn step_action(&mut self, name: &str) {
        *self.count.entry(name.to_string()).or_insert(0) += 1;
    }
    fn action_finished(&mut self, name: &str) -> bool {
        self.reached(name, Some(self.script.finish.get(name).unwrap_or(&2)))
    }
    fn action_failed(&mut self, name: &str) -> bool {
        self.reached(name, self.script.fail.get(name))
    }
    fn call(&mut self, name: &str, kind: CallKind) {
        if kind == CallKind::Start {
            self.count.insert(name.to_string(), 0);
        }
    }
}

fn marking_json(plan: &Plan, state: &PlanState) -> String {
    let mut m: BTreeMap<&str, u32> = BTreeMap::new();
    for (p, n) in state.marked() {
        *m.entry(plan.places()[p].label.as_str()).or_default() += n;
    }
    serde_json::to_string(&m).expect("a map of strings to numbers serialises")
}

/// Runs `plan` from its initial state against `script` for at most
/// `max_steps` steps (usually [`DEFAULT_MAX_STEPS`]) (stopping at goal or fail), writing the JSON lines
/// described in the module docs to `out`. Returns the final status.
pub fn simulate(
    plan: &Plan,
    script: &Script,
    max_steps: u64,
    out: &mut dyn Write,
) -> io::Result<PlanStatus> {
    let mut state = PlanState::new(plan);
    let mut env = ScriptedEnv::new(script);
    writeln!(
        out,
        "{{\"step\":0,\"marking\":{}}}",
        marking_json(plan, &state)
    )?;
    let mut k = 0;
    while state.status(plan) == PlanStatus::Running && k < max_steps {
        k += 1;
        env.set_step(k);
        let report = step(plan, &mut state, &mut env);
        let calls: Vec<String> = report.calls.iter().map(ToString::to_string).collect();
        let calls = serde_json::to_string(&calls).expect("strings serialise");
        writeln!(
            out,
            "{{\"step\":{k},\"calls\":{calls},\"marking\":{}}}",
            marking_json(plan, &state)
        )?;
        // As a mission would: a place past the token limit stops the plan as failed.
        if let Some(why) = state.runaway(plan) {
            let why = serde_json::to_string(&why).expect("strings serialise");
            writeln!(out, "{{\"result\":\"fail\",\"step\":{k},\"reason\":{why}}}")?;
            return Ok(PlanStatus::Fail);
        }
    }
    let status = state.status(plan);
    writeln!(out, "{{\"result\":\"{}\",\"step\":{k}}}", status.as_str())?;
    Ok(status)
}
