//! The evaluator: a typed tree, the current property values, the time, and `held` states.

use std::time::Duration;

use tokio::time::Instant;

use super::check::Node;
use super::parse::BinOp;
use super::value::Value;
use crate::range::short_number;

/// The last value of a property as the evaluator sees it.
#[derive(Debug, Clone)]
pub(crate) struct PropSlot {
    /// Converted once per write; an error if the value could not be read.
    pub value: Result<Value, String>,
    pub written: Instant,
}

/// Everything one evaluation reads and updates.
pub(crate) struct Eval<'a> {
    pub props: &'a [PropSlot],
    /// Per `held`: since when its condition has been true.
    pub held: &'a mut [Option<Instant>],
    pub now: Instant,
    /// The earliest future instant at which a time-dependent result may change.
    pub deadline: Option<Instant>,
    /// The floor of `held` windows and `age` write times (see `ExprSet::set_origin`).
    pub origin: Option<Instant>,
    /// What `elapsed()` counts from.
    pub since: Instant,
}

/// The elements of a list value.
fn list_of(v: Value) -> Result<Vec<ron::Value>, String> {
    match v {
        Value::Dyn(ron::Value::Seq(xs)) => Ok(xs),
        other => Err(format!("expected a list, found {other}")),
    }
}

/// `x op y` for the four operations. A result that is not a number (`0 / 0`, `inf - inf`) or
/// that leaves the finite numbers from finite operands (`1 / 0`, an overflow) is an error, so
/// the expression cannot be evaluated (a condition is then false, a value not written) rather
/// than letting NaN or an infinity into comparisons and parameters. Infinities read from
/// properties (a laser's "no return") still compute: `inf * 2` is `inf`.
fn arithmetic(op: BinOp, x: f64, y: f64) -> Result<Value, String> {
    let r = match op {
        BinOp::Add => x + y,
        BinOp::Sub => x - y,
        BinOp::Mul => x * y,
        _ => x / y,
    };
    let from_infinity = !(x.is_finite() && y.is_finite());
    if r.is_finite() || (from_infinity && !r.is_nan()) {
        return Ok(Value::Num(r));
    }
    Err(match op {
        BinOp::Div if y == 0.0 => format!("division by zero ({} / 0)", short_number(x)),
        op => format!(
            "{} {} {} is not a finite number",
            short_number(x),
            op.symbol(),
            short_number(y)
        ),
    })
}

/// Slack added to `age` deadlines so that `age(p) > 2` is already true when re-evaluated.
const AGE_SLACK: Duration = Duration::from_millis(1);

impl Eval<'_> {
    fn wake_at(&mut self, t: Instant) {
        if t > self.now && self.deadline.is_none_or(|d| t < d) {
            self.deadline = Some(t);
        }
    }

    fn num(&mut self, n: &Node) -> Result<f64, String> {
        match self.eval(n)? {
            Value::Num(x) => Ok(x),
            other => Err(format!("expected a number, found {other}")),
        }
    }

    fn bool(&mut self, n: &Node) -> Result<bool, String> {
        match self.eval(n)? {
            Value::Bool(x) => Ok(x),
            other => Err(format!("expected a boolean, found {other}")),
        }
    }

    /// Evaluates `n`. Both sides of `and`/`or` are evaluated (no short cut) so that every
    /// `held` sees its condition at every evaluation.
    pub fn eval(&mut self, n: &Node) -> Result<Value, String> {
        Ok(match n {
            Node::Const(v) => v.clone(),
            Node::Prop(i) => self.props[*i].value.clone()?,
            Node::Field(base, name) => self.eval(base)?.field(name)?,
            Node::Neg(x) => Value::Num(-self.num(x)?),
            Node::Not(x) => Value::Bool(!self.bool(x)?),
            Node::Abs(x) => Value::Num(self.num(x)?.abs()),
            Node::MinMax(max, xs) => {
                let mut acc = self.num(&xs[0])?;
                for x in &xs[1..] {
                    let v = self.num(x)?;
                    acc = if *max { acc.max(v) } else { acc.min(v) };
                }
                Value::Num(acc)
            }
            Node::MinMaxList(max, list) => {
                let mut acc: Option<f64> = None;
                for x in list_of(self.eval(list)?)? {
                    let ron::Value::Number(x) = x else {
                        return Err("a list element is not a number".into());
                    };
                    let x = x.into_f64();
                    acc = Some(acc.map_or(x, |a| if *max { a.max(x) } else { a.min(x) }));
                }
                Value::Num(acc.ok_or("min/max of an empty list")?)
            }
            Node::Len(list) => Value::Num(list_of(self.eval(list)?)?.len() as f64),
            Node::Clamp(x, lo, hi) => {
                let (x, lo, hi) = (self.num(x)?, self.num(lo)?, self.num(hi)?);
                // Bounds the wrong way round are an error, not a silent `hi` (and not
                // f64::clamp, which panics on them).
                if lo > hi {
                    return Err(format!(
                        "clamp(x, lo, hi): lo ({}) is above hi ({})",
                        short_number(lo),
                        short_number(hi)
                    ));
                }
                Value::Num(x.max(lo).min(hi))
            }
            Node::Age(i) => Value::Num(
                self.now
                    .saturating_duration_since(self.written(*i))
                    .as_secs_f64(),
            ),
            Node::Elapsed => {
                Value::Num(self.now.saturating_duration_since(self.since).as_secs_f64())
            }
            Node::Held(cond, secs, slot) => {
                let c = self.bool(cond)?;
                let since = if c {
                    // `set_origin` forgets the window, so it starts at the origin at the earliest.
                    *self.held[*slot].get_or_insert(self.now)
                } else {
                    self.held[*slot] = None;
                    return Ok(Value::Bool(false));
                };
                let until = since + Duration::from_secs_f64(secs.max(0.0));
                self.wake_at(until);
                Value::Bool(self.now >= until)
            }
            Node::Bin(op, a, b) => self.binary(*op, a, b)?,
        })
    }

    /// The number a leaf (a property or a constant) holds, read in place; `None` for any other
    /// node or value, which the general path evaluates.
    #[inline]
    fn leaf_num(&self, n: &Node) -> Option<f64> {
        match n {
            Node::Prop(i) => match &self.props[*i].value {
                Ok(Value::Num(x)) => Some(*x),
                _ => None,
            },
            Node::Const(Value::Num(x)) => Some(*x),
            _ => None,
        }
    }

    fn binary(&mut self, op: BinOp, a: &Node, b: &Node) -> Result<Value, String> {
        use BinOp::*;
        // The usual condition (`a/out/x > 0.5`, `p >= q`) compares two numbers read from
        // leaves: computed without cloning values or recursing. Leaves have no `age` deadline,
        // and the result is what the general path below gives.
        let leaves = match op {
            And | Or => None,
            _ => self.leaf_num(a).zip(self.leaf_num(b)),
        };
        if let Some((x, y)) = leaves {
            return Ok(match op {
                Add | Sub | Mul | Div => arithmetic(op, x, y)?,
                Lt => Value::Bool(x < y),
                Le => Value::Bool(x <= y),
                Gt => Value::Bool(x > y),
                Ge => Value::Bool(x >= y),
                Eq => Value::Bool(x == y),
                // `Ne` (`And` and `Or` took the general path).
                _ => Value::Bool(x != y),
            });
        }
        let (x, y) = (self.eval(a)?, self.eval(b)?);
        if matches!(op, Lt | Le | Gt | Ge) {
            self.age_deadline(a, &y);
            self.age_deadline(b, &x);
        }
        Ok(match (op, x, y) {
            (And, Value::Bool(x), Value::Bool(y)) => Value::Bool(x && y),
            (Or, Value::Bool(x), Value::Bool(y)) => Value::Bool(x || y),
            (Eq, x, y) => Value::Bool(x == y),
            (Ne, x, y) => Value::Bool(x != y),
            (op, Value::Num(x), Value::Num(y)) => match op {
                Add | Sub | Mul | Div => arithmetic(op, x, y)?,
                Lt => Value::Bool(x < y),
                Le => Value::Bool(x <= y),
                Gt => Value::Bool(x > y),
                _ => Value::Bool(x >= y),
            },
            (op, x, y) => return Err(format!("`{}` cannot apply to {x} and {y}", op.symbol())),
        })
    }

    /// When property `i` counts as written for `age`: its write time, but not before the origin.
    fn written(&self, i: usize) -> Instant {
        let w = self.props[i].written;
        self.origin.map_or(w, |o| w.max(o))
    }

    /// `age(p) < limit` or `elapsed() < limit` (either way round) flips when the time crosses
    /// `limit`: wake then.
    fn age_deadline(&mut self, side: &Node, other: &Value) {
        let from = match side {
            Node::Age(i) => self.written(*i),
            Node::Elapsed => self.since,
            _ => return,
        };
        if let Value::Num(limit) = other {
            // A limit beyond `held`'s longest duration never flips within a run: no wake-up
            // (and no instant overflowing for `age(p) > 1e300`).
            if (0.0..=super::check::MAX_HELD_SECS).contains(limit) {
                let t = from + Duration::from_secs_f64(*limit) + AGE_SLACK;
                self.wake_at(t);
            }
        }
    }
}
