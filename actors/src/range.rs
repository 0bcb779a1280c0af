//! The values a numeric parameter accepts, declared with it ([`Ports::param_in`]) and checked
//! wherever a value is set from outside the module: configs (so `petrel check` refuses what
//! `run` would), overlays and snapshots, tools (`petrel set`) and context rules.
//!
//! Every `f64` parameter accepts only finite numbers, range declared or not: NaN and infinities
//! pass every comparison a module makes, so they must not get in at all.
//!
//! [`Ports::param_in`]: crate::Ports::param_in

use std::fmt;

use crate::value::AnyValue;

/// Inclusive bounds of a numeric parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    min: f64,
    max: f64,
}

impl Range {
    /// `min..=max`.
    pub const fn new(min: f64, max: f64) -> Self {
        Range { min, max }
    }

    /// `min` or more.
    pub const fn at_least(min: f64) -> Self {
        Range { min, max: f64::MAX }
    }

    /// Any finite number: what an `f64` parameter without a declared range accepts.
    pub const FINITE: Range = Range {
        min: f64::MIN,
        max: f64::MAX,
    };

    /// What a message says the parameter expects: `a finite number`, `a value in 0.1..=10`.
    pub fn expected(&self) -> String {
        match *self == Range::FINITE {
            true => "a finite number".into(),
            false => format!("a value in {self}"),
        }
    }

    /// Whether `value` is finite and within the bounds.
    pub fn contains(&self, value: f64) -> bool {
        value.is_finite() && self.min <= value && value <= self.max
    }
}

/// A number as people read it in a message: `0.25`, `1000`, `1e300`, `1e-12`, `NaN`, `inf`
/// (never 300 digits, at most six decimals).
pub fn short_number(x: f64) -> String {
    let a = x.abs();
    if x.is_finite() && a != 0.0 && !(1e-4..1e7).contains(&a) {
        format!("{x:e}")
    } else {
        let text = format!("{x:.6}");
        match text.contains('.') {
            true => text.trim_end_matches('0').trim_end_matches('.').to_string(),
            false => text,
        }
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let num = short_number;
        match (self.min == f64::MIN, self.max == f64::MAX) {
            (true, true) => write!(f, "finite"),
            (false, true) => write!(f, ">= {}", num(self.min)),
            (true, false) => write!(f, "<= {}", num(self.max)),
            (false, false) => write!(f, "{}..={}", num(self.min), num(self.max)),
        }
    }
}

/// A parameter's range with the way to read its values as numbers; or, for a text property
/// that takes a few words (`control/fault`), those words.
#[derive(Clone, Copy)]
pub(crate) struct RangeCheck {
    pub range: Range,
    value_of: fn(&AnyValue) -> Option<f64>,
    /// The words a `String` property takes (empty: a number check).
    choices: &'static [&'static str],
}

impl RangeCheck {
    pub fn new(range: Range) -> Self {
        RangeCheck {
            range,
            value_of: number,
            choices: &[],
        }
    }

    /// The words a `String` property takes (empty for a number check).
    pub fn choices(&self) -> &'static [&'static str] {
        self.choices
    }

    /// A `String` property that takes only `choices`.
    pub fn one_of(choices: &'static [&'static str]) -> Self {
        RangeCheck {
            range: Range::FINITE,
            value_of: |_| None,
            choices,
        }
    }

    /// The value as people read it, if it is refused.
    pub fn refuses(&self, value: &AnyValue) -> Option<String> {
        if !self.choices.is_empty() {
            let text = value.downcast_ref::<String>()?;
            return (!self.choices.contains(&text.as_str())).then(|| format!("{text:?}"));
        }
        (self.value_of)(value)
            .filter(|x| !self.range.contains(*x))
            .map(short_number)
    }

    /// What it takes, for a message: `a value in 0.1..=10`, `one of "", "panic"`.
    pub fn expected(&self) -> String {
        match self.choices {
            [] => self.range.expected(),
            words => {
                let words: Vec<String> = words.iter().map(|w| format!("{w:?}")).collect();
                format!("one of {}", words.join(", "))
            }
        }
    }
}

impl RangeCheck {
    /// For a parameter of a structured type (a pose, a point, a list of numbers): every number
    /// in it must be finite. NaN in a sensor's mount pose made a mapper's ray walk never end.
    pub fn finite_fields<T: crate::PropertyType>() -> Self {
        RangeCheck {
            range: Range::FINITE,
            value_of: non_finite_field::<T>,
            choices: &[],
        }
    }
}

/// The first number in `value` (a `T`) that is not finite, if any.
fn non_finite_field<T: crate::PropertyType>(value: &AnyValue) -> Option<f64> {
    let dynamic = crate::TypeInfo::of::<T>().to_dynamic(value).ok()?;
    first_non_finite(&dynamic)
}

fn first_non_finite(value: &ron::Value) -> Option<f64> {
    match value {
        ron::Value::Number(n) => Some(n.into_f64()).filter(|x| !x.is_finite()),
        ron::Value::Seq(items) => items.iter().find_map(first_non_finite),
        ron::Value::Map(map) => map.iter().find_map(|(_, v)| first_non_finite(v)),
        ron::Value::Option(Some(inner)) => first_non_finite(inner),
        _ => None,
    }
}

fn number(value: &AnyValue) -> Option<f64> {
    value
        .downcast_ref::<f64>()
        .copied()
        .or_else(|| value.downcast_ref::<i64>().map(|i| *i as f64))
}

/// The numbers a parameter may have a [`Range`] on.
pub trait Numeric: crate::PropertyType {}
impl Numeric for f64 {}
impl Numeric for i64 {}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn refuses_what_is_out_of_bounds_or_not_finite() {
        let check = RangeCheck::new(Range::new(0.1, 10.0));
        for bad in [0.0, 10.5, f64::NAN, f64::INFINITY, -1e300] {
            assert!(
                check.refuses(&(Arc::new(bad) as AnyValue)).is_some(),
                "{bad}"
            );
        }
        assert_eq!(check.refuses(&(Arc::new(0.1) as AnyValue)), None);
        assert_eq!(check.refuses(&(Arc::new(7_i64) as AnyValue)), None);
        assert_eq!(
            check.refuses(&(Arc::new(70_i64) as AnyValue)),
            Some("70".into())
        );
        let finite = RangeCheck::new(Range::FINITE);
        assert_eq!(finite.refuses(&(Arc::new(-1e300) as AnyValue)), None);
        assert!(finite
            .refuses(&(Arc::new(f64::NEG_INFINITY) as AnyValue))
            .is_some());
    }

    #[test]
    fn numbers_stay_short() {
        let shown: Vec<String> = [
            0.25,
            1000.0,
            1e300,
            1e-12,
            f64::NAN,
            f64::NEG_INFINITY,
            -3.0,
            0.0,
        ]
        .map(short_number)
        .into();
        assert_eq!(
            shown,
            ["0.25", "1000", "1e300", "1e-12", "NaN", "-inf", "-3", "0"]
        );
    }

    #[test]
    fn shows_as_a_person_writes_it() {
        assert_eq!(Range::new(0.1, 1000.0).to_string(), "0.1..=1000");
        assert_eq!(Range::at_least(0.0).to_string(), ">= 0");
        assert_eq!(Range::FINITE.to_string(), "finite");
    }
}
