//! Compiling the syntax tree into a net with PNPgen's structure.

use std::collections::HashMap;

use super::layout::layout;
use super::parse::{Item, Parser};
use super::rules::{parse_rules, Rule, RuleEnd};
use super::syntax_error;
use crate::build::{ArcEnd, RawArc, RawNet, RawPlace, RawTransition};
use crate::condition::Cond;
use crate::error::PlanError;
use crate::model::Plan;

/// Where a plan action sits, for execution rules.
struct Occurrence {
    name: std::sync::Arc<str>,
    before: usize,
    exec: usize,
    after: usize,
}

struct Net<'a> {
    raw: RawNet,
    src: &'a str,
    lines: petrel_actors::LineIndex,
    file: &'a str,
    init: usize,
    goal: Option<usize>,
    fail: Option<usize>,
    labels: HashMap<String, usize>,
    gotos: Vec<(usize, String, usize)>,
    occurrences: Vec<Occurrence>,
    inline: Vec<(usize, Rule)>,
    sources: crate::model::Sources,
}

impl Net<'_> {
    fn place(&mut self, label: &str) -> usize {
        let i = self.raw.places.len();
        let label = if label.is_empty() {
            format!("X{i}")
        } else {
            label.to_string()
        };
        self.raw.places.push(RawPlace {
            id: format!("p{i}"),
            label,
            initial: 0,
            position: None,
        });
        i
    }

    fn arc(&mut self, source: ArcEnd, target: ArcEnd) {
        self.raw.arcs.push(RawArc {
            id: None,
            source,
            target,
            weight: 1,
        });
    }

    fn trans(&mut self, label: &str, ins: &[usize], outs: &[usize]) -> usize {
        let i = self.raw.transitions.len();
        let id = format!("t{i}");
        self.raw.transitions.push(RawTransition {
            id,
            label: label.to_string(),
            position: None,
        });
        for &p in ins {
            self.arc(ArcEnd::Place(p as u32), ArcEnd::Transition(i as u32));
        }
        for &p in outs {
            self.arc(ArcEnd::Transition(i as u32), ArcEnd::Place(p as u32));
        }
        i
    }

    /// `cur -> A.start -> A.exec -> A.end -> after`; returns (exec, after).
    fn action(&mut self, cur: usize, name: &str) -> (usize, usize) {
        let exec = self.place(&format!("{name}.exec"));
        self.trans(&format!("{name}.start"), &[cur], &[exec]);
        let after = self.place("");
        self.trans(&format!("{name}.end"), &[exec], &[after]);
        (exec, after)
    }

    // seq, item, choice and parallel recurse once per nesting level: they keep their frames
    // small (labels and errors are built in separate functions), so a debug build compiles
    // MAX_DEPTH levels in well under a megabyte of stack.

    fn seq(&mut self, mut cur: Option<usize>, items: &[Item]) -> Result<Option<usize>, PlanError> {
        for item in items {
            if let Item::Label { name, at } = item {
                cur = Some(self.label(cur, name, *at)?);
                continue;
            }
            // Only reachable through a conditional whose branches all jump.
            let c = match cur {
                Some(p) => p,
                None => self.place(""),
            };
            cur = self.item(c, item)?;
        }
        Ok(cur)
    }

    #[inline(never)]
    fn label(&mut self, cur: Option<usize>, name: &str, at: usize) -> Result<usize, PlanError> {
        let here = match cur {
            Some(p) => p,
            None => self.place(""),
        };
        if self.labels.insert(name.to_string(), here).is_some() {
            return Err(syntax_error(
                self.src,
                self.file,
                at,
                format!("label '{name}' defined twice"),
            ));
        }
        Ok(here)
    }

    fn item(&mut self, cur: usize, item: &Item) -> Result<Option<usize>, PlanError> {
        match item {
            Item::Choice(branches) => self.choice(cur, branches),
            Item::Block(body) => self.seq(Some(cur), body),
            Item::Parallel(branches) => self.parallel(cur, branches),
            leaf => Ok(self.leaf(cur, leaf)),
        }
    }

    fn choice(
        &mut self,
        cur: usize,
        branches: &[(Cond<String>, Vec<Item>)],
    ) -> Result<Option<usize>, PlanError> {
        let mut ends = Vec::new();
        for (cond, body) in branches {
            let start = self.branch(cur, cond);
            ends.extend(self.seq(Some(start), body)?);
        }
        let merge = self.place("");
        for e in ends {
            self.trans(" ", &[e], &[merge]);
        }
        Ok(Some(merge))
    }

    /// A `[COND]` transition from `cur` to a new place, returned.
    #[inline(never)]
    fn branch(&mut self, cur: usize, cond: &Cond<String>) -> usize {
        let start = self.place("");
        self.trans(&format!("[{cond}]"), &[cur], &[start]);
        start
    }

    fn parallel(&mut self, cur: usize, branches: &[Vec<Item>]) -> Result<Option<usize>, PlanError> {
        let starts: Vec<usize> = branches.iter().map(|_| self.place("")).collect();
        self.trans("[]", &[cur], &starts);
        let mut ends = Vec::new();
        for (s, body) in starts.iter().zip(branches) {
            ends.extend(self.seq(Some(*s), body)?);
        }
        let next = self.place("");
        self.trans("[]", &ends, &[next]);
        Ok(Some(next))
    }

    /// An item without nested items.
    #[inline(never)]
    fn leaf(&mut self, cur: usize, item: &Item) -> Option<usize> {
        match item {
            Item::Action {
                name,
                timeout: None,
                rules,
                at,
            } => {
                let (name, line) = self.written(name, *at);
                let (exec, after) = self.action(cur, &name);
                self.own_last(2, &name, line);
                self.occurrence(name, cur, exec, after, rules);
                Some(after)
            }
            Item::Action {
                name,
                timeout: Some(secs),
                rules,
                at,
            } => {
                let (name, line) = self.written(name, *at);
                let (pa, pw) = (self.place(""), self.place(""));
                self.trans("[]", &[cur], &[pa, pw]);
                let (exec, end_a) = self.action(pa, &name);
                self.own_last(2, &name, line);
                self.occurrence(name.clone(), pa, exec, end_a, rules);
                let wait = format!("wait_{secs}");
                let (wexec, end_w) = self.action(pw, &wait);
                let next = self.place("");
                self.trans(&format!("{wait}.interrupt []"), &[wexec, end_a], &[next]);
                self.trans(&format!("{name}.interrupt []"), &[exec, end_w], &[next]);
                // Both ended in the same step: nothing is left to interrupt.
                self.trans("[]", &[end_a, end_w], &[next]);
                Some(next)
            }
            Item::Goto { label, at } => {
                let t = self.trans(" ", &[cur], &[]);
                self.gotos.push((t, label.clone(), *at));
                None
            }
            Item::RestartPlan => {
                let init = self.init;
                self.trans(" ", &[cur], &[init]);
                None
            }
            Item::FailPlan => {
                let fail = self.fail_place();
                self.trans(" ", &[cur], &[fail]);
                None
            }
            Item::Label { .. } | Item::Choice(_) | Item::Block(_) | Item::Parallel(_) => Some(cur),
        }
    }

    fn occurrence(
        &mut self,
        name: std::sync::Arc<str>,
        before: usize,
        exec: usize,
        after: usize,
        rules: &[Rule],
    ) {
        self.occurrences.push(Occurrence {
            name,
            before,
            exec,
            after,
        });
        let i = self.occurrences.len() - 1;
        self.inline.extend(rules.iter().map(|r| (i, r.clone())));
    }

    /// Records where action `name` is written (its first occurrence); returns the one shared
    /// copy of its name and the line of this occurrence.
    fn written(&mut self, name: &str, at: usize) -> (std::sync::Arc<str>, u32) {
        let line = self.lines.line(at) as u32;
        let lines = &mut self.sources.action_lines;
        let name = match lines.get_key_value(name) {
            Some((shared, _)) => shared.clone(),
            None => {
                let shared: std::sync::Arc<str> = name.into();
                lines.insert(shared.clone(), line);
                shared
            }
        };
        (name, line)
    }

    /// Marks the last `n` transitions made as action `name`'s (written at `line`).
    fn own_last(&mut self, n: usize, name: &std::sync::Arc<str>, line: u32) {
        let len = self.raw.transitions.len();
        let origin = crate::model::Origin::Action {
            name: name.clone(),
            line,
        };
        self.sources.mark(len.saturating_sub(n), len, origin);
    }

    fn fail_place(&mut self) -> usize {
        match self.fail {
            Some(f) => f,
            None => {
                let f = self.place("fail");
                self.fail = Some(f);
                f
            }
        }
    }

    /// Refuses `rule` (of rules file `f`, `text`) if applying it would take the net past
    /// [`MAX_TRANSITIONS`]: a rule applies to every occurrence of the actions it names, so a
    /// thousand rules on an action of a 20,000-step plan wrote twenty million recoveries and ran
    /// out of memory.
    fn check_growth(&self, rule: &Rule, text: &str, f: &str) -> Result<(), PlanError> {
        let matches = self
            .occurrences
            .iter()
            .filter(|o| rule.matches(&o.name))
            .count();
        // The interrupt, the return, and each recovery action's start and end.
        let each = 2 + 2 * rule.recovery.len();
        let grown = self.raw.transitions.len() + matches.saturating_mul(each);
        if grown <= MAX_TRANSITIONS {
            return Ok(());
        }
        let message = format!(
            "the net would pass {MAX_TRANSITIONS} transitions with this rule ({matches} occurrences of the actions it names, {each} transitions each, after {} already); a plan with its rules may have at most {MAX_TRANSITIONS} (name fewer actions, or split the plan into sub-plans)",
            self.raw.transitions.len()
        );
        Err(syntax_error(text, f, rule.during_at, message))
    }

    fn apply_rule(&mut self, occ: usize, rule: &Rule) {
        let (name, before, exec, after) = {
            let o = &self.occurrences[occ];
            (o.name.clone(), o.before, o.exec, o.after)
        };
        let mut cur = self.place("");
        let label = match &rule.cond {
            None => format!("{name}.fail"),
            Some(c) => format!("{name}.interrupt [{c}]"),
        };
        let first = self.trans(&label, &[exec], &[cur]);
        for r in &rule.recovery {
            cur = self.action(cur, r).1;
        }
        let target = match rule.end {
            RuleEnd::RestartAction => before,
            RuleEnd::SkipAction => after,
            RuleEnd::RestartPlan => self.init,
            RuleEnd::FailPlan => self.fail_place(),
            RuleEnd::Goal => match self.goal {
                Some(g) => g,
                None => {
                    let g = self.place("goal");
                    self.goal = Some(g);
                    g
                }
            },
        };
        let last = self.trans(" ", &[cur], &[target]);
        // Every transition of the recovery is the rule's, for messages.
        let origin = format!("the rule at {} for `{name}`", rule.origin);
        let origin = crate::model::Origin::Rule(origin.into());
        self.sources.mark(first, last + 1, origin);
    }
}

/// The most transitions a text plan's net may have once its execution rules are applied:
/// far above a 100,000-step plan's own net (about 200,000), low enough to be analysed.
pub(crate) const MAX_TRANSITIONS: usize = 1_000_000;

/// Compiles a text plan into a [`Plan`] with PNPgen's net structure (see the
/// `text` module docs for the language and the choices made).
///
/// `file` names the plan in errors, `name` is the plan name, `rules` an
/// optional rules file as (text, file name).
pub fn compile_text(
    src: &str,
    file: &str,
    name: &str,
    rules: Option<(&str, &str)>,
) -> Result<Plan, PlanError> {
    let items = Parser::new(src, file).plan()?;
    if items.is_empty() {
        return Err(syntax_error(
            src,
            file,
            src.len(),
            "empty plan; expected at least one action",
        ));
    }
    let parsed = match rules {
        Some((text, f)) => parse_rules(text, f)?,
        None => Vec::new(),
    };
    let mut net = Net {
        raw: RawNet {
            name: name.to_string(),
            ..RawNet::default()
        },
        src,
        lines: petrel_actors::LineIndex::new(src),
        file,
        init: 0,
        goal: None,
        fail: None,
        labels: HashMap::new(),
        gotos: Vec::new(),
        occurrences: Vec::new(),
        inline: Vec::new(),
        sources: crate::model::Sources {
            file: file.to_string(),
            ..Default::default()
        },
    };
    let init = net.place("init");
    net.raw.places[init].initial = 1;
    if let Some(end) = net.seq(Some(init), &items)? {
        net.raw.places[end].label = "goal".into();
        net.goal = Some(end);
    }
    drop(items); // the net holds everything from here on
    for (t, label, at) in std::mem::take(&mut net.gotos) {
        let Some(&p) = net.labels.get(&label) else {
            return Err(syntax_error(
                src,
                file,
                at,
                format!("no {label} in the plan"),
            ));
        };
        net.arc(ArcEnd::Transition(t as u32), ArcEnd::Place(p as u32));
    }
    for rule in &parsed {
        if let Some((text, f)) = rules {
            net.check_growth(rule, text, f)?;
        }
        let mut applied = false;
        for occ in 0..net.occurrences.len() {
            if rule.matches(&net.occurrences[occ].name) {
                net.apply_rule(occ, rule);
                applied = true;
            }
        }
        // A misspelt action would leave its failure unhandled without a word.
        if let (false, Some(action), Some((text, f))) = (applied, &rule.during, rules) {
            let mut actions: Vec<&str> = net.occurrences.iter().map(|o| &*o.name).collect();
            actions.sort_unstable();
            actions.dedup();
            let message = format!(
                "`*during* {action}`: the plan has no action `{action}` (nor `{action}_...`); its actions: {}",
                actions.join(", ")
            );
            return Err(syntax_error(text, f, rule.during_at, message));
        }
    }
    for (occ, rule) in std::mem::take(&mut net.inline) {
        net.apply_rule(occ, &rule);
    }
    layout(&mut net.raw);
    let mut plan = Plan::build(net.raw, file)?;
    plan.sources = net.sources;
    Ok(plan)
}
