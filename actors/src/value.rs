//! Type-erased property values and the per-type operations the blackboard needs
//! (config parsing, snapshot writing, short display for traces).

use std::any::{Any, TypeId};
use std::fmt;
use std::sync::Arc;

use crate::types::PropertyType;

/// A property value of any [`PropertyType`], shared: cloning it copies a pointer.
pub type AnyValue = Arc<dyn Any + Send + Sync>;

/// The operations on values of one [`PropertyType`], looked up without knowing the type.
#[derive(Clone, Copy)]
pub struct TypeInfo {
    name: &'static str,
    id: fn() -> TypeId,
    from_ron: fn(ron::Value) -> Result<AnyValue, String>,
    to_ron: fn(&AnyValue) -> Result<String, String>,
    short: fn(&AnyValue) -> String,
    to_dynamic: fn(&AnyValue) -> Result<ron::Value, String>,
    write_json: fn(&AnyValue, &mut Vec<u8>) -> Result<(), String>,
    from_json: fn(&[u8]) -> Result<AnyValue, String>,
}

/// Longest value text shown in traces and summaries.
const SHORT_LEN: usize = 60;

impl TypeInfo {
    /// The operations for `T`.
    pub fn of<T: PropertyType>() -> Self {
        TypeInfo {
            name: T::TYPE_NAME,
            id: TypeId::of::<T>,
            from_ron: |v| {
                v.into_rust::<T>()
                    .map(|t| Arc::new(t) as AnyValue)
                    .map_err(|e| e.to_string())
            },
            to_ron: |v| {
                let t = v.downcast_ref::<T>().ok_or("value has another type")?;
                ron::to_string(t).map_err(|e| e.to_string())
            },
            short: |v| match v.downcast_ref::<T>() {
                Some(t) => shorten(format!("{t:?}")),
                None => "<other type>".to_string(),
            },
            // Through RON text: slow-ish, but only used for field access on structured values
            // (expressions), never on the hot path of plain numbers and booleans.
            to_dynamic: |v| {
                let t = v.downcast_ref::<T>().ok_or("value has another type")?;
                let text = ron::to_string(t).map_err(|e| e.to_string())?;
                ron::from_str::<ron::Value>(&text).map_err(|e| e.to_string())
            },
            write_json: |v, out| {
                let t = v.downcast_ref::<T>().ok_or("value has another type")?;
                serde_json::to_writer(out, t).map_err(|e| e.to_string())
            },
            from_json: |bytes| {
                serde_json::from_slice::<T>(bytes)
                    .map(|t| Arc::new(t) as AnyValue)
                    .map_err(|e| e.to_string())
            },
        }
    }

    /// The stable type name, e.g. `f64` or `Pose2`.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Whether `value` is of this type.
    pub fn is_type_of(&self, value: &(dyn Any + Send + Sync)) -> bool {
        value.type_id() == (self.id)()
    }

    /// Whether this describes `T`.
    pub fn is<T: 'static>(&self) -> bool {
        (self.id)() == TypeId::of::<T>()
    }

    /// Converts a config value into a value of this type, or says what was wrong.
    pub fn from_ron(&self, value: ron::Value) -> Result<AnyValue, String> {
        (self.from_ron)(value)
    }

    /// Writes a value of this type as RON text.
    pub fn to_ron(&self, value: &AnyValue) -> Result<String, String> {
        (self.to_ron)(value)
    }

    /// A dynamic view of a value (structs become maps keyed by field name), for code that
    /// inspects values of types it does not know, such as expression field access.
    pub fn to_dynamic(&self, value: &AnyValue) -> Result<ron::Value, String> {
        (self.to_dynamic)(value)
    }

    /// A value of this type as JSON (the team wire format: any zenoh client can read it).
    pub fn to_json(&self, value: &AnyValue) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        (self.write_json)(value, &mut out)?;
        Ok(out)
    }

    /// Appends a value of this type as JSON to `out` (a recorder reuses one buffer for all);
    /// on an error, `out` may hold part of it.
    pub fn write_json(&self, value: &AnyValue, out: &mut Vec<u8>) -> Result<(), String> {
        (self.write_json)(value, out)
    }

    /// Reads a value of this type from JSON, or says why it is not one.
    pub fn from_json(&self, bytes: &[u8]) -> Result<AnyValue, String> {
        (self.from_json)(bytes)
    }

    /// A short human-readable rendering of a value, for traces and summaries.
    pub fn short(&self, value: &AnyValue) -> String {
        (self.short)(value)
    }
}

impl PartialEq for TypeInfo {
    fn eq(&self, other: &Self) -> bool {
        (self.id)() == (other.id)()
    }
}

impl fmt::Debug for TypeInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name)
    }
}

/// A value written as in a config file: structs as `(x: 1.0, y: 2.0)`, lists as `[..]`, so
/// that messages show the form a user writes, never a type's name in the code.
pub fn config_form(v: &ron::Value) -> String {
    match v {
        ron::Value::Map(m) if m.keys().all(|k| matches!(k, ron::Value::String(_))) => {
            let fields: Vec<String> = m
                .iter()
                .map(|(k, v)| match k {
                    ron::Value::String(k) => format!("{k}: {}", config_form(v)),
                    _ => unreachable!("keys checked above"),
                })
                .collect();
            format!("({})", fields.join(", "))
        }
        ron::Value::Seq(xs) if xs.len() > 4 => {
            let head: Vec<String> = xs.iter().take(3).map(config_form).collect();
            format!("[{}, ...]", head.join(", "))
        }
        ron::Value::Seq(xs) => format!(
            "[{}]",
            xs.iter().map(config_form).collect::<Vec<_>>().join(", ")
        ),
        ron::Value::Number(n) => {
            let x = n.into_f64();
            if x.fract() == 0.0
                && matches!(n, ron::value::Number::F32(_) | ron::value::Number::F64(_))
            {
                format!("{x:.1}")
            } else {
                x.to_string()
            }
        }
        other => ron::to_string(other).unwrap_or_default(),
    }
}

/// RON text as a person writes it in a config: a space after each `,` and `:` outside strings
/// (`(x:1.0,y:2.0)` becomes `(x: 1.0, y: 2.0)`), so messages show values in config syntax
/// with fields in their declared order.
pub fn spaced_ron(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / 4);
    let (mut in_string, mut escaped) = (false, false);
    for c in text.chars() {
        out.push(c);
        if in_string {
            match c {
                _ if escaped => escaped = false,
                '\\' => escaped = true,
                '"' => in_string = false,
                _ => {}
            }
        } else if c == '"' {
            in_string = true;
        } else if c == ',' || c == ':' {
            out.push(' ');
        }
    }
    out
}

/// A conversion error from serde in the terms of a config file: what was expected, as a value
/// written like `example` (the property's current value), never a type's name in the code.
pub fn config_value_error(reason: &str, example: &str, given: &ron::Value) -> String {
    let form = example;
    let words = [
        ("Expected a sequence", "expected a list"),
        ("Expected f64", "expected a number"),
        ("Expected f32", "expected a number"),
        ("Expected i64", "expected an integer"),
        ("Expected u64", "expected a non-negative integer"),
        ("Expected u32", "expected a non-negative integer"),
        ("Expected bool", "expected true or false"),
        ("Expected String", "expected a string"),
        ("Unexpected missing field named", "missing field"),
    ];
    if reason.contains("Expected struct") || reason.contains("Repr") {
        return format!("expected a value like {form}, found {}", config_form(given));
    }
    let mut reason = reason.to_string();
    for (from, to) in words {
        reason = reason.replace(from, to);
    }
    format!("{reason}; a value looks like {form}")
}

/// What a value of `type_name` looks like, from a property's `current` value as RON text:
/// that value spaced, unless it is an empty list of a list type (`[]` shows nothing of the
/// items), for which an example with items.
pub(crate) fn value_example(type_name: &str, current: &str) -> String {
    match (type_name, current.trim()) {
        ("Path2", "[]") => "[(x: 1.0, y: 2.0), (x: 3.0, y: 4.0)]".to_string(),
        ("f64[]", "[]") => "[1.0, 2.5]".to_string(),
        _ => spaced_ron(current),
    }
}

fn shorten(mut s: String) -> String {
    if s.len() > SHORT_LEN {
        let mut cut = SHORT_LEN;
        while !s.is_char_boundary(cut) {
            cut -= 1;
        }
        s.truncate(cut);
        s.push('…');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::Pose2;

    #[test]
    fn value_errors_speak_config_syntax() {
        assert_eq!(
            spaced_ron(r#"(x:1.0,y:2.0,name:"a,b:c")"#),
            r#"(x: 1.0, y: 2.0, name: "a,b:c")"#
        );
        let given = ron::Value::String("big".into());
        assert_eq!(
            config_value_error(
                "Expected struct PointRepr but found a string",
                "(x: 0.0, y: 0.0)",
                &given
            ),
            "expected a value like (x: 0.0, y: 0.0), found \"big\""
        );
        assert_eq!(
            config_value_error(
                "Expected f64 but found the string \"a\" instead",
                "1.0",
                &given
            ),
            "expected a number but found the string \"a\" instead; a value looks like 1.0"
        );
    }

    #[test]
    fn converts_config_values_and_reports_type_errors() {
        let f = TypeInfo::of::<f64>();
        let v = f.from_ron(ron::from_str("2").unwrap()).unwrap();
        assert_eq!(*v.downcast_ref::<f64>().unwrap(), 2.0);
        let err = f.from_ron(ron::from_str("\"fast\"").unwrap()).unwrap_err();
        assert!(err.to_lowercase().contains("expected f64"), "{err}");
        assert!(TypeInfo::of::<i64>()
            .from_ron(ron::from_str("2.5").unwrap())
            .is_err());
    }

    #[test]
    fn struct_values_round_trip_through_snapshot_text() {
        let t = TypeInfo::of::<Pose2>();
        let v: AnyValue = Arc::new(Pose2::new(1.0, 2.0, 0.5));
        let text = t.to_ron(&v).unwrap();
        let back = t.from_ron(ron::from_str(&text).unwrap()).unwrap();
        assert_eq!(back.downcast_ref::<Pose2>().unwrap().y(), 2.0);
        assert_eq!(t.short(&v), "Pose2(x: 1.000, y: 2.000, theta: 0.500)");
        let ron::Value::Map(fields) = t.to_dynamic(&v).unwrap() else {
            panic!("a struct is a map")
        };
        let y = fields.get(&ron::Value::String("y".into())).unwrap();
        assert!(
            matches!(y, ron::Value::Number(n) if n.into_f64() == 2.0),
            "{y:?}"
        );
        let long: AnyValue = Arc::new(vec![0.5_f64; 100]);
        let shown = TypeInfo::of::<Vec<f64>>().short(&long);
        assert!(
            shown.ends_with('…') && shown.chars().count() == SHORT_LEN + 1,
            "{shown}"
        );
    }
}
