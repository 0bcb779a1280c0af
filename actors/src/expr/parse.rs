//! The parser: tokens to an [`Ast`] with spans, by precedence climbing.
//!
//! Precedence, loosest first: `or`/`||`, `and`/`&&`, `not`/`!`, comparisons (not chained),
//! `+ -`, `* /`, unary `-`, field access `.name`, then literals, paths, calls and parentheses.

use super::lexer::{lex, Tok};
use super::{ExprError, Span, MAX_DEPTH};

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `and`, `&&`
    And,
    /// `or`, `||`
    Or,
}

impl BinOp {
    /// The operator as written (`and`/`or` in words).
    pub fn symbol(self) -> &'static str {
        use BinOp::*;
        match self {
            Add => "+",
            Sub => "-",
            Mul => "*",
            Div => "/",
            Lt => "<",
            Le => "<=",
            Gt => ">",
            Ge => ">=",
            Eq => "==",
            Ne => "!=",
            And => "and",
            Or => "or",
        }
    }
}

/// A built-in function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// `abs(x)`
    Abs,
    /// `min(a, b, ...)`
    Min,
    /// `max(a, b, ...)`
    Max,
    /// `clamp(x, lo, hi)`
    Clamp,
    /// `held(cond, duration)`: `cond` has been true continuously for `duration`.
    Held,
    /// `age(path)`: seconds since the property was last written.
    Age,
    /// `elapsed()`: seconds since the expression's origin (for a plan action's conditions,
    /// the action's start), or since the expression was added when it has none.
    Elapsed,
    /// `len(list)`: the number of elements of a list.
    Len,
}

impl Func {
    fn from_name(name: &str) -> Option<Func> {
        Some(match name {
            "abs" => Func::Abs,
            "min" => Func::Min,
            "max" => Func::Max,
            "clamp" => Func::Clamp,
            "held" => Func::Held,
            "age" => Func::Age,
            "elapsed" => Func::Elapsed,
            "len" => Func::Len,
            _ => return None,
        })
    }
}

/// An expression node with the span of source it covers.
#[derive(Debug, Clone, PartialEq)]
pub struct Ast {
    /// What the node is.
    pub kind: AstKind,
    /// Where it is in the source.
    pub span: Span,
}

/// The kinds of expression nodes.
#[derive(Debug, Clone, PartialEq)]
pub enum AstKind {
    /// A number (durations are seconds).
    Num(f64),
    /// `true` or `false`.
    Bool(bool),
    /// A string literal.
    Str(String),
    /// A property, as written.
    Path(String),
    /// `base.name`.
    Field(Box<Ast>, String),
    /// Unary minus.
    Neg(Box<Ast>),
    /// `not` / `!`.
    Not(Box<Ast>),
    /// A binary operation.
    Bin(BinOp, Box<Ast>, Box<Ast>),
    /// A function call.
    Call(Func, Vec<Ast>),
}

/// Parses one expression; the whole source must be consumed.
pub fn parse(src: &str) -> Result<Ast, ExprError> {
    let toks = lex(src)?;
    let mut p = Parser {
        src,
        toks,
        pos: 0,
        depth: 0,
    };
    let ast = p.or()?;
    match p.toks.get(p.pos) {
        None => Ok(ast),
        Some((t, s)) => Err(p.err(
            *s,
            format!("unexpected {}; expected an operator or the end", show(t)),
        )),
    }
}

/// Precedences of [`Parser::expr`], loosest first.
const OR: u8 = 1;
const AND: u8 = 2;
const NOT: u8 = 3;
const CMP: u8 = 4;
const ADD: u8 = 5;
const MUL: u8 = 6;

struct Parser<'a> {
    src: &'a str,
    toks: Vec<(Tok, Span)>,
    pos: usize,
    /// Levels open at the current token (see [`MAX_DEPTH`]): the parser recurses once per
    /// parenthesis, call, `not` and `-`, and later passes recurse once per tree level.
    depth: usize,
}

fn show(t: &Tok) -> String {
    match t {
        Tok::Num(n) => format!("number `{n}`"),
        Tok::Str(s) => format!("string {s:?}"),
        Tok::Path(p) => format!("property `{p}`"),
        Tok::Word(w) => format!("`{w}`"),
        Tok::Op(o) => format!("`{o}`"),
    }
}

impl Parser<'_> {
    fn err(&self, span: Span, msg: impl Into<String>) -> ExprError {
        ExprError::at(self.src, span.start, msg)
    }

    /// Opens one more level at `span`; closed by `leave`.
    fn enter(&mut self, span: Span) -> Result<(), ExprError> {
        if self.depth == MAX_DEPTH {
            return Err(self.err(span, format!("nesting deeper than {MAX_DEPTH} levels")));
        }
        self.depth += 1;
        Ok(())
    }

    fn leave(&mut self, levels: usize) {
        self.depth -= levels;
    }

    fn end_span(&self) -> Span {
        Span::new(self.src.len(), self.src.len())
    }

    fn peek_op(&self, ops: &[&str]) -> Option<(&'static str, Span)> {
        match self.toks.get(self.pos) {
            Some((Tok::Op(o), s)) if ops.contains(o) => Some((o, *s)),
            Some((Tok::Word(w), s)) if ops.contains(&w.as_str()) => Some((
                if w == "and" {
                    "and"
                } else if w == "or" {
                    "or"
                } else {
                    "not"
                },
                *s,
            )),
            _ => None,
        }
    }

    fn expect(&mut self, op: &str) -> Result<Span, ExprError> {
        match self.toks.get(self.pos) {
            Some((Tok::Op(o), s)) if *o == op => {
                self.pos += 1;
                Ok(*s)
            }
            Some((t, s)) => Err(self.err(*s, format!("expected `{op}`, found {}", show(t)))),
            None => Err(self.err(self.end_span(), format!("expected `{op}`, found the end"))),
        }
    }

    /// The binary operator at the current token, with its precedence (tighter is higher).
    fn peek_binary(&self) -> Option<(BinOp, u8, Span)> {
        let (op, s) = self.peek_op(&[
            "||", "or", "&&", "and", "<", "<=", ">", ">=", "==", "!=", "+", "-", "*", "/",
        ])?;
        let (op, prec) = match op {
            "||" | "or" => (BinOp::Or, OR),
            "&&" | "and" => (BinOp::And, AND),
            "<" => (BinOp::Lt, CMP),
            "<=" => (BinOp::Le, CMP),
            ">" => (BinOp::Gt, CMP),
            ">=" => (BinOp::Ge, CMP),
            "==" => (BinOp::Eq, CMP),
            "!=" => (BinOp::Ne, CMP),
            "+" => (BinOp::Add, ADD),
            "-" => (BinOp::Sub, ADD),
            "*" => (BinOp::Mul, MUL),
            _ => (BinOp::Div, MUL),
        };
        Some((op, prec, s))
    }

    /// An expression whose binary operators bind at least as tightly as `min` (precedence
    /// climbing: one function for every level keeps the recursion per parenthesis short).
    fn expr(&mut self, min: u8) -> Result<Ast, ExprError> {
        let mut lhs = match self.peek_op(&["!", "not"]) {
            Some((_, s)) if min <= NOT => {
                self.enter(s)?;
                self.pos += 1;
                let inner = self.expr(NOT)?;
                self.leave(1);
                Ast {
                    span: s.to(inner.span),
                    kind: AstKind::Not(Box::new(inner)),
                }
            }
            _ => self.unary()?,
        };
        // Each operator of a chain puts the chain's start one tree level deeper.
        let mut links = 0;
        let mut comparison: Option<Span> = None;
        while let Some((op, prec, s)) = self.peek_binary() {
            if prec < min {
                break;
            }
            if let (Some(first), CMP) = (comparison, prec) {
                return Err(self.chained(first, s));
            }
            comparison = (prec == CMP).then_some(s);
            // A flat chain is as deep as it is long: say so, or the limit reads as a mystery.
            self.enter(s).map_err(|mut e| {
                e.message
                    .push_str(" (each operator of a chain counts one level)");
                e
            })?;
            links += 1;
            self.pos += 1;
            let rhs = self.expr(prec + 1)?;
            let span = lhs.span.to(rhs.span);
            lhs = Ast {
                kind: AstKind::Bin(op, Box::new(lhs), Box::new(rhs)),
                span,
            };
        }
        self.leave(links);
        Ok(lhs)
    }

    fn chained(&self, first: Span, second: Span) -> ExprError {
        let o = &self.src[second.start..second.end];
        let msg = format!("comparisons do not chain: use `and` between them (before `{o}`, after the comparison at column {})", self.col(first));
        self.err(second, msg)
    }

    fn col(&self, s: Span) -> u32 {
        ExprError::at(self.src, s.start, "").column
    }

    fn or(&mut self) -> Result<Ast, ExprError> {
        self.expr(OR)
    }

    // unary, primary and parenthesised are on the recursive path with expr: the cold parts
    // (field chains, leaves, errors) live in separate functions so that, in a debug build,
    // MAX_DEPTH levels of parentheses fit in well under a megabyte of stack.

    fn unary(&mut self) -> Result<Ast, ExprError> {
        if let Some((_, s)) = self.peek_op(&["-"]) {
            self.enter(s)?;
            self.pos += 1;
            let inner = self.unary()?;
            self.leave(1);
            let span = s.to(inner.span);
            return Ok(Ast {
                kind: AstKind::Neg(Box::new(inner)),
                span,
            });
        }
        let base = self.primary()?;
        self.fields(base)
    }

    /// `base.name.name...`
    #[inline(never)]
    fn fields(&mut self, mut base: Ast) -> Result<Ast, ExprError> {
        let mut links = 0;
        while let Some((_, dot)) = self.peek_op(&["."]) {
            self.enter(dot)?;
            links += 1;
            self.pos += 1;
            match self.toks.get(self.pos).cloned() {
                Some((Tok::Word(name), s)) => {
                    self.pos += 1;
                    let span = base.span.to(s);
                    base = Ast {
                        kind: AstKind::Field(Box::new(base), name),
                        span,
                    };
                }
                Some((t, s)) => {
                    return Err(self.err(
                        s,
                        format!("expected a field name after `.`, found {}", show(&t)),
                    ))
                }
                None => return Err(self.err(self.end_span(), "expected a field name after `.`")),
            }
        }
        self.leave(links);
        Ok(base)
    }

    fn primary(&mut self) -> Result<Ast, ExprError> {
        let Some((tok, span)) = self.toks.get(self.pos).cloned() else {
            return Err(self.err(self.end_span(), "expected a value, found the end"));
        };
        self.pos += 1;
        match tok {
            Tok::Op("(") => self.parenthesised(span),
            Tok::Word(w) => match Func::from_name(&w) {
                Some(f) => self.call(f, span),
                None => self.leaf(Tok::Word(w), span),
            },
            t => self.leaf(t, span),
        }
    }

    /// `( expr )`, after the `(` at `open`.
    fn parenthesised(&mut self, open: Span) -> Result<Ast, ExprError> {
        self.enter(open)?;
        let inner = self.or()?;
        let close = self.expect(")")?;
        self.leave(1);
        Ok(Ast {
            kind: inner.kind,
            span: open.to(close),
        })
    }

    /// A literal or a property, or the error for any other token.
    #[inline(never)]
    fn leaf(&self, tok: Tok, span: Span) -> Result<Ast, ExprError> {
        let kind = match tok {
            Tok::Num(n) => AstKind::Num(n),
            Tok::Str(s) => AstKind::Str(s),
            Tok::Path(p) => AstKind::Path(p),
            Tok::Word(w) if w == "true" || w == "false" => AstKind::Bool(w == "true"),
            Tok::Word(w) => return Err(self.err(span, format!(
                "unknown name `{w}`; expected a property `module/path`, a number, a string, true/false, or a function (abs, min, max, clamp, held, age, elapsed, len)"
            ))),
            t => return Err(self.err(span, format!("expected a value, found {}", show(&t)))),
        };
        Ok(Ast { kind, span })
    }

    fn call(&mut self, f: Func, name: Span) -> Result<Ast, ExprError> {
        self.enter(name)?;
        self.expect("(")?;
        let mut args = Vec::new();
        if self.peek_op(&[")"]).is_none() {
            loop {
                args.push(self.or()?);
                if self.peek_op(&[","]).is_none() {
                    break;
                }
                self.pos += 1;
            }
        }
        let close = self.expect(")")?;
        self.leave(1);
        Ok(Ast {
            kind: AstKind::Call(f, args),
            span: name.to(close),
        })
    }
}
