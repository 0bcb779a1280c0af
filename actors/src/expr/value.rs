//! Run-time values of expressions.

use std::fmt;
use std::sync::Arc;

use crate::value::{AnyValue, TypeInfo};

/// The value of an expression or sub-expression. Serializable, so what a context set can be
/// kept in a module's `state/` memory: untagged (`true`, `0.5`, `"slow"`), since a snapshot
/// is read through RON's dynamic values, which keep no enum variant names.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum Value {
    /// A boolean.
    Bool(bool),
    /// A number (integers are read as `f64`).
    Num(f64),
    /// A string.
    Str(Arc<str>),
    /// A structured value, in dynamic form, awaiting field access.
    Dyn(ron::Value),
}

impl Value {
    /// The boolean, if this is one.
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Bool(b) => Some(*b),
            _ => None,
        }
    }

    /// The number, if this is one.
    pub fn as_num(&self) -> Option<f64> {
        match self {
            Value::Num(n) => Some(*n),
            _ => None,
        }
    }

    /// Reads a property value: plain types directly, others through their dynamic form.
    pub fn of_property(info: TypeInfo, v: &AnyValue) -> Result<Value, String> {
        if let Some(b) = v.downcast_ref::<bool>() {
            Ok(Value::Bool(*b))
        } else if let Some(n) = v.downcast_ref::<f64>() {
            Ok(Value::Num(*n))
        } else if let Some(n) = v.downcast_ref::<i64>() {
            Ok(Value::Num(*n as f64))
        } else if let Some(s) = v.downcast_ref::<String>() {
            Ok(Value::Str(s.as_str().into()))
        } else {
            info.to_dynamic(v).map(Value::of_dynamic)
        }
    }

    /// Converts a dynamic value: leaves become plain values, the rest stays dynamic.
    pub fn of_dynamic(v: ron::Value) -> Value {
        match v {
            ron::Value::Bool(b) => Value::Bool(b),
            ron::Value::Number(n) => Value::Num(n.into_f64()),
            ron::Value::String(s) => Value::Str(s.into()),
            ron::Value::Char(c) => Value::Str(c.to_string().into()),
            other => Value::Dyn(other),
        }
    }

    /// Field `name` of a structured value.
    pub fn field(&self, name: &str) -> Result<Value, String> {
        match self {
            Value::Dyn(ron::Value::Map(m)) => m
                .get(&ron::Value::String(name.to_string()))
                .cloned()
                .map(Value::of_dynamic)
                .ok_or_else(|| format!("the value has no field `{name}`")),
            other => Err(format!("field `{name}` of {other}, which has no fields")),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(b) => write!(f, "{b}"),
            Value::Num(n) => write!(f, "{n}"),
            Value::Str(s) => write!(f, "{s:?}"),
            Value::Dyn(v) => write!(f, "{}", ron::to_string(v).unwrap_or_default()),
        }
    }
}
