//! A serialised value kept in memory as what it was written from: the form a method's report
//! section takes in a LOD's report entry, so that the report can hold sections of any method
//! without naming their types, and write each exactly as its own type would (`f32` fields as
//! `f32`, fields in their declared order).
//!
//! `serde_json::Value` would not do: it keeps every float as `f64` (an `f32` 0.1 would be
//! written 0.10000000149011612) and, without its `preserve_order` feature, sorts object keys.

use std::fmt;

use serde::de::{DeserializeOwned, MapAccess, SeqAccess, Visitor};
use serde::ser::{self, Serialize, SerializeMap, SerializeSeq, Serializer};
use serde::{Deserialize, Deserializer};

/// A serialised value: JSON's data model, with floats kept at the width they were written
/// with and object entries in the order they were written.
#[derive(Clone, Debug, PartialEq)]
pub enum SectionValue {
    /// `null`: a unit, a `None`.
    Null,
    /// A boolean.
    Bool(bool),
    /// An unsigned integer.
    U64(u64),
    /// A signed integer.
    I64(i64),
    /// A single-precision float (written as `f32`: its shortest decimal).
    F32(f32),
    /// A double-precision float.
    F64(f64),
    /// A string (or a char, or a unit enum variant's name).
    String(String),
    /// A sequence, tuple or byte string.
    Array(Vec<SectionValue>),
    /// A struct or map, entries in order.
    Object(Vec<(String, SectionValue)>),
}

/// Why a value cannot be kept as a [`SectionValue`] (a map whose keys are not strings or
/// integers), or why a section does not read back as the type asked for.
#[derive(Debug, thiserror::Error)]
#[error("report section: {0}")]
pub struct SectionError(String);

impl ser::Error for SectionError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        SectionError(msg.to_string())
    }
}

impl SectionValue {
    /// `value` as it serialises.
    pub fn of<T: Serialize + ?Sized>(value: &T) -> Result<SectionValue, SectionError> {
        value.serialize(ValueSerializer)
    }

    /// The value read back as a `T` (through its JSON text).
    pub fn to_typed<T: DeserializeOwned>(&self) -> Result<T, SectionError> {
        let text = serde_json::to_string(self).map_err(|e| SectionError(e.to_string()))?;
        serde_json::from_str(&text).map_err(|e| SectionError(e.to_string()))
    }
}

impl Serialize for SectionValue {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            SectionValue::Null => s.serialize_unit(),
            SectionValue::Bool(b) => s.serialize_bool(*b),
            SectionValue::U64(n) => s.serialize_u64(*n),
            SectionValue::I64(n) => s.serialize_i64(*n),
            SectionValue::F32(x) => s.serialize_f32(*x),
            SectionValue::F64(x) => s.serialize_f64(*x),
            SectionValue::String(t) => s.serialize_str(t),
            SectionValue::Array(items) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for item in items {
                    seq.serialize_element(item)?;
                }
                seq.end()
            }
            SectionValue::Object(entries) => {
                let mut map = s.serialize_map(Some(entries.len()))?;
                for (k, v) in entries {
                    map.serialize_entry(k, v)?;
                }
                map.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for SectionValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<SectionValue, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
}

/// Reads any self-describing value (JSON's floats come back as `f64`).
struct ValueVisitor;

impl<'de> Visitor<'de> for ValueVisitor {
    type Value = SectionValue;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<SectionValue, E> {
        Ok(SectionValue::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<SectionValue, E> {
        Ok(SectionValue::I64(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<SectionValue, E> {
        Ok(SectionValue::U64(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<SectionValue, E> {
        Ok(SectionValue::F64(v))
    }
    fn visit_str<E>(self, v: &str) -> Result<SectionValue, E> {
        Ok(SectionValue::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<SectionValue, E> {
        Ok(SectionValue::String(v))
    }
    fn visit_unit<E>(self) -> Result<SectionValue, E> {
        Ok(SectionValue::Null)
    }
    fn visit_none<E>(self) -> Result<SectionValue, E> {
        Ok(SectionValue::Null)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<SectionValue, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<SectionValue, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element()? {
            items.push(item);
        }
        Ok(SectionValue::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<SectionValue, A::Error> {
        let mut entries = Vec::new();
        while let Some((k, v)) = map.next_entry::<String, SectionValue>()? {
            entries.push((k, v));
        }
        Ok(SectionValue::Object(entries))
    }
}

/// Serialises into a [`SectionValue`], as `serde_json` would write the value.
struct ValueSerializer;

/// A sequence, tuple or tuple struct being serialised; `variant` names the enum variant that
/// wraps it (`{"Variant": [...]}`).
struct SeqBuilder {
    variant: Option<&'static str>,
    items: Vec<SectionValue>,
}

/// A map or struct being serialised; `variant` names the enum variant that wraps it.
struct MapBuilder {
    variant: Option<&'static str>,
    entries: Vec<(String, SectionValue)>,
    /// The key of the entry whose value comes next ([`SerializeMap::serialize_key`]).
    key: Option<String>,
}

/// `value` wrapped in its variant's name, as externally tagged enums are written.
fn tagged(variant: Option<&'static str>, value: SectionValue) -> SectionValue {
    match variant {
        Some(v) => SectionValue::Object(vec![(v.to_string(), value)]),
        None => value,
    }
}

impl Serializer for ValueSerializer {
    type Ok = SectionValue;
    type Error = SectionError;
    type SerializeSeq = SeqBuilder;
    type SerializeTuple = SeqBuilder;
    type SerializeTupleStruct = SeqBuilder;
    type SerializeTupleVariant = SeqBuilder;
    type SerializeMap = MapBuilder;
    type SerializeStruct = MapBuilder;
    type SerializeStructVariant = MapBuilder;

    fn serialize_bool(self, v: bool) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::Bool(v))
    }
    fn serialize_i8(self, v: i8) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::I64(v.into()))
    }
    fn serialize_i16(self, v: i16) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::I64(v.into()))
    }
    fn serialize_i32(self, v: i32) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::I64(v.into()))
    }
    fn serialize_i64(self, v: i64) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::I64(v))
    }
    fn serialize_u8(self, v: u8) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::U64(v.into()))
    }
    fn serialize_u16(self, v: u16) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::U64(v.into()))
    }
    fn serialize_u32(self, v: u32) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::U64(v.into()))
    }
    fn serialize_u64(self, v: u64) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::U64(v))
    }
    fn serialize_f32(self, v: f32) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::F32(v))
    }
    fn serialize_f64(self, v: f64) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::F64(v))
    }
    fn serialize_char(self, v: char) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::String(v.to_string()))
    }
    fn serialize_str(self, v: &str) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::String(v.to_string()))
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::Array(
            v.iter().map(|&b| SectionValue::U64(b.into())).collect(),
        ))
    }
    fn serialize_none(self) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::Null)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<SectionValue, SectionError> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::Null)
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::Null)
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<SectionValue, SectionError> {
        Ok(SectionValue::String(variant.to_string()))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<SectionValue, SectionError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        v: &T,
    ) -> Result<SectionValue, SectionError> {
        Ok(tagged(Some(variant), v.serialize(self)?))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<SeqBuilder, SectionError> {
        Ok(SeqBuilder {
            variant: None,
            items: Vec::with_capacity(len.unwrap_or(0)),
        })
    }
    fn serialize_tuple(self, len: usize) -> Result<SeqBuilder, SectionError> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_struct(
        self,
        _: &'static str,
        len: usize,
    ) -> Result<SeqBuilder, SectionError> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<SeqBuilder, SectionError> {
        Ok(SeqBuilder {
            variant: Some(variant),
            items: Vec::with_capacity(len),
        })
    }
    fn serialize_map(self, _: Option<usize>) -> Result<MapBuilder, SectionError> {
        Ok(MapBuilder {
            variant: None,
            entries: Vec::new(),
            key: None,
        })
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<MapBuilder, SectionError> {
        self.serialize_map(None)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<MapBuilder, SectionError> {
        Ok(MapBuilder {
            variant: Some(variant),
            entries: Vec::new(),
            key: None,
        })
    }
}

impl SeqBuilder {
    /// Adds one element.
    fn push<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SectionError> {
        self.items.push(v.serialize(ValueSerializer)?);
        Ok(())
    }
    /// The finished array, in its variant when it has one.
    fn finish(self) -> Result<SectionValue, SectionError> {
        Ok(tagged(self.variant, SectionValue::Array(self.items)))
    }
}

impl ser::SerializeSeq for SeqBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SectionError> {
        self.push(v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

impl ser::SerializeTuple for SeqBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SectionError> {
        self.push(v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

impl ser::SerializeTupleStruct for SeqBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SectionError> {
        self.push(v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

impl ser::SerializeTupleVariant for SeqBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SectionError> {
        self.push(v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

impl MapBuilder {
    /// Adds one entry.
    fn insert<T: Serialize + ?Sized>(&mut self, key: String, v: &T) -> Result<(), SectionError> {
        self.entries.push((key, v.serialize(ValueSerializer)?));
        Ok(())
    }
    /// The finished object, in its variant when it has one.
    fn finish(self) -> Result<SectionValue, SectionError> {
        Ok(tagged(self.variant, SectionValue::Object(self.entries)))
    }
}

/// A map key as JSON writes it: strings as they are, integers, booleans and chars as text.
fn key_text<T: Serialize + ?Sized>(key: &T) -> Result<String, SectionError> {
    match key.serialize(ValueSerializer)? {
        SectionValue::String(s) => Ok(s),
        SectionValue::U64(n) => Ok(n.to_string()),
        SectionValue::I64(n) => Ok(n.to_string()),
        SectionValue::Bool(b) => Ok(b.to_string()),
        other => Err(SectionError(format!(
            "a map key must be a string, not {other:?}"
        ))),
    }
}

impl SerializeMap for MapBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), SectionError> {
        self.key = Some(key_text(key)?);
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SectionError> {
        let key = self
            .key
            .take()
            .ok_or_else(|| SectionError("a map value without its key".into()))?;
        self.insert(key, v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

impl ser::SerializeStruct for MapBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), SectionError> {
        self.insert(key.to_string(), v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

impl ser::SerializeStructVariant for MapBuilder {
    type Ok = SectionValue;
    type Error = SectionError;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), SectionError> {
        self.insert(key.to_string(), v)
    }
    fn end(self) -> Result<SectionValue, SectionError> {
        self.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;

    #[derive(Serialize)]
    struct Sample {
        name: &'static str,
        count: usize,
        ratio: f32,
        error: f64,
        nothing: Option<u8>,
        list: Vec<i32>,
        nested: Inner,
        not_a_number: f32,
    }

    #[derive(Serialize)]
    struct Inner {
        z: bool,
        a: (u8, char),
    }

    #[test]
    fn a_value_writes_as_its_type_does() {
        let sample = Sample {
            name: "x\"y",
            count: 7,
            ratio: 0.1,
            error: 0.30000000000000004,
            nothing: None,
            list: vec![-1, 2],
            nested: Inner {
                z: true,
                a: (3, 'c'),
            },
            not_a_number: f32::NAN,
        };
        let value = SectionValue::of(&sample).unwrap();
        assert_eq!(
            serde_json::to_string_pretty(&value).unwrap(),
            serde_json::to_string_pretty(&sample).unwrap()
        );
        // Read back from its text, it writes the same text again.
        let text = serde_json::to_string(&value).unwrap();
        let back: SectionValue = serde_json::from_str(&text).unwrap();
        assert_eq!(serde_json::to_string(&back).unwrap(), text);
    }
}
