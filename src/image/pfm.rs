//! Portable float maps (PFM), the format pbrt-v3 writes besides EXR.
//!
//! Layout: a text header `PF` (RGB) or `Pf` (grey), whitespace, `width height`, whitespace, a scale
//! whose sign gives the byte order (negative: little-endian) and whose magnitude multiplies the values
//! (as pbrt-v3's reader does when it is not 1), exactly one whitespace byte, then 32-bit floats, rows from
//! the *bottom* of the image to the top. We write `PF`, scale `-1`, little-endian, bottom row first.
//!
//! Depends only on the [`Image`] type; it knows nothing of scenes or rendering.

use std::io::Write;

use super::Image;

/// Decodes a PFM file's bytes; the message says what is wrong (bad header, truncated data, …).
pub(crate) fn decode(bytes: &[u8]) -> Result<Image, String> {
    let mut header = Header { bytes, pos: 0 };
    let magic = header.token().ok_or("not a PFM file: empty")?;
    let channels = match magic {
        b"PF" => 3,
        b"Pf" => 1,
        _ => {
            let shown = String::from_utf8_lossy(&magic[..magic.len().min(8)]).into_owned();
            return Err(format!("not a PFM file: starts with {shown:?}, expected \"PF\" or \"Pf\""));
        }
    };
    let width = header.number::<usize>("width")?;
    let height = header.number::<usize>("height")?;
    let scale = header.number::<f32>("scale")?;
    if width == 0 || height == 0 {
        return Err(format!("bad PFM header: size {width}×{height} has no pixels"));
    }
    if scale == 0.0 || !scale.is_finite() {
        return Err(format!("bad PFM header: scale {scale} must be a non-zero finite number"));
    }
    // Exactly one whitespace byte separates the header from the data.
    match bytes.get(header.pos) {
        Some(b) if b.is_ascii_whitespace() => header.pos += 1,
        _ => return Err("bad PFM header: no whitespace after the scale".into()),
    }
    let data = &bytes[header.pos..];
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels * 4))
        .ok_or_else(|| format!("bad PFM header: size {width}×{height} is too large"))?;
    if data.len() < expected {
        return Err(format!(
            "truncated PFM: {width}×{height}×{channels} floats need {expected} bytes of pixel data, found {}",
            data.len()
        ));
    }
    let little_endian = scale < 0.0;
    let factor = scale.abs();
    let value = |i: usize| {
        let b: [u8; 4] = [data[4 * i], data[4 * i + 1], data[4 * i + 2], data[4 * i + 3]];
        let v = if little_endian { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) };
        if factor == 1.0 { v } else { v * factor }
    };
    let mut image = Image::new(width, height);
    for (file_row, chunk) in image.pixels.chunks_mut(width).rev().enumerate() {
        for (x, p) in chunk.iter_mut().enumerate() {
            let i = (file_row * width + x) * channels;
            *p = if channels == 3 { [value(i), value(i + 1), value(i + 2)] } else { [value(i); 3] };
        }
    }
    Ok(image)
}

/// Writes `image` as a little-endian RGB PFM (scale -1), bottom row first.
pub(crate) fn encode(image: &Image, out: &mut impl Write) -> Result<(), String> {
    let io = |e: std::io::Error| format!("cannot write: {e}");
    write!(out, "PF\n{} {}\n-1\n", image.width, image.height).map_err(io)?;
    let mut row_bytes = Vec::with_capacity(image.width * 12);
    for row in image.pixels.chunks(image.width).rev() {
        row_bytes.clear();
        for p in row {
            for v in p {
                row_bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        out.write_all(&row_bytes).map_err(io)?;
    }
    Ok(())
}

/// A cursor over the whitespace-separated tokens of the header.
struct Header<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Header<'a> {
    /// The next token (at most 64 bytes are looked at, so binary junk ends quickly).
    fn token(&mut self) -> Option<&'a [u8]> {
        while self.bytes.get(self.pos)?.is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() && self.pos - start < 64 {
            self.pos += 1;
        }
        Some(&self.bytes[start..self.pos])
    }

    /// The next token parsed as a `T`, or a message naming the header field.
    fn number<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, String> {
        let token = self.token().ok_or_else(|| format!("bad PFM header: missing {what}"))?;
        let text = std::str::from_utf8(token).unwrap_or("");
        text.parse().map_err(|_| format!("bad PFM header: {what} {:?} is not a number", String::from_utf8_lossy(token)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Image {
        let mut im = Image::new(3, 2);
        im.set(0, 0, [1.0, 2.0, 3.0]); // top left
        im.set(2, 1, [-4.5, 1e-30, 65504.0]); // bottom right
        im
    }

    #[test]
    fn round_trip_and_row_order() {
        let mut bytes = Vec::new();
        encode(&sample(), &mut bytes).unwrap();
        assert!(bytes.starts_with(b"PF\n3 2\n-1\n"));
        // The first pixel in the file is the bottom-left one, which is black.
        let data = &bytes[b"PF\n3 2\n-1\n".len()..];
        assert_eq!(&data[..12], &[0u8; 12]);
        // The first pixel of the second file row is the top-left one.
        assert_eq!(f32::from_le_bytes(data[36..40].try_into().unwrap()), 1.0);
        assert_eq!(decode(&bytes).unwrap(), sample());
    }

    fn handmade(magic: &str, scale: &str, values: &[f32], big_endian: bool, w: usize, h: usize) -> Vec<u8> {
        let mut b = format!("{magic}\n{w} {h}\n{scale}\n").into_bytes();
        for v in values {
            b.extend_from_slice(&if big_endian { v.to_be_bytes() } else { v.to_le_bytes() });
        }
        b
    }

    #[test]
    fn big_endian_grey_and_scale() {
        // 1×2 grey, big-endian (positive scale 2): file rows bottom first.
        let im = decode(&handmade("Pf", "2.0", &[1.0, 3.0], true, 1, 2)).unwrap();
        assert_eq!(im.pixels, vec![[6.0; 3], [2.0; 3]]);
        let im = decode(&handmade("Pf", "-1.0", &[1.0, 3.0], false, 1, 2)).unwrap();
        assert_eq!(im.pixels, vec![[3.0; 3], [1.0; 3]]);
    }

    #[test]
    fn header_with_spaces_instead_of_newlines() {
        let mut b = b"PF 1 1 -1.0 ".to_vec();
        for v in [0.25f32, 0.5, 0.75] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        assert_eq!(decode(&b).unwrap().pixels, vec![[0.25, 0.5, 0.75]]);
    }

    #[test]
    fn bad_files_give_messages() {
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"".to_vec(), "empty"),
            (b"P6\n1 1\n255\n".to_vec(), "expected \"PF\""),
            (b"PF\nx 1\n-1\n".to_vec(), "width"),
            (b"PF\n1\n".to_vec(), "missing"),
            (b"PF\n0 5\n-1\n".to_vec(), "no pixels"),
            (b"PF\n1 1\n0\n".to_vec(), "scale"),
            (b"PF\n1 1\nnan\n".to_vec(), "scale"),
            (b"PF\n1 1\n-1".to_vec(), "whitespace"),
            (handmade("PF", "-1", &[1.0, 2.0], false, 1, 1), "truncated"),
            (b"PF\n99999999999 99999999999\n-1\n".to_vec(), "too large"),
            (b"PF\n18446744073709551617 1\n-1\n".to_vec(), "width"),
        ];
        for (bytes, needle) in cases {
            let msg = decode(&bytes).unwrap_err();
            assert!(msg.contains(needle), "{msg:?} should mention {needle:?}");
        }
    }

    #[test]
    fn junk_never_panics() {
        // A cheap deterministic fuzz: prefixes and byte flips of a valid file.
        let mut good = Vec::new();
        encode(&sample(), &mut good).unwrap();
        for n in 0..good.len() {
            let _ = decode(&good[..n]);
        }
        for i in 0..16 {
            for bit in 0..8 {
                let mut b = good.clone();
                b[i] ^= 1 << bit;
                let _ = decode(&b);
            }
        }
    }
}
