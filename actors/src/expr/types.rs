//! Static types of expressions, and the environment giving property types.

use std::collections::HashMap;
use std::fmt;

use crate::value::{AnyValue, TypeInfo};

/// The type of an expression or a property, as the checker sees it.
#[derive(Debug, Clone, PartialEq)]
pub enum Ty {
    /// `bool`.
    Bool,
    /// A number (`f64`, `i64`, any numeric field).
    Num,
    /// A string.
    Str,
    /// A structured value with named fields (e.g. `Pose2`: `x`, `y`, `theta`).
    Struct {
        /// The type name, for messages.
        name: String,
        /// Fields and their types, in declaration order.
        fields: Vec<(String, Ty)>,
    },
    /// A list (`f64[]`, a scan's `ranges`): `min(list)`, `max(list)`, `len(list)`.
    List(Box<Ty>),
    /// Anything else (images, maps...): can be read by `age` only.
    Other(String),
}

impl Ty {
    /// The type of a property of type `info`, reading the field layout of structs from
    /// `sample` (its declared default or current value).
    pub fn of_property(info: TypeInfo, sample: &AnyValue) -> Ty {
        if info.is::<bool>() {
            Ty::Bool
        } else if info.is::<f64>() || info.is::<i64>() {
            Ty::Num
        } else if info.is::<String>() {
            Ty::Str
        } else {
            match info.to_dynamic(sample) {
                Ok(v) => Ty::of_dynamic(info.name(), &v),
                Err(_) => Ty::Other(info.name().to_string()),
            }
        }
    }

    /// The type of a dynamic value (`name` names structs).
    pub fn of_dynamic(name: &str, v: &ron::Value) -> Ty {
        match v {
            ron::Value::Bool(_) => Ty::Bool,
            ron::Value::Number(_) => Ty::Num,
            ron::Value::String(_) | ron::Value::Char(_) => Ty::Str,
            ron::Value::Map(m) if m.keys().all(|k| matches!(k, ron::Value::String(_))) => {
                Ty::Struct {
                    name: name.to_string(),
                    fields: m
                        .iter()
                        .map(|(k, v)| {
                            let ron::Value::String(k) = k else {
                                unreachable!("keys checked above")
                            };
                            (k.clone(), Ty::of_dynamic(&format!("{name}.{k}"), v))
                        })
                        .collect(),
                }
            }
            // The element type comes from the first element; an empty sample (a default
            // value) is taken as a list of numbers, the common case (ranges, samples).
            ron::Value::Seq(xs) => Ty::List(Box::new(
                xs.first()
                    .map_or(Ty::Num, |x| Ty::of_dynamic(&format!("{name}[]"), x)),
            )),
            _ => Ty::Other(name.to_string()),
        }
    }

    /// "numbers", "booleans"... for messages about lists.
    fn plural(&self) -> String {
        match self {
            Ty::Bool => "booleans".into(),
            Ty::Num => "numbers".into(),
            Ty::Str => "strings".into(),
            other => format!("values ({other})"),
        }
    }

    /// The type of field `name`, if this is a struct that has it.
    pub fn field(&self, name: &str) -> Option<&Ty> {
        match self {
            Ty::Struct { fields, .. } => fields.iter().find(|(f, _)| f == name).map(|(_, t)| t),
            _ => None,
        }
    }
}

impl fmt::Display for Ty {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Ty::Bool => f.write_str("a boolean"),
            Ty::Num => f.write_str("a number"),
            Ty::Str => f.write_str("a string"),
            Ty::Struct { name, .. } => write!(f, "a {name}"),
            Ty::List(elem) => write!(f, "a list of {}", elem.plural()),
            Ty::Other(name) => write!(f, "a {name}"),
        }
    }
}

/// Property types by address (as written in expressions), for the checker.
#[derive(Debug, Clone, Default)]
pub struct TypeEnv {
    props: HashMap<String, Ty>,
}

impl TypeEnv {
    /// An empty environment.
    pub fn new() -> Self {
        Self::default()
    }

    /// Declares property `path` with type `ty`.
    pub fn insert(&mut self, path: &str, ty: Ty) -> &mut Self {
        self.props.insert(path.to_string(), ty);
        self
    }

    /// Declares property `path` of type `info`, struct fields read from `sample`.
    pub fn insert_property(&mut self, path: &str, info: TypeInfo, sample: &AnyValue) -> &mut Self {
        self.insert(path, Ty::of_property(info, sample))
    }

    /// The type of property `path`.
    pub fn get(&self, path: &str) -> Option<&Ty> {
        self.props.get(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Pose2, Twist2};
    use std::sync::Arc;

    #[test]
    fn property_types_come_from_type_info_and_struct_layout() {
        let num = Ty::of_property(TypeInfo::of::<i64>(), &(Arc::new(3_i64) as AnyValue));
        assert_eq!(num, Ty::Num);
        let pose = Ty::of_property(
            TypeInfo::of::<Pose2>(),
            &(Arc::new(Pose2::default()) as AnyValue),
        );
        assert_eq!(pose.field("theta"), Some(&Ty::Num));
        assert_eq!(pose.to_string(), "a Pose2");
        let twist = Ty::of_property(
            TypeInfo::of::<Twist2>(),
            &(Arc::new(Twist2::default()) as AnyValue),
        );
        assert!(twist.field("omega").is_some() && twist.field("w").is_none());
        let list = Ty::of_property(
            TypeInfo::of::<Vec<f64>>(),
            &(Arc::new(vec![1.0]) as AnyValue),
        );
        assert_eq!(list, Ty::List(Box::new(Ty::Num)));
        assert_eq!(list.to_string(), "a list of numbers");
    }
}
