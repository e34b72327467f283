//! A small serde `Deserializer` for the subset of RON that graph files use, about ten
//! times faster than `ron` on large graphs. It only ever answers "this value" or "no":
//! any error, and anything outside the subset, makes the caller parse with `ron`, which
//! then produces the real error and its position.
//!
//! The rule it keeps: whenever it returns a value, `ron` (with `UNWRAP_VARIANT_NEWTYPES`)
//! returns the same value for the same text. serde's derive drives every struct, enum,
//! field, default and `deny_unknown_fields` rule; this file only reads tokens, and where
//! `ron`'s token rules are wide (unicode identifiers and whitespace, escapes, raw strings,
//! number prefixes, suffixes and underscores, `inf`/`NaN`, attributes) it accepts less:
//!
//! - whitespace: space, tab, `\n`, `\r`; `//` line comments, nested `/* */` comments;
//! - identifiers: ASCII `[A-Za-z_][A-Za-z0-9_]*`, not followed by a non-ASCII byte or
//!   any byte `ron` would read as part of a (raw) identifier or literal prefix;
//! - strings: `"..."` without a backslash (so no escapes or continuations);
//! - unsigned integers: decimal digits only, no sign, no `_`, no suffix;
//! - `f32`: a run of `[0-9eE.+-]` (what `ron` reads as a float) given to `f32::from_str`,
//!   exactly as `ron` does, without `_` or `..`;
//! - `bool`, `Option` (`Some(..)` / `None`), lists, tuples, named or anonymous structs,
//!   unit / newtype / tuple / struct enum variants, with `ron`'s comma rules (a trailing
//!   comma allowed, never two);
//! - newtype variants and `Some(..)` unwrap a struct inside (`LightCulling(tile: 16)`),
//!   like `ron`'s `UNWRAP_VARIANT_NEWTYPES`.
//!
//! Everything else (maps, chars, bytes, signed integers, `f64`, unit and newtype structs,
//! `deserialize_any` and therefore ignored unknown fields) is an error here.

use serde::de::{self, DeserializeSeed, Visitor};
use std::fmt;

/// "Not handled here": the caller falls back to `ron`.
#[derive(Debug)]
pub struct Fail;

impl fmt::Display for Fail {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("not in the fast RON subset")
    }
}

impl std::error::Error for Fail {}

impl de::Error for Fail {
    fn custom<T: fmt::Display>(_msg: T) -> Self {
        Fail
    }
}

type R<T> = Result<T, Fail>;

/// Deserializes a whole document: one value, then only whitespace and comments.
pub fn from_str<'de, T: de::Deserialize<'de>>(text: &'de str) -> Option<T> {
    let mut de = Deserializer {
        text,
        bytes: text.as_bytes(),
        pos: 0,
        unwrapped: false,
    };
    de.ws().ok()?;
    let value = T::deserialize(&mut de).ok()?;
    de.ws().ok()?;
    (de.pos == de.bytes.len()).then_some(value)
}

pub struct Deserializer<'de> {
    text: &'de str,
    bytes: &'de [u8],
    pos: usize,
    /// Set inside `Variant(` and `Some(`: a struct or tuple there has no parentheses of
    /// its own (ron's `UNWRAP_VARIANT_NEWTYPES`).
    unwrapped: bool,
}

fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}

fn is_ident_continue(b: u8) -> bool {
    IDENT_CONTINUE[b as usize]
}

/// `[A-Za-z0-9_]` by byte, for the identifier loop.
static IDENT_CONTINUE: [bool; 256] = {
    let mut t = [false; 256];
    let mut i = 0;
    while i < 256 {
        let b = i as u8;
        t[i] = b.is_ascii_alphanumeric() || b == b'_';
        i += 1;
    }
    t
};

impl<'de> Deserializer<'de> {
    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.pos).copied()
    }

    fn eat(&mut self, b: u8) -> bool {
        if self.peek() == Some(b) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, b: u8) -> R<()> {
        if self.eat(b) {
            Ok(())
        } else {
            Err(Fail)
        }
    }

    /// Skips whitespace and comments (ron's `skip_ws`, on a narrower whitespace set).
    fn ws(&mut self) -> R<()> {
        let bytes = self.bytes;
        loop {
            while let Some(b' ' | b'\t' | b'\n' | b'\r') = bytes.get(self.pos) {
                self.pos += 1;
            }
            if bytes.get(self.pos) != Some(&b'/') {
                return Ok(());
            }
            match bytes.get(self.pos + 1) {
                Some(b'/') => {
                    // To the end of the line; the newline itself is whitespace.
                    self.pos = match bytes[self.pos..].iter().position(|&b| b == b'\n') {
                        Some(n) => self.pos + n,
                        None => bytes.len(),
                    };
                }
                Some(b'*') => {
                    self.pos += 2;
                    let mut depth = 1usize;
                    while depth > 0 {
                        match (bytes.get(self.pos), bytes.get(self.pos + 1)) {
                            (None, _) => return Err(Fail),
                            (Some(b'/'), Some(b'*')) => {
                                depth += 1;
                                self.pos += 2;
                            }
                            (Some(b'*'), Some(b'/')) => {
                                depth -= 1;
                                self.pos += 2;
                            }
                            _ => self.pos += 1,
                        }
                    }
                }
                _ => return Err(Fail),
            }
        }
    }

    /// ron's `comma`: whitespace, an optional comma, whitespace.
    fn comma(&mut self) -> R<bool> {
        self.ws()?;
        let had = self.eat(b',');
        if had {
            self.ws()?;
        }
        Ok(had)
    }

    /// Whether an identifier starts here.
    fn at_ident(&self) -> bool {
        self.peek().is_some_and(is_ident_start)
    }

    fn ident(&mut self) -> R<&'de str> {
        let start = self.pos;
        if !self.at_ident() {
            return Err(Fail);
        }
        let rest = &self.bytes[start + 1..];
        let end = start
            + 1
            + rest
                .iter()
                .position(|&b| !is_ident_continue(b))
                .unwrap_or(rest.len());
        // A non-ASCII byte could continue the identifier for ron (unicode XID); `.+-`
        // make a raw-identifier suggestion; `"#'` make raw/byte strings or raw
        // identifiers. None of these may follow an identifier in the subset anyway.
        if let Some(b) = self.bytes.get(end) {
            if *b >= 0x80 || matches!(b, b'.' | b'+' | b'-' | b'"' | b'#' | b'\'') {
                return Err(Fail);
            }
        }
        self.pos = end;
        Ok(&self.text[start..end])
    }

    /// Ends a number token: nothing ron could read as a suffix or a longer literal.
    fn number_end(&self, end: usize) -> R<()> {
        match self.bytes.get(end) {
            Some(&b) if b >= 0x80 || is_ident_continue(b) || matches!(b, b'.' | b'+' | b'-') => {
                Err(Fail)
            }
            _ => Ok(()),
        }
    }

    fn unsigned(&mut self, max: u64) -> R<u64> {
        let start = self.pos;
        let mut end = start;
        let mut value: u64 = 0;
        while let Some(&b) = self.bytes.get(end) {
            if !b.is_ascii_digit() {
                break;
            }
            value = value
                .checked_mul(10)
                .and_then(|v| v.checked_add(u64::from(b - b'0')))
                .ok_or(Fail)?;
            end += 1;
        }
        if end == start || value > max {
            return Err(Fail);
        }
        self.number_end(end)?;
        self.pos = end;
        Ok(value)
    }

    fn float32(&mut self) -> R<f32> {
        let start = self.pos;
        let mut end = start;
        while let Some(b'0'..=b'9' | b'e' | b'E' | b'.' | b'+' | b'-') = self.bytes.get(end) {
            end += 1;
        }
        let token = &self.text[start..end];
        if token.is_empty() || token.contains("..") {
            return Err(Fail);
        }
        // `_` would belong to ron's float token; anything else identifier-like a suffix.
        self.number_end(end)?;
        let value = token.parse::<f32>().map_err(|_| Fail)?;
        self.pos = end;
        Ok(value)
    }

    fn string(&mut self) -> R<&'de str> {
        self.expect(b'"')?;
        let start = self.pos;
        let len = self.bytes[start..]
            .iter()
            .position(|&b| b == b'"' || b == b'\\')
            .ok_or(Fail)?;
        let end = start + len;
        if self.bytes[end] == b'\\' {
            return Err(Fail);
        }
        self.pos = end + 1;
        Ok(&self.text[start..end])
    }
}

/// ron's comma-separated list between brackets: elements (or `key: value` fields), a
/// comma after each but possibly the last.
struct Separated<'a, 'de> {
    de: &'a mut Deserializer<'de>,
    close: u8,
    had_comma: bool,
}

impl<'a, 'de> Separated<'a, 'de> {
    fn new(de: &'a mut Deserializer<'de>, close: u8) -> Self {
        Separated {
            de,
            close,
            had_comma: true,
        }
    }

    fn has_element(&mut self) -> R<bool> {
        self.de.ws()?;
        let at_close = self.de.peek() == Some(self.close);
        match (self.had_comma, at_close) {
            (true, at_close) => Ok(!at_close),
            (false, true) => Ok(false),
            (false, false) => Err(Fail),
        }
    }
}

impl<'de> de::SeqAccess<'de> for Separated<'_, 'de> {
    type Error = Fail;

    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> R<Option<T::Value>> {
        if !self.has_element()? {
            return Ok(None);
        }
        let value = seed.deserialize(&mut *self.de)?;
        self.had_comma = self.de.comma()?;
        Ok(Some(value))
    }
}

impl<'de> de::MapAccess<'de> for Separated<'_, 'de> {
    type Error = Fail;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> R<Option<K::Value>> {
        if !self.has_element()? {
            return Ok(None);
        }
        seed.deserialize(FieldName(&mut *self.de)).map(Some)
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> R<V::Value> {
        self.de.ws()?;
        self.de.expect(b':')?;
        self.de.ws()?;
        let value = seed.deserialize(&mut *self.de)?;
        self.had_comma = self.de.comma()?;
        Ok(value)
    }
}

/// A struct field name: an identifier, nothing else (ron reads keys the same way).
struct FieldName<'a, 'de>(&'a mut Deserializer<'de>);

impl<'de> de::Deserializer<'de> for FieldName<'_, 'de> {
    type Error = Fail;

    fn deserialize_any<V: Visitor<'de>>(self, _visitor: V) -> R<V::Value> {
        Err(Fail)
    }

    fn deserialize_identifier<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_borrowed_str(self.0.ident()?)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map struct enum ignored_any
    }
}

impl<'de> Deserializer<'de> {
    /// After `Variant` or `Some`: `(`, the payload (unwrapped), an optional comma, `)`.
    fn unwrapped_payload<T>(&mut self, f: impl FnOnce(&mut Self) -> R<T>) -> R<T> {
        self.ws()?;
        self.expect(b'(')?;
        self.ws()?;
        self.unwrapped = true;
        let value = f(self)?;
        self.unwrapped = false;
        self.comma()?;
        self.expect(b')')?;
        Ok(value)
    }

    /// The fields of a struct (or struct variant) up to `)`, which is consumed unless
    /// the struct is unwrapped in a newtype variant.
    fn struct_body<V: Visitor<'de>>(&mut self, visitor: V) -> R<V::Value> {
        let unwrapped = std::mem::replace(&mut self.unwrapped, false);
        if !unwrapped {
            self.expect(b'(')?;
        }
        let value = visitor.visit_map(Separated::new(self, b')'))?;
        self.ws()?;
        if !unwrapped {
            self.expect(b')')?;
        }
        Ok(value)
    }
}

impl<'de> de::Deserializer<'de> for &mut Deserializer<'de> {
    type Error = Fail;

    fn deserialize_any<V: Visitor<'de>>(self, _visitor: V) -> R<V::Value> {
        Err(Fail)
    }

    fn deserialize_bool<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        match self.ident()? {
            "true" => visitor.visit_bool(true),
            "false" => visitor.visit_bool(false),
            _ => Err(Fail),
        }
    }

    fn deserialize_u8<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_u8(self.unsigned(u8::MAX.into())? as u8)
    }

    fn deserialize_u16<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_u16(self.unsigned(u16::MAX.into())? as u16)
    }

    fn deserialize_u32<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_u32(self.unsigned(u32::MAX.into())? as u32)
    }

    fn deserialize_u64<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_u64(self.unsigned(u64::MAX)?)
    }

    fn deserialize_f32<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_f32(self.float32()?)
    }

    fn deserialize_str<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_borrowed_str(self.string()?)
    }

    fn deserialize_string<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_borrowed_str(self.string()?)
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        match self.ident()? {
            "None" => visitor.visit_none(),
            "Some" => self.unwrapped_payload(|de| visitor.visit_some(de)),
            _ => Err(Fail),
        }
    }

    fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        self.unwrapped = false;
        self.expect(b'[')?;
        let value = visitor.visit_seq(Separated::new(self, b']'))?;
        self.ws()?;
        self.expect(b']')?;
        Ok(value)
    }

    fn deserialize_tuple<V: Visitor<'de>>(self, _len: usize, visitor: V) -> R<V::Value> {
        let unwrapped = std::mem::replace(&mut self.unwrapped, false);
        if !unwrapped {
            self.expect(b'(')?;
        }
        let value = visitor.visit_seq(Separated::new(self, b')'))?;
        self.ws()?;
        if !unwrapped {
            self.expect(b')')?;
        }
        Ok(value)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> R<V::Value> {
        // ron reads `Range*` structs as `a..b`; not part of the subset.
        if name.starts_with("Range") {
            return Err(Fail);
        }
        if !self.unwrapped && self.at_ident() {
            // An optional struct name, which must be the (serde) name.
            if name.is_empty() || self.ident()? != name {
                return Err(Fail);
            }
            self.ws()?;
        }
        self.struct_body(visitor)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> R<V::Value> {
        self.unwrapped = false;
        visitor.visit_enum(self)
    }

    fn deserialize_identifier<V: Visitor<'de>>(self, visitor: V) -> R<V::Value> {
        visitor.visit_borrowed_str(self.ident()?)
    }

    serde::forward_to_deserialize_any! {
        i8 i16 i32 i64 i128 u128 f64 char bytes byte_buf unit unit_struct
        newtype_struct tuple_struct map ignored_any
    }
}

impl<'de> de::EnumAccess<'de> for &mut Deserializer<'de> {
    type Error = Fail;
    type Variant = Self;

    fn variant_seed<V: DeserializeSeed<'de>>(self, seed: V) -> R<(V::Value, Self)> {
        self.ws()?;
        let variant = seed.deserialize(&mut *self)?;
        Ok((variant, self))
    }
}

impl<'de> de::VariantAccess<'de> for &mut Deserializer<'de> {
    type Error = Fail;

    fn unit_variant(self) -> R<()> {
        Ok(())
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> R<T::Value> {
        self.unwrapped_payload(|de| seed.deserialize(de))
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, visitor: V) -> R<V::Value> {
        self.ws()?;
        de::Deserializer::deserialize_tuple(self, len, visitor)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> R<V::Value> {
        self.ws()?;
        self.struct_body(visitor)
    }
}
