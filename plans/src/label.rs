//! Place and transition labels.
//!
//! A label is split into words on spaces that are not inside `(...)` or
//! `[...]`. Place words: `A.exec` / `A.ex` / legacy `ex.A` (execution place
//! of `A`), `goal`, `goal(n)`, `fail`, `fail(n)`; any other word is ignored.
//! Transition words: at most one guard `[COND]`, calls `A.start`, `A.end`,
//! `A.interrupt`/`A.interr`, `A.resume`/`A.res`, `A.fail`, and the bare forms
//! `start`/`resume` (every execution place among the outputs) and
//! `end`/`interrupt`/`fail` (every execution place among the inputs); other
//! words without a dot are ignored, a dotted word with another function is an
//! error. The executable name is the text before the **last** dot.

use std::fmt;

/// A call a transition makes on an executable when it fires.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CallKind {
    /// `A.start`: (re)start `A`; its step count restarts from 0.
    Start,
    /// `A.end`: `A` finished and is done with.
    End,
    /// `A.interrupt`: suspend `A`; it is kept and may be resumed.
    Interrupt,
    /// `A.resume`: continue an interrupted `A`.
    Resume,
    /// `A.fail`: `A` failed and is done with.
    Fail,
}

impl CallKind {
    /// The canonical function name, as in `A.start`.
    pub fn as_str(self) -> &'static str {
        match self {
            CallKind::Start => "start",
            CallKind::End => "end",
            CallKind::Interrupt => "interrupt",
            CallKind::Resume => "resume",
            CallKind::Fail => "fail",
        }
    }

    pub(crate) fn parse(f: &str) -> Option<CallKind> {
        Some(match f {
            "start" => CallKind::Start,
            "end" => CallKind::End,
            "interrupt" | "interr" => CallKind::Interrupt,
            "resume" | "res" => CallKind::Resume,
            "fail" => CallKind::Fail,
            _ => return None,
        })
    }

    /// Whether a bare call refers to the output execution places
    /// (`start`, `resume`) rather than the input ones.
    pub(crate) fn bare_uses_outputs(self) -> bool {
        matches!(self, CallKind::Start | CallKind::Resume)
    }
}

impl fmt::Display for CallKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Splits a label into words on spaces outside `(...)` and `[...]`.
pub fn split_label(label: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut start = None;
    for (i, c) in label.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            _ => {}
        }
        if c.is_whitespace() && depth <= 0 {
            if let Some(s) = start.take() {
                out.push(&label[s..i]);
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        out.push(&label[s..]);
    }
    out
}

/// What a place label says.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct PlaceLabel {
    pub exec: Option<String>,
    pub goal: u32,
    pub fail: u32,
}

fn marking_word(word: &str, key: &str) -> Result<Option<u32>, String> {
    let Some(rest) = word.strip_prefix(key) else {
        return Ok(None);
    };
    if rest.is_empty() {
        return Ok(Some(1));
    }
    let Some(n) = rest.strip_prefix('(').and_then(|r| r.strip_suffix(')')) else {
        return Ok(None);
    };
    match n.trim().parse::<u32>() {
        Ok(n) if n > 0 => Ok(Some(n)),
        _ => Err(format!(
            "'{word}': expected {key}(N) with N a positive number"
        )),
    }
}

pub(crate) fn parse_place_label(label: &str) -> Result<PlaceLabel, String> {
    let mut out = PlaceLabel::default();
    for word in split_label(label) {
        if let Some(n) = marking_word(word, "goal")? {
            out.goal += n;
        } else if let Some(n) = marking_word(word, "fail")? {
            out.fail += n;
        } else if let Some(name) = exec_name(word) {
            if let Some(prev) = &out.exec {
                if prev != name {
                    return Err(format!(
                        "two execution places in one label: '{prev}' and '{name}'"
                    ));
                }
            }
            out.exec = Some(name.to_string());
        }
    }
    Ok(out)
}

fn exec_name(word: &str) -> Option<&str> {
    if let Some((name, f)) = word.rsplit_once('.') {
        if (f == "exec" || f == "ex") && !name.is_empty() {
            return Some(name);
        }
    }
    word.strip_prefix("ex.").filter(|n| !n.is_empty())
}

/// Who a call in a transition label is addressed to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum CallTarget {
    /// `A.start`.
    Named(String),
    /// Bare `start` etc.: resolved against the transition's places.
    Bare,
}

/// What a transition label says.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct TransitionLabel {
    /// The guard text without the brackets, if there is a guard.
    pub guard: Option<String>,
    pub calls: Vec<(CallTarget, CallKind)>,
}

pub(crate) fn parse_transition_label(label: &str) -> Result<TransitionLabel, String> {
    let mut out = TransitionLabel::default();
    for word in split_label(label) {
        // Tolerate a guard glued to a call (`A.end[x]`).
        let (word, guard) = match word.find('[') {
            Some(0) | None => (word, None),
            Some(i) => (&word[..i], Some(&word[i..])),
        };
        for w in [Some(word), guard].into_iter().flatten() {
            if let Some(inner) = w.strip_prefix('[') {
                let Some(inner) = inner.strip_suffix(']') else {
                    return Err(format!("guard '{w}' has no closing ']'"));
                };
                if out.guard.is_some() {
                    return Err("more than one guard [..]; combine them with (and ..)".into());
                }
                out.guard = Some(inner.to_string());
            } else if let Some((name, f)) = w.rsplit_once('.') {
                let Some(kind) = CallKind::parse(f) else {
                    return Err(format!(
                        "unknown function '{f}' in '{w}'; expected start, end, interrupt, interr, resume, res or fail"
                    ));
                };
                if name.is_empty() {
                    return Err(format!("'{w}' has no executable name before the dot"));
                }
                out.calls.push((CallTarget::Named(name.to_string()), kind));
            } else if let Some(kind) = CallKind::parse(w) {
                out.calls.push((CallTarget::Bare, kind));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split() {
        assert_eq!(
            split_label("a.end [and x (or y z)]  b.start"),
            ["a.end", "[and x (or y z)]", "b.start"]
        );
        assert_eq!(split_label("   "), Vec::<&str>::new());
        assert_eq!(split_label("goal(2) fail"), ["goal(2)", "fail"]);
    }

    #[test]
    fn place_labels() {
        let p = |l: &str| parse_place_label(l).unwrap();
        assert_eq!(p("A.exec").exec.as_deref(), Some("A"));
        assert_eq!(p("A.ex").exec.as_deref(), Some("A"));
        assert_eq!(p("ex.A").exec.as_deref(), Some("A"));
        assert_eq!(
            p("gotopose_6_2_0.exec").exec.as_deref(),
            Some("gotopose_6_2_0")
        );
        assert_eq!(
            p("robot_0#pathLeft.exec").exec.as_deref(),
            Some("robot_0#pathLeft")
        );
        assert_eq!(p("a.b.exec").exec.as_deref(), Some("a.b"));
        assert_eq!(
            p("goal"),
            PlaceLabel {
                exec: None,
                goal: 1,
                fail: 0
            }
        );
        assert_eq!(
            p("fail(3)"),
            PlaceLabel {
                exec: None,
                goal: 0,
                fail: 3
            }
        );
        assert_eq!(
            p("A.ex goal(1) fail(1)"),
            PlaceLabel {
                exec: Some("A".into()),
                goal: 1,
                fail: 1
            }
        );
        for plain in ["init", "X12", " ", "GOAL", "Goal", "goals", "init.start"] {
            assert_eq!(p(plain), PlaceLabel::default(), "{plain}");
        }
        assert!(parse_place_label("goal(x)").is_err());
        assert!(parse_place_label("a.ex b.ex").is_err());
    }

    #[test]
    fn transition_labels() {
        let t = |l: &str| parse_transition_label(l).unwrap();
        let named = |n: &str, k| (CallTarget::Named(n.into()), k);
        assert_eq!(t("[]").guard.as_deref(), Some(""));
        assert_eq!(t("Fork").calls, []);
        let l = t("[int1] action2.end action1c.interr");
        assert_eq!(l.guard.as_deref(), Some("int1"));
        assert_eq!(
            l.calls,
            [
                named("action2", CallKind::End),
                named("action1c", CallKind::Interrupt)
            ]
        );
        assert_eq!(t("start").calls, [(CallTarget::Bare, CallKind::Start)]);
        assert_eq!(t("a.res b.resume c.fail d.interrupt").calls.len(), 4);
        assert_eq!(t("sense.end[obstacle]").guard.as_deref(), Some("obstacle"));
        assert!(parse_transition_label("a.stop")
            .unwrap_err()
            .contains("unknown function 'stop'"));
        assert!(parse_transition_label("[a] [b]").is_err());
    }
}
