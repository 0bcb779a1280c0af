//! Maps read from configs and rules files that refuse a key written twice. Serde's own map
//! keeps the last value without a word, so `{"params/factor": "oops", "params/factor": 2.0}`
//! passed `petrel check` with its first, invalid value never looked at. RON's dynamic
//! [`ron::Value`] does the same inside a value (two `"say_a"` bindings in a mission's
//! `params/actions`): [`unique_values`] reads values through [`StrictValue`], which refuses
//! them at any depth.

use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;

use serde::de::{Deserializer, Error, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

/// Deserializes a map of string keys, refusing a key that appears twice (for
/// `#[serde(deserialize_with = "...")]`). The error names the key; the file reader adds where.
pub fn unique_keys<'de, D, V>(d: D) -> Result<BTreeMap<String, V>, D::Error>
where
    D: Deserializer<'de>,
    V: Deserialize<'de>,
{
    struct Unique<V>(PhantomData<V>);

    impl<'de, V: Deserialize<'de>> Visitor<'de> for Unique<V> {
        type Value = BTreeMap<String, V>;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a map of names to values")
        }

        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some(key) = map.next_key::<String>()? {
                if out.contains_key(&key) {
                    return Err(A::Error::custom(format!(
                        "`{key}` is written twice in this map; keep one"
                    )));
                }
                let value = map.next_value()?;
                out.insert(key, value);
            }
            Ok(out)
        }
    }

    d.deserialize_map(Unique(PhantomData))
}

/// [`unique_keys`] for a map of [`ron::Value`]s, each read as a [`StrictValue`]: a key written
/// twice is refused at the top and inside every value.
pub fn unique_values<'de, D>(d: D) -> Result<BTreeMap<String, ron::Value>, D::Error>
where
    D: Deserializer<'de>,
{
    let strict: BTreeMap<String, StrictValue> = unique_keys(d)?;
    Ok(strict.into_iter().map(|(k, v)| (k, v.0)).collect())
}

/// A [`ron::Value`] read as RON reads one, except that a map writing a key twice is an error
/// naming the key (RON's own keeps the last).
pub struct StrictValue(pub ron::Value);

impl<'de> Deserialize<'de> for StrictValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(StrictVisitor).map(StrictValue)
    }
}

struct StrictVisitor;

/// The visitor's methods for numbers, one per width.
macro_rules! numbers {
    ($($visit:ident: $ty:ty),*) => {
        $(fn $visit<E: Error>(self, v: $ty) -> Result<ron::Value, E> {
            Ok(ron::Value::Number(v.into()))
        })*
    };
}

impl<'de> Visitor<'de> for StrictVisitor {
    type Value = ron::Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a RON value")
    }

    fn visit_bool<E: Error>(self, v: bool) -> Result<ron::Value, E> {
        Ok(ron::Value::Bool(v))
    }

    // Every width, as RON's own visitor: a value reads back as the same `Number` variant.
    numbers!(visit_i8: i8, visit_i16: i16, visit_i32: i32, visit_i64: i64, visit_u8: u8,
        visit_u16: u16, visit_u32: u32, visit_u64: u64, visit_f32: f32, visit_f64: f64);

    fn visit_char<E: Error>(self, v: char) -> Result<ron::Value, E> {
        Ok(ron::Value::Char(v))
    }

    fn visit_str<E: Error>(self, v: &str) -> Result<ron::Value, E> {
        Ok(ron::Value::String(v.to_owned()))
    }

    fn visit_string<E: Error>(self, v: String) -> Result<ron::Value, E> {
        Ok(ron::Value::String(v))
    }

    fn visit_bytes<E: Error>(self, v: &[u8]) -> Result<ron::Value, E> {
        Ok(ron::Value::Bytes(v.to_vec()))
    }

    fn visit_byte_buf<E: Error>(self, v: Vec<u8>) -> Result<ron::Value, E> {
        Ok(ron::Value::Bytes(v))
    }

    fn visit_none<E: Error>(self) -> Result<ron::Value, E> {
        Ok(ron::Value::Option(None))
    }

    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<ron::Value, D::Error> {
        Ok(ron::Value::Option(Some(Box::new(
            d.deserialize_any(StrictVisitor)?,
        ))))
    }

    fn visit_unit<E: Error>(self) -> Result<ron::Value, E> {
        Ok(ron::Value::Unit)
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<ron::Value, D::Error> {
        d.deserialize_any(StrictVisitor)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ron::Value, A::Error> {
        let mut items = Vec::new();
        while let Some(StrictValue(x)) = seq.next_element()? {
            items.push(x);
        }
        Ok(ron::Value::Seq(items))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<ron::Value, A::Error> {
        let mut out = ron::Map::new();
        while let Some(StrictValue(key)) = map.next_key()? {
            if out.get(&key).is_some() {
                let shown = match &key {
                    ron::Value::String(s) => s.clone(),
                    other => ron::to_string(other).unwrap_or_else(|_| format!("{other:?}")),
                };
                return Err(A::Error::custom(format!(
                    "`{shown}` is written twice in this map; keep one"
                )));
            }
            let StrictValue(value) = map.next_value()?;
            out.insert(key, value);
        }
        Ok(ron::Value::Map(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    struct Config {
        #[serde(deserialize_with = "unique_keys")]
        values: BTreeMap<String, ron::Value>,
    }

    #[derive(Debug, Deserialize)]
    struct Strict {
        #[serde(deserialize_with = "unique_values")]
        values: BTreeMap<String, ron::Value>,
    }

    #[test]
    fn a_key_written_twice_inside_a_value_is_refused_where_it_is_written_again() {
        let text = "(values: {\"m/params/actions\": {\n  \"say_a\": (finished: \"x\"),\n  \"say_a\": (finished: \"y\"),\n}})";
        let e = ron::from_str::<Strict>(text).unwrap_err();
        assert_eq!(e.span.start.line, 3, "{e}");
        assert!(e.to_string().contains("`say_a` is written twice"), "{e}");
        // A struct's field twice, inside a list.
        let e = ron::from_str::<Strict>("(values: {\"a\": [(x: 1.0, x: 2.0)]})").unwrap_err();
        assert!(e.to_string().contains("`x` is written twice"), "{e}");
        // Everything else reads as RON's own Value reads it.
        let text = r#"(values: {"a": [1, -2, 3.5, "s", 'c', true, (x: 1.0, y: 2.0), Some(4), None, (), kitchen, {"k": [1, 2]}, (1, 2)]})"#;
        let strict = ron::from_str::<Strict>(text).unwrap();
        let plain = ron::from_str::<Config>(text).unwrap();
        assert_eq!(strict.values, plain.values);
    }

    #[test]
    fn a_key_written_twice_is_refused_where_it_is_written_again() {
        let text = "(values: {\n  \"a\": \"oops\",\n  \"a\": 2.0,\n})";
        let e = ron::from_str::<Config>(text).unwrap_err();
        assert_eq!(e.span.start.line, 3, "{e}");
        assert!(e.to_string().contains("`a` is written twice"), "{e}");
        let ok = ron::from_str::<Config>("(values: {\"a\": 1, \"b\": 2})").unwrap();
        assert_eq!(ok.values.len(), 2);
    }
}
