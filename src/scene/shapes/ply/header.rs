//! STAGE 2 (scene loading, PLY reader): the PLY header — format, elements, properties and their types.

/// The body encoding named on the `format` line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// A PLY scalar type.
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
    /// The type for a header type name, in either the old (`uchar`) or the sized (`uint8`) spelling.
    pub(super) fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
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

    /// Size in bytes in a binary body.
    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(super) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// What one property holds: a single value, or a length-prefixed list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { len: Scalar, item: Scalar },
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) props: Vec<Property>,
}

impl Element {
    /// The position of the non-list property called `name`.
    pub(super) fn scalar(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
    }

    /// "vertices", "faces" or "\"name\" elements", for messages.
    pub(super) fn plural(&self) -> String {
        match self.name.as_str() {
            "vertex" => "vertices".into(),
            "face" => "faces".into(),
            other => format!("\"{other}\" elements"),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct Header {
    pub(super) format: Format,
    pub(super) elements: Vec<Element>,
    /// Byte offset of the first byte after the `end_header` line.
    pub(super) body_start: usize,
    /// 1-based line number of the first body line (for ascii messages).
    pub(super) body_line: usize,
}

/// Parses the header, line by line, up to and including `end_header`.
pub(super) fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err("not a PLY file (the first line is not \"ply\")".into());
    }
    let (mut format, mut elements) = (None, Vec::<Element>::new());
    let (mut pos, mut line) = (0, 0);
    loop {
        let rest = bytes.get(pos..).unwrap_or_default();
        let Some(len) = rest.iter().position(|&b| b == b'\n') else {
            return Err("the header has no end_header line".into());
        };
        let text = String::from_utf8_lossy(rest.get(..len).unwrap_or_default());
        pos += len + 1;
        line += 1;
        let at = |msg: String| format!("header line {line}: {msg}");
        match text.split_whitespace().collect::<Vec<_>>().as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["ply"] if line == 1 => {}
            ["format", name, version] => format = Some(parse_format(name, version).map_err(at)?),
            ["element", name, count] => {
                let count = count
                    .parse()
                    .map_err(|_| at(format!("element count \"{count}\" is not a non-negative integer")))?;
                if matches!(*name, "vertex" | "face") && elements.iter().any(|e| e.name == *name) {
                    return Err(at(format!("a second \"{name}\" element")));
                }
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            ["property", words @ ..] => {
                let prop = parse_property(words).map_err(at)?;
                let element = elements.last_mut().ok_or_else(|| at("a property before any element".into()))?;
                element.props.push(prop);
            }
            ["end_header"] => break,
            [word, ..] => return Err(at(format!("unknown header keyword \"{word}\""))),
        }
    }
    let format = format.ok_or("the header has no format line")?;
    Ok(Header { format, elements, body_start: pos, body_line: line + 1 })
}

pub(super) fn parse_format(name: &str, version: &str) -> Result<Format, String> {
    let format = match name {
        "ascii" => Format::Ascii,
        "binary_little_endian" => Format::BinaryLe,
        "binary_big_endian" => Format::BinaryBe,
        _ => {
            return Err(format!(
                "unsupported format \"{name}\" (expected ascii, binary_little_endian or binary_big_endian)"
            ));
        }
    };
    if version != "1.0" {
        return Err(format!("unsupported PLY version \"{version}\" (only 1.0 is known)"));
    }
    Ok(format)
}

/// Parses the words after `property`: `TYPE NAME` or `list LENTYPE ITEMTYPE NAME`.
pub(super) fn parse_property(words: &[&str]) -> Result<Property, String> {
    let ty = |name: &str| Scalar::from_name(name).ok_or_else(|| format!("unknown property type \"{name}\""));
    let (kind, name) = match words {
        ["list", len, item, name] => {
            let len_ty = ty(len)?;
            if len_ty.is_float() {
                return Err(format!("list length type \"{len}\" is not an integer type"));
            }
            (Kind::List { len: len_ty, item: ty(item)? }, name)
        }
        [scalar, name] => (Kind::Scalar(ty(scalar)?), name),
        _ => {
            return Err("expected \"property TYPE NAME\" or \"property list LENTYPE ITEMTYPE NAME\"".into());
        }
    };
    Ok(Property { name: name.to_string(), kind })
}
