//! Parser of text plans into a small syntax tree.

use super::lexer::{Lexer, Tok};
use super::rules::{parse_rule, Rule};
use super::syntax_error;
use crate::condition::{parse_condition, Cond};
use crate::error::PlanError;

/// A plan item; `at` fields are byte offsets for error messages.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Item {
    Action {
        name: String,
        timeout: Option<u32>,
        rules: Vec<Rule>,
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

pub(crate) struct Parser<'a> {
    lx: Lexer<'a>,
    file: &'a str,
}

impl<'a> Parser<'a> {
    pub fn new(src: &'a str, file: &'a str) -> Self {
        Parser {
            lx: Lexer::new(src),
            file,
        }
    }

    fn err<T>(&self, at: usize, m: impl Into<String>) -> Result<T, PlanError> {
        Err(syntax_error(self.lx.src, self.file, at, m))
    }

    fn next(&mut self) -> Result<(usize, Tok), PlanError> {
        self.lx.next().or_else(|at| {
            let c = self.lx.src[at..].chars().next().unwrap_or(' ');
            self.err(at, format!("unexpected character '{c}'"))
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
        let items = self.seq()?;
        match self.next()? {
            (_, Tok::End) => Ok(items),
            (at, t) => self.err(
                at,
                format!(
                    "unexpected {}; expected ';' or the end of the plan",
                    show(&t)
                ),
            ),
        }
    }

    /// Items separated by `;`, up to a token that cannot start an item.
    fn seq(&mut self) -> Result<Vec<Item>, PlanError> {
        let mut items: Vec<Item> = Vec::new();
        loop {
            match self.peek()? {
                (at, Tok::Word(_) | Tok::Punct("<" | "{")) => {
                    let item = self.item()?;
                    let jumped = matches!(
                        items.last(),
                        Some(Item::Goto { .. } | Item::RestartPlan | Item::FailPlan)
                    );
                    if jumped && !matches!(item, Item::Label { .. }) {
                        return self.err(at, "unreachable: only a LABEL_x may follow a jump");
                    }
                    items.push(item);
                }
                _ => return Ok(items),
            }
            match self.peek()? {
                (_, Tok::Punct(";")) => {
                    self.next()?;
                }
                _ => return Ok(items),
            }
        }
    }

    fn item(&mut self) -> Result<Item, PlanError> {
        let (at, tok) = self.next()?;
        match tok {
            Tok::Word(w) => self.word(at, w),
            Tok::Punct("<") => self.choice(),
            Tok::Punct("{") => {
                let mut branches = vec![self.block_rest(at)?];
                while let (_, Tok::Punct("||")) = self.peek()? {
                    self.next()?;
                    match self.next()? {
                        (at, Tok::Punct("{")) => branches.push(self.block_rest(at)?),
                        (at, t) => {
                            return self.err(
                                at,
                                format!("unexpected {}; expected '{{' after '||'", show(&t)),
                            )
                        }
                    }
                }
                Ok(if branches.len() == 1 {
                    Item::Block(branches.pop().unwrap_or_default())
                } else {
                    Item::Parallel(branches)
                })
            }
            t => self.err(
                at,
                format!("unexpected {}; expected an action, '<' or '{{'", show(&t)),
            ),
        }
    }

    fn block_rest(&mut self, open: usize) -> Result<Vec<Item>, PlanError> {
        let items = self.seq()?;
        match self.next()? {
            (_, Tok::Punct("}")) => Ok(items),
            (at, t) => self.err(
                at,
                format!(
                    "unexpected {}; expected '}}' closing the '{{' at {}",
                    show(&t),
                    self.here(open)
                ),
            ),
        }
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
                            "unexpected {}; expected a number of seconds after '|'",
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
        })
    }

    fn choice(&mut self) -> Result<Item, PlanError> {
        let mut branches = Vec::new();
        loop {
            let start = self.lx.pos;
            let Some((base, text)) = self.lx.raw_until('?') else {
                return self.err(start, "expected 'CONDITION ?' in a conditional plan");
            };
            if let Some(bad) = text.find([';', ':', '>', '<']) {
                return self.err(base + bad, "expected '?' after the condition");
            }
            let cond = match parse_condition(text) {
                Ok(Cond::True) => return self.err(base, "expected a condition before '?'"),
                Ok(c) => c,
                Err(e) => {
                    let col = text
                        .char_indices()
                        .nth(e.column - 1)
                        .map_or(text.len(), |(i, _)| i);
                    return self.err(base + col, format!("bad condition: {}", e.message));
                }
            };
            branches.push((cond, self.seq()?));
            match self.next()? {
                (_, Tok::Punct(":")) => {}
                (_, Tok::Punct(">")) => return Ok(Item::Choice(branches)),
                (at, t) => {
                    return self.err(
                        at,
                        format!("unexpected {}; expected ';', ':' or '>'", show(&t)),
                    )
                }
            }
        }
    }
}

fn show(t: &Tok) -> String {
    match t {
        Tok::Word(w) => format!("'{w}'"),
        Tok::Punct(p) => format!("'{p}'"),
        Tok::End => "end of input".into(),
    }
}
