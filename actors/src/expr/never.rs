//! Conditions that can never be true, found without running them: comparisons of one property
//! with constants that contradict each other (`v > 5 and v < 3`, `mode == 1 and mode == 2`).
//!
//! The analysis is deliberately small and sound: it only claims "never" for a conjunction of
//! comparisons between a property (or one of its fields) and a number whose ranges do not
//! overlap, and for `or`s of such; anything it does not understand counts as "may hold".

use super::parse::{Ast, AstKind, BinOp, Func};
use super::{ExprError, Span};

/// Returns why `ast` (parsed from `src`) can never be true, if that can be shown: the two
/// comparisons that contradict each other, at the position of the first.
pub fn never_true(src: &str, ast: &Ast) -> Option<ExprError> {
    match &ast.kind {
        AstKind::Bin(BinOp::Or, a, b) => {
            // Both sides must be impossible; report the first.
            let left = never_true(src, a)?;
            never_true(src, b)?;
            Some(left)
        }
        _ => {
            let mut bounds: Vec<Range> = Vec::new();
            collect(ast, false, &mut bounds);
            bounds.iter().find_map(|r| r.contradiction(src))
        }
    }
}

/// One end of a range: the value, whether it is included, and the comparison that set it.
#[derive(Debug, Clone, Copy)]
struct Bound {
    value: f64,
    inclusive: bool,
    span: Span,
}

/// What the conjunction so far allows for one operand (a property or a field of one).
#[derive(Debug)]
struct Range {
    operand: String,
    lo: Option<Bound>,
    hi: Option<Bound>,
}

impl Range {
    fn tighten_lo(&mut self, b: Bound) {
        let tighter = match self.lo {
            None => true,
            Some(lo) => b.value > lo.value || (b.value == lo.value && !b.inclusive),
        };
        if tighter {
            self.lo = Some(b);
        }
    }

    fn tighten_hi(&mut self, b: Bound) {
        let tighter = match self.hi {
            None => true,
            Some(hi) => b.value < hi.value || (b.value == hi.value && !b.inclusive),
        };
        if tighter {
            self.hi = Some(b);
        }
    }

    fn contradiction(&self, src: &str) -> Option<ExprError> {
        let (lo, hi) = (self.lo?, self.hi?);
        let empty =
            lo.value > hi.value || (lo.value == hi.value && !(lo.inclusive && hi.inclusive));
        if !empty {
            return None;
        }
        let (first, second) = match lo.span.start <= hi.span.start {
            true => (lo.span, hi.span),
            false => (hi.span, lo.span),
        };
        let text = |s: Span| src[s.start..s.end].trim();
        Some(ExprError::at(
            src,
            first.start,
            format!(
                "`{}` and `{}` cannot both be true",
                text(first),
                text(second)
            ),
        ))
    }
}

/// Adds the ranges `ast` requires to be true (`negated`: to be false) to `out`.
fn collect(ast: &Ast, negated: bool, out: &mut Vec<Range>) {
    match &ast.kind {
        AstKind::Bin(BinOp::And, a, b) if !negated => {
            collect(a, false, out);
            collect(b, false, out);
        }
        // not (a or b) = not a and not b
        AstKind::Bin(BinOp::Or, a, b) if negated => {
            collect(a, true, out);
            collect(b, true, out);
        }
        AstKind::Not(x) => collect(x, !negated, out),
        // held(c, d) is true only while c is.
        AstKind::Call(Func::Held, args) if !negated => {
            if let Some(condition) = args.first() {
                collect(condition, false, out);
            }
        }
        AstKind::Bin(op, a, b) => {
            let Some((operand, op, value)) = comparison(*op, a, b) else {
                return;
            };
            let op = if negated { negate(op) } else { Some(op) };
            let Some(op) = op else { return };
            let bound = |inclusive| Bound {
                value,
                inclusive,
                span: ast.span,
            };
            let range = match out.iter_mut().position(|r| r.operand == operand) {
                Some(i) => &mut out[i],
                None => {
                    out.push(Range {
                        operand,
                        lo: None,
                        hi: None,
                    });
                    out.last_mut().expect("just pushed")
                }
            };
            match op {
                BinOp::Gt => range.tighten_lo(bound(false)),
                BinOp::Ge => range.tighten_lo(bound(true)),
                BinOp::Lt => range.tighten_hi(bound(false)),
                BinOp::Le => range.tighten_hi(bound(true)),
                BinOp::Eq => {
                    range.tighten_lo(bound(true));
                    range.tighten_hi(bound(true));
                }
                _ => {}
            }
        }
        _ => {}
    }
}

/// `operand op number`, turning `number op operand` around; `None` for anything else.
fn comparison(op: BinOp, a: &Ast, b: &Ast) -> Option<(String, BinOp, f64)> {
    let flipped = match op {
        BinOp::Lt => BinOp::Gt,
        BinOp::Le => BinOp::Ge,
        BinOp::Gt => BinOp::Lt,
        BinOp::Ge => BinOp::Le,
        BinOp::Eq | BinOp::Ne => op,
        _ => return None,
    };
    match (operand(a), number(b), number(a), operand(b)) {
        (Some(x), Some(n), _, _) => Some((x, op, n)),
        (_, _, Some(n), Some(x)) => Some((x, flipped, n)),
        _ => None,
    }
}

/// The comparison that is true exactly when `op` is false (`None`: not a range, e.g. `!=`).
fn negate(op: BinOp) -> Option<BinOp> {
    Some(match op {
        BinOp::Lt => BinOp::Ge,
        BinOp::Le => BinOp::Gt,
        BinOp::Gt => BinOp::Le,
        BinOp::Ge => BinOp::Lt,
        BinOp::Ne => BinOp::Eq,
        _ => return None,
    })
}

/// A property or a field of one, as written.
fn operand(a: &Ast) -> Option<String> {
    match &a.kind {
        AstKind::Path(p) => Some(p.clone()),
        AstKind::Field(base, name) => Some(format!("{}.{name}", operand(base)?)),
        _ => None,
    }
}

/// A number literal, possibly negated.
fn number(a: &Ast) -> Option<f64> {
    match &a.kind {
        AstKind::Num(n) => Some(*n),
        AstKind::Neg(x) => number(x).map(|n| -n),
        _ => None,
    }
}
