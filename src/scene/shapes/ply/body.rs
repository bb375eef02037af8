//! STAGE 2 (scene loading, PLY reader): decoding the body — binary (either endianness) and ascii values,
//! with errors that say which record the data ran out in.

use super::header::{Element, Kind, Property, Scalar};

/// Why reading a value failed.
#[derive(Debug)]
pub(super) enum BodyErr {
    /// The data ran out.
    Eof,
    /// A malformed value; the message says where and what.
    Bad(String),
}

impl BodyErr {
    /// The message for this failure while reading property `prop` of record `done` of `el`.
    pub(super) fn describe(self, done: u64, el: &Element, prop: &Property) -> String {
        match self {
            BodyErr::Eof => format!(
                "file ends after {done} of {} {} (the file is truncated, or its header is wrong)",
                el.count,
                el.plural()
            ),
            BodyErr::Bad(msg) => {
                format!("{msg} (property \"{}\" of {} {done})", prop.name, el.name)
            }
        }
    }
}

/// A body decoder: a stream of values whose types the header gives.
pub(super) trait Body {
    /// Reads the next value of type `ty`, widened to f64 (exact for every PLY type).
    fn value(&mut self, ty: Scalar) -> Result<f64, BodyErr>;
    /// Skips `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), BodyErr>;
    /// At most how many records of `el` the rest of the data can hold (caps allocations).
    fn max_records(&self, el: &Element) -> usize;
}

/// Decodes a binary body; `BIG` selects big-endian.
pub(super) struct Binary<'a, const BIG: bool> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
}

macro_rules! decode {
    ($rest:expr, $t:ty) => {
        $rest.first_chunk().map(|b| (if BIG { <$t>::from_be_bytes(*b) } else { <$t>::from_le_bytes(*b) }) as f64)
    };
}

impl<const BIG: bool> Body for Binary<'_, BIG> {
    #[inline]
    fn value(&mut self, ty: Scalar) -> Result<f64, BodyErr> {
        let rest = self.data.get(self.pos..).unwrap_or_default();
        let v = match ty {
            Scalar::I8 => decode!(rest, i8),
            Scalar::U8 => decode!(rest, u8),
            Scalar::I16 => decode!(rest, i16),
            Scalar::U16 => decode!(rest, u16),
            Scalar::I32 => decode!(rest, i32),
            Scalar::U32 => decode!(rest, u32),
            Scalar::F32 => decode!(rest, f32),
            Scalar::F64 => decode!(rest, f64),
        };
        let v = v.ok_or(BodyErr::Eof)?;
        self.pos += ty.size();
        Ok(v)
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), BodyErr> {
        let left = self.data.len() - self.pos;
        let bytes = usize::try_from(n).ok().and_then(|n| n.checked_mul(ty.size()));
        match bytes {
            Some(b) if b <= left => {
                self.pos += b;
                Ok(())
            }
            _ => Err(BodyErr::Eof),
        }
    }

    fn max_records(&self, el: &Element) -> usize {
        let min_size: usize = el
            .props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(ty) => ty.size(),
                Kind::List { len, .. } => len.size(),
            })
            .sum();
        (self.data.len() - self.pos) / min_size.max(1)
    }
}

/// Decodes an ascii body: values separated by whitespace, counting lines for messages.
pub(super) struct Ascii<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    /// The file line that `pos` is on.
    pub(super) line: usize,
}

impl<'a> Ascii<'a> {
    pub(super) fn token(&mut self) -> Option<&'a [u8]> {
        while let Some(&c) = self.data.get(self.pos).filter(|c| c.is_ascii_whitespace()) {
            self.line += usize::from(c == b'\n');
            self.pos += 1;
        }
        let start = self.pos;
        while self.data.get(self.pos).is_some_and(|c| !c.is_ascii_whitespace()) {
            self.pos += 1;
        }
        self.data.get(start..self.pos).filter(|t| !t.is_empty())
    }
}

impl Body for Ascii<'_> {
    fn value(&mut self, ty: Scalar) -> Result<f64, BodyErr> {
        let token = self.token().ok_or(BodyErr::Eof)?;
        let text = std::str::from_utf8(token).ok();
        let v = if ty.is_float() {
            text.and_then(|t| t.parse::<f64>().ok())
        } else {
            text.and_then(|t| t.parse::<i64>().ok()).map(|v| v as f64)
        };
        v.ok_or_else(|| {
            let shown: String = String::from_utf8_lossy(token).chars().take(40).collect();
            let want = if ty.is_float() { "a number" } else { "an integer" };
            BodyErr::Bad(format!("line {}: expected {want}, found \"{shown}\"", self.line))
        })
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), BodyErr> {
        for _ in 0..n {
            self.value(ty)?;
        }
        Ok(())
    }

    fn max_records(&self, el: &Element) -> usize {
        // Each value takes at least one character and one separator.
        (self.data.len() - self.pos) / (2 * el.props.len()).max(1)
    }
}
