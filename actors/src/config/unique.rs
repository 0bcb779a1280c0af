//! Maps read from configs and rules files that refuse a key written twice. Serde's own map
//! keeps the last value without a word, so `{"params/factor": "oops", "params/factor": 2.0}`
//! passed `petrel check` with its first, invalid value never looked at.

use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;

use serde::de::{Deserializer, Error, MapAccess, Visitor};
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

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    struct Config {
        #[serde(deserialize_with = "unique_keys")]
        values: BTreeMap<String, ron::Value>,
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
