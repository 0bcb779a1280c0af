//! The parser: tokens to an [`Ast`] with spans, by precedence climbing.
//!
//! Precedence, loosest first: `or`/`||`, `and`/`&&`, `not`/`!`, comparisons (not chained),
//! `+ -`, `* /`, unary `-`, field access `.name`, then literals, paths, calls and parentheses.

use super::lexer::{lex, Tok};
use super::{ExprError, Span};

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
    let mut p = Parser { src, toks, pos: 0 };
    let ast = p.or()?;
    match p.toks.get(p.pos) {
        None => Ok(ast),
        Some((t, s)) => Err(p.err(
            *s,
            format!("unexpected {}; expected an operator or the end", show(t)),
        )),
    }
}

struct Parser<'a> {
    src: &'a str,
    toks: Vec<(Tok, Span)>,
    pos: usize,
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

    fn binary(
        &mut self,
        ops: &[&str],
        next: fn(&mut Self) -> Result<Ast, ExprError>,
        chain: bool,
    ) -> Result<Ast, ExprError> {
        let mut lhs = next(self)?;
        while let Some((op, s)) = self.peek_op(ops) {
            self.pos += 1;
            let rhs = next(self)?;
            let op = match op {
                "||" | "or" => BinOp::Or,
                "&&" | "and" => BinOp::And,
                "+" => BinOp::Add,
                "-" => BinOp::Sub,
                "*" => BinOp::Mul,
                "/" => BinOp::Div,
                "<" => BinOp::Lt,
                "<=" => BinOp::Le,
                ">" => BinOp::Gt,
                ">=" => BinOp::Ge,
                "==" => BinOp::Eq,
                _ => BinOp::Ne,
            };
            let span = lhs.span.to(rhs.span);
            lhs = Ast {
                kind: AstKind::Bin(op, Box::new(lhs), Box::new(rhs)),
                span,
            };
            if !chain {
                if let Some((o, s2)) = self.peek_op(ops) {
                    return Err(self.err(s2, format!("comparisons do not chain: use `and` between them (before `{o}`, after the comparison at column {})", self.col(s))));
                }
            }
        }
        Ok(lhs)
    }

    fn col(&self, s: Span) -> u32 {
        ExprError::at(self.src, s.start, "").column
    }

    fn or(&mut self) -> Result<Ast, ExprError> {
        self.binary(&["||", "or"], Self::and, true)
    }

    fn and(&mut self) -> Result<Ast, ExprError> {
        self.binary(&["&&", "and"], Self::not, true)
    }

    fn not(&mut self) -> Result<Ast, ExprError> {
        if let Some((_, s)) = self.peek_op(&["!", "not"]) {
            self.pos += 1;
            let inner = self.not()?;
            let span = s.to(inner.span);
            return Ok(Ast {
                kind: AstKind::Not(Box::new(inner)),
                span,
            });
        }
        self.cmp()
    }

    fn cmp(&mut self) -> Result<Ast, ExprError> {
        self.binary(&["<", "<=", ">", ">=", "==", "!="], Self::add, false)
    }

    fn add(&mut self) -> Result<Ast, ExprError> {
        self.binary(&["+", "-"], Self::mul, true)
    }

    fn mul(&mut self) -> Result<Ast, ExprError> {
        self.binary(&["*", "/"], Self::unary, true)
    }

    fn unary(&mut self) -> Result<Ast, ExprError> {
        if let Some((_, s)) = self.peek_op(&["-"]) {
            self.pos += 1;
            let inner = self.unary()?;
            let span = s.to(inner.span);
            return Ok(Ast {
                kind: AstKind::Neg(Box::new(inner)),
                span,
            });
        }
        let mut base = self.primary()?;
        while self.peek_op(&["."]).is_some() {
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
        Ok(base)
    }

    fn primary(&mut self) -> Result<Ast, ExprError> {
        let Some((tok, span)) = self.toks.get(self.pos).cloned() else {
            return Err(self.err(self.end_span(), "expected a value, found the end"));
        };
        self.pos += 1;
        let kind = match tok {
            Tok::Num(n) => AstKind::Num(n),
            Tok::Str(s) => AstKind::Str(s),
            Tok::Path(p) => AstKind::Path(p),
            Tok::Op("(") => {
                let inner = self.or()?;
                let close = self.expect(")")?;
                return Ok(Ast { kind: inner.kind, span: span.to(close) });
            }
            Tok::Word(w) if w == "true" || w == "false" => AstKind::Bool(w == "true"),
            Tok::Word(w) => match Func::from_name(&w) {
                Some(f) => return self.call(f, span),
                None => return Err(self.err(span, format!(
                    "unknown name `{w}`; expected a property `module/path`, a number, a string, true/false, or a function (abs, min, max, clamp, held, age)"
                ))),
            },
            t => return Err(self.err(span, format!("expected a value, found {}", show(&t)))),
        };
        Ok(Ast { kind, span })
    }

    fn call(&mut self, f: Func, name: Span) -> Result<Ast, ExprError> {
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
        Ok(Ast {
            kind: AstKind::Call(f, args),
            span: name.to(close),
        })
    }
}
