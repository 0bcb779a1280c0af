//! Parser of text plans into a small syntax tree.

use super::lexer::{Lexer, Tok};
use super::rules::{parse_rule, Rule};
use super::{syntax_error, too_deep};
use crate::condition::{parse_condition, Cond};
use crate::error::{PlanError, MAX_DEPTH};

/// A plan item; `at` fields are byte offsets for error messages.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Item {
    Action {
        name: String,
        timeout: Option<u32>,
        rules: Vec<Rule>,
        at: usize,
    },
    Choice(Vec<(Cond<String>, Vec<Item>)>),
    Block(Vec<Item>),
    Parallel(Vec<Vec<Item>>),
    Label {
        name: String,
        at: usize,
    },
    Goto {
        label: String,
        at: usize,
    },
    RestartPlan,
    FailPlan,
}

/// A block or conditional being parsed; `usize` is the byte offset of its `{` or `<`.
enum Open {
    /// `{ seq } || { seq } ...`: the branches closed so far.
    Block(usize, Vec<Vec<Item>>),
    /// `< COND ? seq : ...`: the branches closed so far and the condition of the open one.
    Choice(usize, Vec<(Cond<String>, Vec<Item>)>, Cond<String>),
}

pub(crate) struct Parser<'a> {
    lx: Lexer<'a>,
    file: &'a str,
    /// Blocks and conditionals open around the current item, at most [`MAX_DEPTH`] (the
    /// compiler recurses once per level).
    depth: usize,
    /// Steps written so far, repeats written out: at most [`MAX_STEPS`].
    written: usize,
}

impl<'a> Parser<'a> {
    pub fn new(src: &'a str, file: &'a str) -> Self {
        Parser {
            lx: Lexer::new(src),
            file,
            depth: 0,
            written: 0,
        }
    }

    /// Counts `more` steps written at byte `at`: a plan of more than [`MAX_STEPS`] is refused
    /// where it passes the limit, before its net is built (a few million written-out actions
    /// took gigabytes, and the analysis then ran out of memory).
    fn count(&mut self, more: usize, at: usize) -> Result<(), PlanError> {
        self.written = self.written.saturating_add(more);
        if self.written > MAX_STEPS {
            return self.err(at, format!("the plan passes {MAX_STEPS} steps (actions, labels and gotos, repeats written out) here; a plan may have at most {MAX_STEPS} (split it into sub-plans, or loop with a label and a goto)"));
        }
        Ok(())
    }

    /// Opens one more level at byte `at` (a `{` or a `<`); closed by `leave`.
    fn enter(&mut self, at: usize) -> Result<(), PlanError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(too_deep(self.lx.src, self.file, at));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    fn err<T>(&self, at: usize, m: impl Into<String>) -> Result<T, PlanError> {
        Err(syntax_error(self.lx.src, self.file, at, m))
    }

    fn next(&mut self) -> Result<(usize, Tok), PlanError> {
        self.lx.next().or_else(|at| {
            let c = self.lx.src[at..].chars().next().unwrap_or(' ');
            // A control character (a NUL) shows as nothing: name it by its code.
            let shown = match c.is_control() {
                true => format!("U+{:04X}", u32::from(c)),
                false => format!("'{c}'"),
            };
            self.err(at, format!("unexpected character {shown}"))
        })
    }

    fn peek(&mut self) -> Result<(usize, Tok), PlanError> {
        let save = self.lx.pos;
        let r = self.next();
        self.lx.pos = save;
        r
    }

    /// The whole plan.
    pub fn plan(&mut self) -> Result<Vec<Item>, PlanError> {
        let items = self.nested()?;
        match self.next()? {
            (_, Tok::End) => Ok(items),
            (at, t) => Err(self.unexpected(at, &t, "';' or the end of the plan")),
        }
    }

    /// The top-level sequence, up to a token that cannot continue it.
    ///
    /// Blocks and conditionals nest, but the parser does not recurse: each open one is a
    /// [`Open`] on an explicit stack together with the sequence it interrupts, so nesting costs
    /// heap, not stack; [`MAX_DEPTH`] bounds it for the compiler, which does recurse.
    fn nested(&mut self) -> Result<Vec<Item>, PlanError> {
        let mut stack: Vec<(Open, Vec<Item>)> = Vec::new();
        let mut items: Vec<Item> = Vec::new();
        // Whether the current sequence may go on (at its start, or after a ';').
        let mut more = true;
        loop {
            if more {
                if let (at, Tok::Punct(";")) = self.peek()? {
                    return self.err(
                        at,
                        "expected an action before this ';' (two ';' in a row, or a ';' with nothing before it)",
                    );
                }
                if let (at, Tok::Word(_) | Tok::Punct("<" | "{")) = self.peek()? {
                    let (_, tok) = self.next()?;
                    let item = match tok {
                        Tok::Punct("<") => {
                            self.enter(at)?;
                            let cond = self.condition()?;
                            let open = Open::Choice(at, Vec::new(), cond);
                            stack.push((open, std::mem::take(&mut items)));
                            continue;
                        }
                        Tok::Punct("{") => {
                            self.enter(at)?;
                            stack.push((Open::Block(at, Vec::new()), std::mem::take(&mut items)));
                            continue;
                        }
                        Tok::Word(w) => self.word(at, w)?,
                        _ => unreachable!("peeked a word, '<' or '{{'"),
                    };
                    self.count(1, at)?;
                    self.push(&mut items, item, at)?;
                    more = self.eat(";")?;
                    continue;
                }
            }
            // The current sequence ends here: close what encloses it.
            let Some((open, outer)) = stack.last_mut() else {
                return Ok(items);
            };
            let (at, t) = self.next()?;
            let (item, start) = match open {
                Open::Block(open_at, branches) => {
                    if t != Tok::Punct("}") {
                        return Err(self.unclosed(at, &t, *open_at));
                    }
                    if items.is_empty() {
                        return self.err(
                            *open_at,
                            "empty block '{ }'; expected at least one action inside",
                        );
                    }
                    branches.push(std::mem::take(&mut items));
                    if self.eat("||")? {
                        match self.next()? {
                            (_, Tok::Punct("{")) => {
                                more = true;
                                continue;
                            }
                            (at, t) => return Err(self.unexpected(at, &t, "'{' after '||'")),
                        }
                    }
                    let item = if branches.len() == 1 {
                        let body = branches.pop().unwrap_or_default();
                        match self.repeat()? {
                            Some((n, n_at)) => {
                                if let Some((name, at)) = first_label(&body).filter(|_| n > 1) {
                                    return self.err(at, format!("label '{name}' is inside '{{ ... }} * {n}', which writes the block out {n} times: the label would be defined {n} times (put it before the block, or loop with a label and a goto)"));
                                }
                                let once = steps(&body);
                                let steps = once.saturating_mul(n as usize);
                                if steps > MAX_STEPS {
                                    return self.err(n_at, format!("'{{ ... }} * {n}' writes out {steps} steps; a plan may have at most {MAX_STEPS} (repeat less, or loop with a label and a goto)"));
                                }
                                // The body's steps were counted once as they were read.
                                self.count(steps - once, n_at)?;
                                Item::Block(repeated(body, n))
                            }
                            None => Item::Block(body),
                        }
                    } else {
                        Item::Parallel(std::mem::take(branches))
                    };
                    (item, *open_at)
                }
                Open::Choice(open_at, branches, cond) => {
                    branches.push((
                        std::mem::replace(cond, Cond::True),
                        std::mem::take(&mut items),
                    ));
                    match t {
                        Tok::Punct(":") => {
                            *cond = self.condition()?;
                            more = true;
                            continue;
                        }
                        Tok::Punct(">") => (Item::Choice(std::mem::take(branches)), *open_at),
                        t => return Err(self.unexpected(at, &t, "';', ':' or '>'")),
                    }
                }
            };
            items = std::mem::take(outer);
            stack.pop();
            self.leave();
            self.push(&mut items, item, start)?;
            more = self.eat(";")?;
        }
    }

    /// Appends `item` (starting at byte `at`) to a sequence: only a label may follow a jump.
    fn push(&self, items: &mut Vec<Item>, item: Item, at: usize) -> Result<(), PlanError> {
        let jumped = matches!(
            items.last(),
            Some(Item::Goto { .. } | Item::RestartPlan | Item::FailPlan)
        );
        if jumped && !matches!(item, Item::Label { .. }) {
            return self.err(at, "unreachable: only a LABEL_x may follow a jump");
        }
        items.push(item);
        Ok(())
    }

    /// Consumes the next token if it is `punct`.
    fn eat(&mut self, punct: &'static str) -> Result<bool, PlanError> {
        let found = self.peek()?.1 == Tok::Punct(punct);
        if found {
            self.next()?;
        }
        Ok(found)
    }

    fn unexpected(&self, at: usize, t: &Tok, expected: &str) -> PlanError {
        syntax_error(
            self.lx.src,
            self.file,
            at,
            format!("unexpected {}; expected {expected}", show(t)),
        )
    }

    fn unclosed(&self, at: usize, t: &Tok, open: usize) -> PlanError {
        let expected = format!("'}}' closing the '{{' at {}", self.here(open));
        self.unexpected(at, t, &expected)
    }

    fn here(&self, at: usize) -> String {
        let (l, c) = super::line_col(self.lx.src, at);
        format!("{l}:{c}")
    }

    fn word(&mut self, at: usize, w: String) -> Result<Item, PlanError> {
        if let Some(label) = w.strip_prefix("GOTO_") {
            if !label.starts_with("LABEL_") {
                return self.err(at, format!("'{w}': expected GOTO_LABEL_name"));
            }
            return Ok(Item::Goto {
                label: label.to_string(),
                at,
            });
        }
        if w.starts_with("LABEL_") {
            return Ok(Item::Label { name: w, at });
        }
        match w.as_str() {
            "restart_plan" => return Ok(Item::RestartPlan),
            "fail_plan" => return Ok(Item::FailPlan),
            _ => {}
        }
        if !w.starts_with(|c: char| c.is_alphanumeric() || c == '_') || w.contains('*') {
            return self.err(at, format!("'{w}' is not an action name"));
        }
        let mut timeout = None;
        if let (_, Tok::Punct("|")) = self.peek()? {
            self.next()?;
            match self.next()? {
                (_, Tok::Word(n)) if n.parse::<u32>().is_ok() => timeout = n.parse().ok(),
                (at, t) => {
                    return self.err(
                        at,
                        format!(
                            "unexpected {}; expected a whole number of seconds after '|' (0 to 4294967295)",
                            show(&t)
                        ),
                    )
                }
            }
        }
        let mut rules = Vec::new();
        while let (bang, Tok::Punct("!")) = self.peek()? {
            self.next()?;
            let Some((base, text)) = self.lx.raw_until('!') else {
                return self.err(bang, "inline rule without its closing '!'");
            };
            rules.push(parse_rule(self.lx.src, self.file, base, text, false)?);
        }
        Ok(Item::Action {
            name: w,
            timeout,
            rules,
            at,
        })
    }

    /// `* N` after a block: how many times to run it (the block is written out N times).
    fn repeat(&mut self) -> Result<Option<(u32, usize)>, PlanError> {
        let (at, Tok::Word(w)) = self.peek()? else {
            return Ok(None);
        };
        let Some(glued) = w.strip_prefix('*') else {
            return Ok(None);
        };
        self.next()?;
        let (n_at, n) = if glued.is_empty() {
            match self.next()? {
                (n_at, Tok::Word(n)) => (n_at, n),
                (n_at, t) => return Err(self.unexpected(n_at, &t, "a number of times after '*'")),
            }
        } else {
            (at + 1, glued.to_string())
        };
        match n.parse::<u32>() {
            Ok(k) if (1..=MAX_REPEAT).contains(&k) => Ok(Some((k, n_at))),
            _ => self.err(
                n_at,
                format!("'{n}': expected a number of times from 1 to {MAX_REPEAT} after '*'"),
            ),
        }
    }

    /// `COND ?` of a conditional.
    fn condition(&mut self) -> Result<Cond<String>, PlanError> {
        let start = self.lx.pos;
        let Some((base, text)) = self.lx.raw_until('?') else {
            return self.err(start, "expected 'CONDITION ?' in a conditional plan");
        };
        if let Some(bad) = text.find([';', ':', '>', '<']) {
            return self.err(base + bad, "expected '?' after the condition");
        }
        match parse_condition(text) {
            Ok(Cond::True) => self.err(base, "expected a condition before '?'"),
            Ok(c) => Ok(c),
            Err(e) => {
                let col = text
                    .char_indices()
                    .nth(e.column - 1)
                    .map_or(text.len(), |(i, _)| i);
                self.err(base + col, format!("bad condition: {}", e.message))
            }
        }
    }
}

/// The most times `{ ... } * N` may repeat a block.
pub(crate) const MAX_REPEAT: u32 = 1000;

/// The most steps (actions, labels, gotos) a plan may have once its repeats are written out:
/// nested repeats multiply, and `{ { a } * 1000 } * 1000` would be a million actions.
pub(crate) const MAX_STEPS: usize = 100_000;

/// The steps `items` holds, counted through blocks, branches and parallels.
fn steps(items: &[Item]) -> usize {
    items
        .iter()
        .map(|item| match item {
            Item::Choice(branches) => branches.iter().map(|(_, b)| steps(b)).sum(),
            Item::Block(body) => steps(body),
            Item::Parallel(branches) => branches.iter().map(|b| steps(b)).sum(),
            _ => 1,
        })
        .fold(0, usize::saturating_add)
}

/// The first label in `items`, nested blocks included: its name and where it is written.
fn first_label(items: &[Item]) -> Option<(&str, usize)> {
    items.iter().find_map(|item| match item {
        Item::Label { name, at } => Some((name.as_str(), *at)),
        Item::Block(body) => first_label(body),
        Item::Choice(branches) => branches.iter().find_map(|(_, b)| first_label(b)),
        Item::Parallel(branches) => branches.iter().find_map(|b| first_label(b)),
        _ => None,
    })
}

/// `body` written out `n` times, one after the other.
fn repeated(body: Vec<Item>, n: u32) -> Vec<Item> {
    let mut out = Vec::with_capacity(body.len() * n as usize);
    for _ in 1..n {
        out.extend(body.iter().cloned());
    }
    out.extend(body);
    out
}

fn show(t: &Tok) -> String {
    match t {
        Tok::Word(w) => format!("'{w}'"),
        Tok::Punct(p) => format!("'{p}'"),
        Tok::End => "end of input".into(),
    }
}
