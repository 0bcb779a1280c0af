//! Execution rules: `*if* COND *during* ACTION *do* R1; R2; END`.
//!
//! `COND` is a condition in prefix syntax, or `action_failed` (the rule then
//! fires on `ACTION.fail` instead of `ACTION.interrupt [COND]`). `ACTION`
//! matches a plan action by full name or by the name before its first `_`.
//! `END` is `restart_action`, `skip_action`, `restart_plan`, `fail_plan` or
//! `goal`. In a rules file each non-blank line not starting with `#` is one
//! rule; inline rules (`A ! *if* C *do* ... !`) may leave out `*during*`.

use super::syntax_error;
use crate::condition::{parse_condition, Cond};
use crate::error::PlanError;

/// How a recovery ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RuleEnd {
    RestartAction,
    SkipAction,
    RestartPlan,
    FailPlan,
    Goal,
}

impl RuleEnd {
    pub fn parse(w: &str) -> Option<RuleEnd> {
        Some(match w {
            "restart_action" => RuleEnd::RestartAction,
            "skip_action" => RuleEnd::SkipAction,
            "restart_plan" => RuleEnd::RestartPlan,
            "fail_plan" => RuleEnd::FailPlan,
            "goal" => RuleEnd::Goal,
            _ => return None,
        })
    }
}

/// A parsed rule.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Rule {
    /// `None` for `action_failed`.
    pub cond: Option<Cond<String>>,
    pub during: Option<String>,
    /// Where `during`'s action name is written (a byte offset into the rules file).
    pub during_at: usize,
    pub recovery: Vec<String>,
    pub end: RuleEnd,
    /// Where it is written (`file:line`) and its text, for messages.
    pub origin: String,
}

impl Rule {
    /// Whether the rule applies to plan action `name`.
    pub fn matches(&self, name: &str) -> bool {
        self.during
            .as_deref()
            .is_some_and(|d| d == name || name.split('_').next() == Some(d))
    }
}

/// Parses every rule of a rules file.
pub(crate) fn parse_rules(src: &str, file: &str) -> Result<Vec<Rule>, PlanError> {
    let mut out = Vec::new();
    let mut offset = 0;
    for line in src.split_inclusive('\n') {
        let t = line.trim();
        if !t.is_empty() && !t.starts_with('#') {
            let body = line.trim_end_matches(['\n', '\r']);
            out.push(parse_rule(src, file, offset, body, true)?);
        }
        offset += line.len();
    }
    Ok(out)
}

/// Parses one rule: `text` is the slice of `src` starting at byte `base`.
pub(crate) fn parse_rule(
    src: &str,
    file: &str,
    base: usize,
    text: &str,
    need_during: bool,
) -> Result<Rule, PlanError> {
    let err = |at: usize, m: String| syntax_error(src, file, base + at, m);
    let lead = text.len() - text.trim_start().len();
    if !text[lead..].starts_with("*if*") {
        return Err(err(
            lead,
            "expected a rule '*if* COND *during* ACTION *do* ...'".into(),
        ));
    }
    let cond_start = lead + 4;
    let do_at = text[cond_start..]
        .find("*do*")
        .map(|i| i + cond_start)
        .ok_or_else(|| err(text.len(), "expected '*do*' after the condition".into()))?;
    let during_at = text[cond_start..do_at]
        .find("*during*")
        .map(|i| i + cond_start);
    let mut name_at = base;
    let (cond_end, during) = match during_at {
        Some(d) => {
            let written = &text[d + 8..do_at];
            let action = written.trim();
            name_at = base + d + 8 + (written.len() - written.trim_start().len());
            if action.is_empty() || action.contains(char::is_whitespace) {
                return Err(err(
                    d + 8,
                    format!("expected one action name after '*during*', found '{action}'"),
                ));
            }
            (d, Some(action.to_string()))
        }
        None if need_during => {
            return Err(err(
                do_at,
                "expected '*during* ACTION' before '*do*'".into(),
            ))
        }
        None => (do_at, None),
    };
    let cond_text = &text[cond_start..cond_end];
    let cond = if cond_text.trim() == "action_failed" {
        None
    } else {
        match parse_condition(cond_text) {
            Ok(Cond::True) => {
                return Err(err(cond_start, "expected a condition after '*if*'".into()))
            }
            Ok(c) => Some(c),
            Err(e) => {
                let col = cond_text
                    .char_indices()
                    .nth(e.column - 1)
                    .map_or(cond_text.len(), |(i, _)| i);
                return Err(err(
                    cond_start + col,
                    format!("bad condition: {}", e.message),
                ));
            }
        }
    };
    let mut recovery = Vec::new();
    let mut end = None;
    let mut at = do_at + 4;
    for part in text[do_at + 4..].split(';') {
        let word = part.trim();
        let word_at = at + (part.len() - part.trim_start().len());
        at += part.len() + 1;
        if word.is_empty() {
            continue;
        }
        if end.is_some() {
            return Err(err(
                word_at,
                format!("'{word}' follows the end of the recovery"),
            ));
        }
        if !word.chars().all(super::lexer::is_word_char) {
            return Err(err(
                word_at,
                format!("expected an action name, found '{word}'"),
            ));
        }
        match RuleEnd::parse(word) {
            Some(e) => end = Some(e),
            None => recovery.push(word.trim_end_matches('*').to_string()),
        }
    }
    let end = end.ok_or_else(|| {
        err(
            text.trim_end().len(),
            "expected the recovery to end with restart_action, skip_action, restart_plan, fail_plan or goal".into(),
        )
    })?;
    let (line, _) = super::line_col(src, base + lead);
    Ok(Rule {
        cond,
        during,
        during_at: name_at,
        recovery,
        end,
        origin: format!("{file}:{line} (`{}`)", text.trim()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_rules() {
        let src = "# c\n*if* (and a (not b)) *during* goto *do* say_x; wait*; restart_action\n\n*if* action_failed *during* say *do* fail_plan\n";
        let rules = parse_rules(src, "r.er").unwrap();
        assert_eq!(rules.len(), 2);
        assert_eq!(rules[0].during.as_deref(), Some("goto"));
        assert_eq!(rules[0].recovery, ["say_x", "wait"]);
        assert_eq!(rules[0].end, RuleEnd::RestartAction);
        assert!(
            rules[0].matches("goto_printer")
                && rules[0].matches("goto")
                && !rules[0].matches("gotox")
        );
        assert_eq!(rules[1].cond, None);
    }

    #[test]
    fn rule_errors_have_positions() {
        let e = parse_rules("\n*if* x *during* a *do* b", "r.er")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("r.er:2:25: expected the recovery to end"),
            "{e}"
        );
        let e = parse_rules("*if* (and x *during* a *do* goal", "r.er")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("r.er:1:"), "{e}");
        assert!(e.contains("bad condition"), "{e}");
        let e = parse_rules("*if* x *do* goal", "r.er")
            .unwrap_err()
            .to_string();
        assert!(e.contains("*during*"), "{e}");
    }
}
