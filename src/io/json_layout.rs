//! The layout of the JSON files the crate writes: any serde value, keys in the order it
//! serializes them (serde_json's own map would sort them), scalars, vectors and 3-row
//! matrices on one line, one sample per line, everything else indented by two spaces.
//!
//! Numbers are serde_json's: the shortest text that reads back to the same f64, non-finite
//! ones as `null`.

use serde::Serialize;
use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use std::fmt;
use std::fmt::Write;

/// A JSON value with its keys in the order written.
enum Json {
    Null,
    Bool(bool),
    Integer(i128),
    Number(f64),
    Text(String),
    Array(Vec<Json>),
    Object(Vec<(String, Json)>),
}

/// `value` as JSON text in the layout of this module, ending with a newline.
pub(crate) fn pretty<T: Serialize>(value: &T) -> String {
    // serde_json writes the value compactly (keys in order, numbers in their shortest
    // round-trip form); reading that text back as a `Json` keeps both.
    let tree = serde_json::to_string(value)
        .ok()
        .and_then(|text| serde_json::from_str::<Json>(&text).ok())
        .unwrap_or(Json::Null);
    let mut text = String::new();
    tree.write(&mut text, 0, false);
    text.push('\n');
    text
}

impl Json {
    fn is_scalar(&self) -> bool {
        !matches!(self, Json::Array(_) | Json::Object(_))
    }

    /// Scalars, vectors and 3-row matrices: written on one line.
    fn is_small(&self) -> bool {
        match self {
            Json::Array(items) => {
                items.iter().all(Json::is_scalar)
                    || items.len() <= 3
                        && items
                            .iter()
                            .all(|i| matches!(i, Json::Array(r) if r.iter().all(Json::is_scalar)))
            }
            Json::Object(_) => false,
            _ => true,
        }
    }

    /// Objects inside arrays whose values are all small go on one line (one sample per
    /// line); everything else is indented.
    fn write(&self, out: &mut String, indent: usize, in_array: bool) {
        let pad = |n: usize| " ".repeat(n);
        match self {
            Json::Null => out.push_str("null"),
            Json::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
            Json::Integer(i) => out.push_str(&i.to_string()),
            // serde_json formats numbers and escapes strings; neither can fail.
            Json::Number(x) => out.push_str(&serde_json::to_string(x).unwrap_or_else(|_| "null".into())),
            Json::Text(t) => out.push_str(&quoted(t)),
            Json::Array(items) if items.is_empty() => out.push_str("[]"),
            Json::Array(items) if self.is_small() => {
                out.push('[');
                for (k, item) in items.iter().enumerate() {
                    if k > 0 {
                        out.push_str(", ");
                    }
                    item.write(out, indent, true);
                }
                out.push(']');
            }
            Json::Array(items) => {
                out.push_str("[\n");
                for (k, item) in items.iter().enumerate() {
                    out.push_str(&pad(indent + 2));
                    item.write(out, indent + 2, true);
                    out.push_str(if k + 1 < items.len() { ",\n" } else { "\n" });
                }
                out.push_str(&pad(indent));
                out.push(']');
            }
            Json::Object(fields) if in_array && fields.iter().all(|(_, v)| v.is_small()) => {
                out.push('{');
                for (k, (key, value)) in fields.iter().enumerate() {
                    if k > 0 {
                        out.push_str(", ");
                    }
                    let _ = write!(out, "{}: ", quoted(key));
                    value.write(out, indent, true);
                }
                out.push('}');
            }
            Json::Object(fields) => {
                out.push_str("{\n");
                for (k, (key, value)) in fields.iter().enumerate() {
                    let _ = write!(out, "{}{}: ", pad(indent + 2), quoted(key));
                    value.write(out, indent + 2, false);
                    out.push_str(if k + 1 < fields.len() { ",\n" } else { "\n" });
                }
                out.push_str(&pad(indent));
                out.push('}');
            }
        }
    }
}

/// A string as JSON writes it, quoted and escaped by serde_json (which cannot fail on a
/// string).
fn quoted(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_else(|_| "\"\"".into())
}

/// Reads serde_json's compact text back into a tree, keys in file order.
impl<'de> Deserialize<'de> for Json {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(TreeVisitor)
    }
}

struct TreeVisitor;

impl<'de> Visitor<'de> for TreeVisitor {
    type Value = Json;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_unit<E: de::Error>(self) -> Result<Json, E> {
        Ok(Json::Null)
    }

    fn visit_bool<E: de::Error>(self, b: bool) -> Result<Json, E> {
        Ok(Json::Bool(b))
    }

    fn visit_i64<E: de::Error>(self, i: i64) -> Result<Json, E> {
        Ok(Json::Integer(i.into()))
    }

    fn visit_u64<E: de::Error>(self, i: u64) -> Result<Json, E> {
        Ok(Json::Integer(i.into()))
    }

    fn visit_f64<E: de::Error>(self, x: f64) -> Result<Json, E> {
        Ok(Json::Number(x))
    }

    fn visit_str<E: de::Error>(self, t: &str) -> Result<Json, E> {
        Ok(Json::Text(t.to_string()))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Json, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element()? {
            items.push(item);
        }
        Ok(Json::Array(items))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Json, A::Error> {
        let mut fields = Vec::new();
        while let Some(entry) = map.next_entry()? {
            fields.push(entry);
        }
        Ok(Json::Object(fields))
    }
}
