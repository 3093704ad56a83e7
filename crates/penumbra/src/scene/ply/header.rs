//! The PLY header: the format line, then the elements in file order, each with its count and
//! properties, up to `end_header`.

use super::{quoted, At, PlyError};

/// How the body is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Format {
    Ascii,
    LittleEndian,
    BigEndian,
}

/// A scalar type of the PLY format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type a header word names (both the old and the sized spellings).
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes of one value in a binary body.
    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// True for the two floating-point types.
    pub(super) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// One property of an element: a scalar, or a list (its count's type, its items' type).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Property {
    pub name: String,
    pub kind: Kind,
}

/// What a property holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// An element: its name, how many rows the header announces, its properties in row order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Element {
    pub name: String,
    pub count: u64,
    pub properties: Vec<Property>,
}

/// A parsed header and where its body starts.
#[derive(Debug)]
pub(super) struct Header {
    pub format: Format,
    pub elements: Vec<Element>,
    /// The byte offset of the body.
    pub body: usize,
    /// The line the body starts on (for an ASCII body).
    pub body_line: usize,
    /// The texture files the `comment TextureFile NAME` lines name (MeshLab, VCGlib), in
    /// order, as written.
    pub texture_files: Vec<String>,
}

/// The file a `comment TextureFile NAME` line names (the rest of the line, which may hold
/// spaces), if `text` is one.
fn texture_file(text: &str) -> Option<String> {
    let rest = text.trim_start().strip_prefix("comment")?.trim_start();
    let name = rest.strip_prefix("TextureFile")?;
    // `TextureFile` followed by white space, then a name.
    let name = name.strip_prefix(|c: char| c.is_ascii_whitespace())?.trim();
    (!name.is_empty()).then(|| name.to_string())
}

/// Reads the header at the start of `bytes`.
pub(super) fn parse(bytes: &[u8]) -> Result<Header, PlyError> {
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut texture_files = Vec::new();
    let mut start = 0;
    let mut line = 0;
    loop {
        line += 1;
        let at = At::Line(line);
        let Some(len) = bytes[start..].iter().position(|&b| b == b'\n') else {
            let message = match line {
                1 => "not a PLY file (it does not start with a `ply` line)",
                _ => "the header has no `end_header` line",
            };
            return Err(PlyError::new(at, message));
        };
        let text = String::from_utf8_lossy(&bytes[start..start + len]);
        start += len + 1;
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        if line == 1 {
            if words != ["ply"] {
                return Err(PlyError::new(
                    at,
                    "not a PLY file (it does not start with a `ply` line)",
                ));
            }
            continue;
        }
        let bad = |message: String| Err(PlyError::new(at, message));
        match words.as_slice() {
            ["comment", ..] => texture_files.extend(texture_file(&text)),
            [] | ["obj_info", ..] => {}
            ["format", name, version] => {
                if format.is_some() {
                    return bad("a second `format` line".into());
                }
                format = Some(match *name {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::LittleEndian,
                    "binary_big_endian" => Format::BigEndian,
                    _ => {
                        return bad(format!(
                            "unknown format {} (known: ascii, binary_little_endian, \
                             binary_big_endian)",
                            quoted(name)
                        ))
                    }
                });
                if *version != "1.0" {
                    return bad(format!(
                        "format version {} is not supported (only 1.0)",
                        quoted(version)
                    ));
                }
            }
            ["element", name, count] => {
                let Ok(count) = count.parse::<u64>() else {
                    return bad(format!(
                        "element {}: its count {} is not a whole number",
                        quoted(name),
                        quoted(count)
                    ));
                };
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return bad("a `property` line before any `element` line".into());
                };
                let property = parse_property(rest).map_err(|m| {
                    PlyError::new(at, format!("element {}: {m}", quoted(&element.name)))
                })?;
                element.properties.push(property);
            }
            ["end_header"] => {
                let Some(format) = format else {
                    return bad("the header has no `format` line".into());
                };
                return Ok(Header {
                    format,
                    elements,
                    body: start,
                    body_line: line + 1,
                    texture_files,
                });
            }
            [word, ..] => {
                return bad(format!(
                    "unknown or malformed header line starting with {}",
                    quoted(word)
                ))
            }
        }
    }
}

/// The property a `property` line's words after `property` declare.
fn parse_property(words: &[&str]) -> Result<Property, String> {
    let scalar = |word: &str| {
        Scalar::parse(word).ok_or_else(|| format!("unknown property type {}", quoted(word)))
    };
    let (kind, name) = match words {
        ["list", count, item, name] => {
            let count = scalar(count)?;
            if count.is_float() {
                return Err(format!(
                    "list property {}: its count type must be an integer type",
                    quoted(name)
                ));
            }
            (
                Kind::List {
                    count,
                    item: scalar(item)?,
                },
                name,
            )
        }
        [ty, name] if *ty != "list" => (Kind::Scalar(scalar(ty)?), name),
        _ => return Err("a malformed `property` line".into()),
    };
    Ok(Property {
        name: name.to_string(),
        kind,
    })
}
