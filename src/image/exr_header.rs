//! The attribute records of an EXR file's first header, read straight from its bytes.
//!
//! The `exr` crate keeps custom attributes in a `HashMap`: reading loses their order, and writing puts
//! them in a different order in every process, so two writes of the same image and text would differ in
//! bytes. This module lists the text (`string`) attributes in file order, and rewrites a header so its text
//! attributes come in a chosen order, which makes a written file depend on nothing but its content.
//!
//! Part of the image stage; depends on nothing else in the crate.

use std::ops::Range;

/// The four bytes every EXR file starts with.
const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Longest attribute or type name looked at (long names are at most 255 bytes).
const MAX_NAME: usize = 256;

/// One attribute of a header: where it lies in the file, its name, its type name and its value.
struct Record {
    /// The whole record: name, type, size and value.
    bytes: Range<usize>,
    /// The attribute's name.
    name: Vec<u8>,
    /// The type's name (`string` for text).
    kind: Vec<u8>,
    /// The value's bytes.
    value: Range<usize>,
}

impl Record {
    fn is_text(&self) -> bool {
        self.kind == b"string"
    }
}

/// The records of the first header, and the position of the null byte that ends the header.
fn records(bytes: &[u8]) -> Result<(Vec<Record>, usize), String> {
    if bytes.len() < 8 || bytes[..4] != MAGIC {
        return Err("not an EXR file".into());
    }
    let truncated = || "EXR header is truncated".to_string();
    let mut pos = 8;
    let mut out = Vec::new();
    loop {
        let start = pos;
        let name = null_terminated(bytes, &mut pos)?;
        if name.is_empty() {
            return Ok((out, start));
        }
        let kind = null_terminated(bytes, &mut pos)?;
        let size: [u8; 4] = bytes.get(pos..pos + 4).and_then(|s| s.try_into().ok()).ok_or_else(truncated)?;
        let size = i32::from_le_bytes(size);
        let size = usize::try_from(size).map_err(|_| format!("EXR header: attribute size {size} is negative"))?;
        let end = (pos + 4).checked_add(size).filter(|&e| e <= bytes.len()).ok_or_else(truncated)?;
        let value = pos + 4..end;
        pos = end;
        out.push(Record { bytes: start..end, name: name.to_vec(), kind: kind.to_vec(), value });
    }
}

/// The bytes from `pos` up to the next null byte, moving `pos` past it.
fn null_terminated<'a>(bytes: &'a [u8], pos: &mut usize) -> Result<&'a [u8], String> {
    let rest = bytes.get(*pos..).unwrap_or(&[]);
    let n = rest.iter().take(MAX_NAME).position(|&b| b == 0).ok_or("EXR header: a name without its end")?;
    *pos += n + 1;
    Ok(&rest[..n])
}

/// EXR text as a string: each byte is the character of the same code (Latin-1), as the `exr` crate maps
/// characters to bytes when writing.
fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}

/// A string as EXR text bytes, `None` when a character is beyond Latin-1.
fn to_latin1(s: &str) -> Option<Vec<u8>> {
    s.chars().map(|c| u8::try_from(u32::from(c)).ok()).collect()
}

/// The text attributes of the first header, in file order, name → value; `type` (which says what a part
/// of a multi-part file holds, not a description of the image) is left out.
pub(crate) fn text_attributes(bytes: &[u8]) -> Result<Vec<(String, String)>, String> {
    let (records, _) = records(bytes)?;
    Ok(records
        .iter()
        .filter(|r| r.is_text() && r.name != b"type")
        .map(|r| (latin1(&r.name), latin1(&bytes[r.value.clone()])))
        .collect())
}

/// Moves the text attributes named in `order` to the end of the first header, in that order. The header
/// keeps its length, so the offset table after it stays valid. Every name must be a text attribute of the
/// header.
pub(crate) fn order_text_attributes(bytes: &mut [u8], order: &[String]) -> Result<(), String> {
    let (records, end) = records(bytes)?;
    let wanted: Vec<Vec<u8>> = order
        .iter()
        .map(|n| to_latin1(n).ok_or_else(|| format!("attribute name {n:?} is not Latin-1")))
        .collect::<Result<_, _>>()?;
    let chosen = |r: &Record| r.is_text() && wanted.contains(&r.name);
    let mut header = Vec::with_capacity(end - 8);
    for r in records.iter().filter(|r| !chosen(r)) {
        header.extend_from_slice(&bytes[r.bytes.clone()]);
    }
    for name in &wanted {
        let r = records
            .iter()
            .find(|r| r.is_text() && &r.name == name)
            .ok_or_else(|| format!("text attribute {:?} is missing from the written header", latin1(name)))?;
        header.extend_from_slice(&bytes[r.bytes.clone()]);
    }
    if header.len() != end - 8 {
        return Err("reordering the EXR header changed its length".into());
    }
    bytes[8..end].copy_from_slice(&header);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A header with the given (name, type, value) records and four bytes of "offset table" after it.
    fn header(records: &[(&str, &str, &[u8])]) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[2, 0, 0, 0]);
        for (name, kind, value) in records {
            b.extend_from_slice(name.as_bytes());
            b.push(0);
            b.extend_from_slice(kind.as_bytes());
            b.push(0);
            b.extend_from_slice(&(value.len() as i32).to_le_bytes());
            b.extend_from_slice(value);
        }
        b.push(0);
        b.extend_from_slice(&[9, 9, 9, 9]);
        b
    }

    #[test]
    fn lists_text_in_file_order() {
        let b = header(&[("z", "string", b"last"), ("n", "int", &[1, 0, 0, 0]), ("a", "string", b"caf\xe9")]);
        let t = text_attributes(&b).unwrap();
        assert_eq!(t, vec![("z".into(), "last".into()), ("a".into(), "café".into())]);
    }

    #[test]
    fn reorders_without_changing_the_length() {
        let mut b = header(&[("b", "string", b"2"), ("n", "int", &[1, 0, 0, 0]), ("a", "string", b"1")]);
        let len = b.len();
        order_text_attributes(&mut b, &["a".into(), "b".into()]).unwrap();
        assert_eq!(b.len(), len);
        assert!(b.ends_with(&[0, 9, 9, 9, 9]));
        let t = text_attributes(&b).unwrap();
        assert_eq!(t, vec![("a".into(), "1".into()), ("b".into(), "2".into())]);
        assert!(order_text_attributes(&mut b, &["missing".into()]).is_err());
    }

    #[test]
    fn junk_is_an_error() {
        assert!(text_attributes(b"").is_err());
        assert!(text_attributes(b"not an exr").is_err());
        let good = header(&[("a", "string", b"1")]);
        for n in 0..good.len() - 5 {
            assert!(text_attributes(&good[..n]).is_err(), "prefix {n}");
        }
        let mut negative = good.clone();
        negative[8 + 2 + 7..8 + 2 + 7 + 4].copy_from_slice(&(-5i32).to_le_bytes());
        assert!(text_attributes(&negative).unwrap_err().contains("negative"));
    }
}
