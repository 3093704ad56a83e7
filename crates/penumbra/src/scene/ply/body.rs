//! The body of a PLY file, value by value: whitespace-separated words in an ASCII body, packed
//! values of the header's byte order in a binary one. Every value read knows where it starts
//! (a line, or a byte offset), for the error that names it.

use super::header::{Format, Scalar};
use super::{At, PlyError};

/// A cursor over the body of a PLY file.
pub(super) struct Body<'a> {
    bytes: &'a [u8],
    format: Format,
    /// The next byte to read.
    pos: usize,
    /// The line `pos` is on (ASCII).
    line: usize,
    /// Where the value read last starts.
    start: At,
}

impl<'a> Body<'a> {
    /// The body of `format` starting at byte `pos`, on line `line`, of `bytes`.
    pub(super) fn new(bytes: &'a [u8], format: Format, pos: usize, line: usize) -> Body<'a> {
        let start = match format {
            Format::Ascii => At::Line(line),
            _ => At::Byte(pos),
        };
        Body {
            bytes,
            format,
            pos,
            line,
            start,
        }
    }

    /// Where the value read last starts, or where the next one starts before any.
    pub(super) fn at(&self) -> At {
        self.start
    }

    /// Bytes not yet read.
    pub(super) fn left(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// The format of the body.
    pub(super) fn format(&self) -> Format {
        self.format
    }

    /// The bytes not yet read (for the bulk reads of `fast`).
    pub(super) fn rest(&self) -> &'a [u8] {
        &self.bytes[self.pos..]
    }

    /// Passes over `n` bytes that a bulk read took from [`Body::rest`] (at most its length).
    pub(super) fn advance(&mut self, n: usize) {
        self.pos += n.min(self.left());
        self.start = At::Byte(self.pos);
    }

    /// The next value, of type `ty`. Integers come back exactly (every PLY integer fits an
    /// `f64`); an ASCII integer must be written as one and be in its type's range.
    pub(super) fn scalar(&mut self, ty: Scalar) -> Result<f64, PlyError> {
        match self.format {
            Format::Ascii => self.ascii(ty),
            Format::LittleEndian => self.binary(ty, false),
            Format::BigEndian => self.binary(ty, true),
        }
    }

    /// A list's count, of type `ty`: a whole number, not negative.
    pub(super) fn count(&mut self, ty: Scalar) -> Result<u64, PlyError> {
        let n = self.scalar(ty)?;
        if n < 0.0 {
            return Err(PlyError::new(
                self.start,
                format!("a negative list count ({n})"),
            ));
        }
        Ok(n as u64)
    }

    /// Passes over `n` values of type `ty` (a list nobody reads).
    pub(super) fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), PlyError> {
        if self.format == Format::Ascii {
            for _ in 0..n {
                self.word()?;
            }
            return Ok(());
        }
        self.start = At::Byte(self.pos);
        let len = n.saturating_mul(ty.size() as u64);
        if len > self.left() as u64 {
            return Err(self.ended(format!("{n} list values of {} bytes", ty.size())));
        }
        self.pos += len as usize;
        Ok(())
    }

    /// The error for a body that ends before `what`.
    fn ended(&self, what: String) -> PlyError {
        PlyError::new(
            self.start,
            format!("the file ends early: expected {what}; it is truncated, or its header's counts are wrong"),
        )
    }

    fn binary(&mut self, ty: Scalar, big: bool) -> Result<f64, PlyError> {
        self.start = At::Byte(self.pos);
        let size = ty.size();
        let Some(b) = self.bytes.get(self.pos..self.pos + size) else {
            return Err(self.ended(format!("a value of {size} bytes")));
        };
        self.pos += size;
        Ok(load(b, ty, big))
    }

    fn ascii(&mut self, ty: Scalar) -> Result<f64, PlyError> {
        let word = self.word()?;
        let bad = |what: &str| {
            PlyError::new(
                self.start,
                format!(
                    "{} is not {what}",
                    super::quoted(&String::from_utf8_lossy(word))
                ),
            )
        };
        let text = std::str::from_utf8(word).map_err(|_| bad("a number"))?;
        if ty.is_float() {
            return text.parse::<f64>().map_err(|_| bad("a number"));
        }
        let (lo, hi): (i64, i64) = match ty {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            _ => (0, u32::MAX.into()),
        };
        match text.parse::<i64>() {
            Ok(n) if (lo..=hi).contains(&n) => Ok(n as f64),
            Ok(_) => Err(bad(&format!("in the range of its type ({lo}..{hi})"))),
            Err(_) => Err(bad("a whole number")),
        }
    }

    /// Passes over the words left on the current line of an ASCII body (values beyond a row's
    /// properties: each row of an ASCII body is one line, as MeshLab and trimesh read it) and
    /// returns how many there were, with the line they are on. Nothing for a binary body.
    pub(super) fn end_row(&mut self) -> (u64, usize) {
        let line = self.line;
        let mut extra = 0;
        if self.format != Format::Ascii {
            return (0, line);
        }
        loop {
            let bytes = self.bytes;
            while let Some(&b) = bytes.get(self.pos).filter(|&&b| b != b'\n') {
                if !b.is_ascii_whitespace() {
                    break;
                }
                self.pos += 1;
            }
            match bytes.get(self.pos) {
                None | Some(b'\n') => return (extra, line),
                Some(_) => {
                    extra += 1;
                    while bytes
                        .get(self.pos)
                        .is_some_and(|b| !b.is_ascii_whitespace())
                    {
                        self.pos += 1;
                    }
                }
            }
        }
    }

    /// The next whitespace-separated word of an ASCII body.
    fn word(&mut self) -> Result<&'a [u8], PlyError> {
        let bytes = self.bytes;
        while let Some(&b) = bytes.get(self.pos).filter(|b| b.is_ascii_whitespace()) {
            self.line += usize::from(b == b'\n');
            self.pos += 1;
        }
        self.start = At::Line(self.line);
        let begin = self.pos;
        while bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        if begin == self.pos {
            return Err(self.ended("another value".into()));
        }
        Ok(&bytes[begin..self.pos])
    }
}

/// The value of type `ty` in `bytes` (exactly its size), in the byte order `big`. Integers
/// come back exactly.
#[inline(always)]
pub(super) fn load(bytes: &[u8], ty: Scalar, big: bool) -> f64 {
    let mut a = [0u8; 8];
    a[..bytes.len()].copy_from_slice(bytes);
    if big {
        a[..bytes.len()].reverse();
    }
    match ty {
        Scalar::I8 => a[0] as i8 as f64,
        Scalar::U8 => a[0] as f64,
        Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
        Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
        Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        Scalar::F64 => f64::from_le_bytes(a),
    }
}
