//! The checker: types an [`Ast`] against property types and lowers it to an evaluation tree.

use super::parse::{Ast, AstKind, BinOp, Func};
use super::types::Ty;
use super::value::Value;
use super::{ExprError, Span};

/// The longest duration `held` accepts, in seconds (about 31 years): a time an instant can
/// always be moved by, whatever the clock says.
pub const MAX_HELD_SECS: f64 = 1e9;

/// A typed node, ready to evaluate; properties are indices given by the resolver.
#[derive(Debug, Clone)]
pub(crate) enum Node {
    Const(Value),
    Prop(usize),
    Field(Box<Node>, String),
    Neg(Box<Node>),
    Not(Box<Node>),
    Bin(BinOp, Box<Node>, Box<Node>),
    Abs(Box<Node>),
    /// `min` (false) or `max` (true).
    MinMax(bool, Vec<Node>),
    /// `min` (false) or `max` (true) of the elements of a list of numbers.
    MinMaxList(bool, Box<Node>),
    /// `len(list)`.
    Len(Box<Node>),
    Clamp(Box<Node>, Box<Node>, Box<Node>),
    /// `held`: condition, seconds, index of its state slot.
    Held(Box<Node>, f64, usize),
    Age(usize),
    /// `elapsed()`.
    Elapsed,
}

/// What the checker needs from its caller.
pub(crate) trait Resolve {
    /// The index and type of property `path`, or an error message.
    fn resolve(&mut self, path: &str) -> Result<(usize, Ty), String>;
    /// A fresh state slot for a `held`.
    fn held_slot(&mut self) -> usize;
    /// The expression depends on time alone (`elapsed`).
    fn timed(&mut self);
}

pub(crate) struct Checker<'a, R> {
    pub src: &'a str,
    pub resolve: &'a mut R,
}

impl<R: Resolve> Checker<'_, R> {
    fn err(&self, span: Span, msg: impl Into<String>) -> ExprError {
        ExprError::at(self.src, span.start, msg)
    }

    fn want(&self, ast: &Ast, got: &Ty, want: &Ty, what: &str) -> Result<(), ExprError> {
        if got == want {
            Ok(())
        } else {
            Err(self.err(ast.span, format!("{what} must be {want}, found {got}")))
        }
    }

    pub fn check(&mut self, ast: &Ast) -> Result<(Node, Ty), ExprError> {
        Ok(match &ast.kind {
            AstKind::Num(n) => (Node::Const(Value::Num(*n)), Ty::Num),
            AstKind::Bool(b) => (Node::Const(Value::Bool(*b)), Ty::Bool),
            AstKind::Str(s) => (Node::Const(Value::Str(s.as_str().into())), Ty::Str),
            AstKind::Path(p) => {
                let (i, ty) = self.resolve.resolve(p).map_err(|m| self.err(ast.span, m))?;
                (Node::Prop(i), ty)
            }
            AstKind::Field(base, name) => {
                let (node, ty) = self.check(base)?;
                let field = match &ty {
                    Ty::Struct { fields, name: tn } => match ty.field(name) {
                        Some(f) => f.clone(),
                        None => {
                            let known: Vec<&str> = fields.iter().map(|(f, _)| f.as_str()).collect();
                            return Err(self.err(
                                ast.span,
                                format!(
                                    "{tn} has no field `{name}`; its fields are {}",
                                    known.join(", ")
                                ),
                            ));
                        }
                    },
                    other => {
                        return Err(self.err(
                            ast.span,
                            format!("field access `.{name}` on {other}, which has no fields"),
                        ))
                    }
                };
                (Node::Field(Box::new(node), name.clone()), field)
            }
            AstKind::Neg(inner) => {
                let (n, t) = self.check(inner)?;
                self.want(inner, &t, &Ty::Num, "the operand of unary `-`")?;
                (Node::Neg(Box::new(n)), Ty::Num)
            }
            AstKind::Not(inner) => {
                let (n, t) = self.check(inner)?;
                self.want(inner, &t, &Ty::Bool, "the operand of `not`")?;
                (Node::Not(Box::new(n)), Ty::Bool)
            }
            AstKind::Bin(op, a, b) => self.binary(ast, *op, a, b)?,
            AstKind::Call(f, args) => self.call(ast, *f, args)?,
        })
    }

    fn binary(&mut self, ast: &Ast, op: BinOp, a: &Ast, b: &Ast) -> Result<(Node, Ty), ExprError> {
        use BinOp::*;
        let (na, ta) = self.check(a)?;
        let (nb, tb) = self.check(b)?;
        let sym = op.symbol();
        let ty = match op {
            Add | Sub | Mul | Div | Lt | Le | Gt | Ge => {
                self.want(a, &ta, &Ty::Num, &format!("the left operand of `{sym}`"))?;
                self.want(b, &tb, &Ty::Num, &format!("the right operand of `{sym}`"))?;
                // Evaluation refuses it every time (see `eval::arithmetic`): say so now.
                if op == Div && matches!(nb, Node::Const(Value::Num(d)) if d == 0.0) {
                    return Err(self.err(b.span, "division by zero: the divisor is the constant 0"));
                }
                if matches!(op, Add | Sub | Mul | Div) {
                    Ty::Num
                } else {
                    Ty::Bool
                }
            }
            And | Or => {
                self.want(a, &ta, &Ty::Bool, &format!("the left operand of `{sym}`"))?;
                self.want(b, &tb, &Ty::Bool, &format!("the right operand of `{sym}`"))?;
                Ty::Bool
            }
            Eq | Ne => {
                if !matches!(ta, Ty::Bool | Ty::Num | Ty::Str) {
                    return Err(self.err(a.span, format!(
                        "`{sym}` compares booleans, numbers or strings, not {ta}; compare its fields instead"
                    )));
                }
                if ta != tb {
                    return Err(self.err(ast.span, format!("cannot compare {ta} with {tb}")));
                }
                Ty::Bool
            }
        };
        Ok((Node::Bin(op, Box::new(na), Box::new(nb)), ty))
    }

    fn call(&mut self, ast: &Ast, f: Func, args: &[Ast]) -> Result<(Node, Ty), ExprError> {
        let src = self.src;
        let arity = |n: usize, name: &str, shape: &str| -> Result<(), ExprError> {
            if args.len() == n {
                Ok(())
            } else {
                let s = if n == 1 { "" } else { "s" };
                let msg = format!(
                    "`{name}` takes {n} argument{s}: {shape}, found {}",
                    args.len()
                );
                Err(ExprError::at(src, ast.span.start, msg))
            }
        };
        match f {
            Func::Age => {
                arity(1, "age", "age(module/path)")?;
                let AstKind::Path(p) = &args[0].kind else {
                    return Err(self.err(
                        args[0].span,
                        "`age` takes a property `module/path`, not an expression",
                    ));
                };
                let (i, _) = self
                    .resolve
                    .resolve(p)
                    .map_err(|m| self.err(args[0].span, m))?;
                Ok((Node::Age(i), Ty::Num))
            }
            Func::Elapsed => {
                arity(0, "elapsed", "elapsed()")?;
                self.resolve.timed();
                Ok((Node::Elapsed, Ty::Num))
            }
            Func::Len => {
                arity(1, "len", "len(list)")?;
                let (n, t) = self.check(&args[0])?;
                if !matches!(t, Ty::List(_)) {
                    return Err(self.err(args[0].span, format!("`len` takes a list, found {t}")));
                }
                Ok((Node::Len(Box::new(n)), Ty::Num))
            }
            Func::Min | Func::Max if args.len() == 1 => {
                let (n, t) = self.check(&args[0])?;
                let name = if f == Func::Max { "max" } else { "min" };
                if t != Ty::List(Box::new(Ty::Num)) {
                    return Err(self.err(
                        ast.span,
                        format!(
                            "`{name}` takes a list of numbers or at least 2 numbers, found {t}"
                        ),
                    ));
                }
                Ok((Node::MinMaxList(f == Func::Max, Box::new(n)), Ty::Num))
            }
            Func::Held => {
                arity(2, "held", "held(condition, duration)")?;
                let (cond, t) = self.check(&args[0])?;
                self.want(&args[0], &t, &Ty::Bool, "the condition of `held`")?;
                let secs = match args[1].kind {
                    AstKind::Num(n) if (0.0..=MAX_HELD_SECS).contains(&n) => n,
                    AstKind::Num(n) => {
                        return Err(self.err(
                            args[1].span,
                            format!(
                                "the duration of `held` must be between 0 and {MAX_HELD_SECS:e} s (about 31 years); found {n:.3e} s"
                            ),
                        ))
                    }
                    _ => {
                        return Err(self.err(
                            args[1].span,
                            "the duration of `held` must be a literal such as `2s` or `500ms`",
                        ))
                    }
                };
                let slot = self.resolve.held_slot();
                Ok((Node::Held(Box::new(cond), secs, slot), Ty::Bool))
            }
            _ => {
                let mut nodes = Vec::with_capacity(args.len());
                for a in args {
                    let (n, t) = self.check(a)?;
                    self.want(a, &t, &Ty::Num, "an argument of a numeric function")?;
                    nodes.push(n);
                }
                let node = match f {
                    Func::Abs => {
                        arity(1, "abs", "abs(x)")?;
                        Node::Abs(Box::new(nodes.remove(0)))
                    }
                    Func::Clamp => {
                        arity(3, "clamp", "clamp(x, lo, hi)")?;
                        let mut it = nodes.into_iter().map(Box::new);
                        let (x, lo, hi) = (it.next(), it.next(), it.next());
                        Node::Clamp(x.expect("3 args"), lo.expect("3 args"), hi.expect("3 args"))
                    }
                    _ => {
                        let max = f == Func::Max;
                        if nodes.len() < 2 {
                            let name = if max { "max" } else { "min" };
                            return Err(self.err(
                                ast.span,
                                format!(
                                    "`{name}` takes at least 2 arguments, found {}",
                                    nodes.len()
                                ),
                            ));
                        }
                        Node::MinMax(max, nodes)
                    }
                };
                Ok((node, Ty::Num))
            }
        }
    }
}
