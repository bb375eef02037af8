//! PNG previews: 8-bit sRGB out (linear values clamped to [0, 1] and encoded with the sRGB curve), and
//! 8- or 16-bit PNG in (decoded from sRGB to linear). Also writes ready-made 8-bit colours, which is how
//! false-colour error maps are saved without a round trip through linear values.
//!
//! Depends only on the [`Image`] type and the `image` crate's PNG codec; it knows nothing of scenes or
//! rendering.

use std::io::Write;
use std::path::Path;

use image::ImageEncoder as _;

use super::Image;
use crate::error::{Error, Result};

/// The sRGB transfer curve, encoded value → linear (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// The inverse sRGB transfer curve, linear → encoded value (IEC 61966-2-1).
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.0031308 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// Linear → 8-bit sRGB code value, clamping to [0, 1] first (NaN becomes 0).
fn to_u8(v: f32) -> u8 {
    let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (linear_to_srgb(c) * 255.0 + 0.5) as u8
}

/// Decodes a PNG file's bytes into linear RGB (alpha is ignored).
pub(crate) fn decode(bytes: &[u8]) -> std::result::Result<Image, String> {
    let decoded = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
        .map_err(|e| format!("cannot decode PNG: {e}"))?;
    let rgb = decoded.to_rgb32f();
    let (width, height) = (rgb.width() as usize, rgb.height() as usize);
    let pixels =
        rgb.pixels().map(|p| [srgb_to_linear(p.0[0]), srgb_to_linear(p.0[1]), srgb_to_linear(p.0[2])]).collect();
    Image::from_pixels(width, height, pixels).ok_or_else(|| "PNG decoder returned a wrong pixel count".into())
}

/// Encodes `image` as an 8-bit sRGB PNG.
pub(crate) fn encode(image: &Image, out: &mut impl Write) -> std::result::Result<(), String> {
    let bytes: Vec<u8> = image.pixels.iter().flat_map(|p| p.map(to_u8)).collect();
    encode_rgb8(image.width, image.height, &bytes, out)
}

/// Encodes ready-made 8-bit RGB bytes (row-major, top row first) as a PNG.
fn encode_rgb8(width: usize, height: usize, rgb: &[u8], out: &mut impl Write) -> std::result::Result<(), String> {
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(format!("{width}×{height} is too large for PNG")),
    };
    image::codecs::png::PngEncoder::new(out)
        .write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| format!("cannot encode PNG: {e}"))
}

/// `image` as the bytes of an 8-bit sRGB PNG file (for pages that embed their pictures).
pub fn png_bytes(image: &Image) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    encode(image, &mut out).map_err(Error::usage)?;
    Ok(out)
}

/// Ready-made 8-bit RGB colours (row-major, top row first) as the bytes of a PNG file.
pub fn rgb8_png_bytes(width: usize, height: usize, rgb: &[[u8; 3]]) -> Result<Vec<u8>> {
    if width.checked_mul(height) != Some(rgb.len()) {
        return Err(Error::usage(format!("cannot encode {} colours as a {width}×{height} image", rgb.len())));
    }
    let bytes: Vec<u8> = rgb.iter().flatten().copied().collect();
    let mut out = Vec::new();
    encode_rgb8(width, height, &bytes, &mut out).map_err(Error::usage)?;
    Ok(out)
}

/// Writes 8-bit RGB colours as they are (no transfer curve): `rgb` holds `width * height` pixels, row by
/// row from the top. Atomic like [`super::write`]; the path must end in `.png`.
pub fn write_rgb8_png(width: usize, height: usize, rgb: &[[u8; 3]], path: &Path) -> Result<()> {
    if super::Format::from_path(path)? != super::Format::Png {
        return Err(Error::usage(format!("\"{}\": a colour map is written as .png", path.display())));
    }
    if width == 0 || height == 0 || width.checked_mul(height) != Some(rgb.len()) {
        return Err(Error::file(path, format!("cannot write {} colours as a {width}×{height} image", rgb.len())));
    }
    let bytes: Vec<u8> = rgb.iter().flatten().copied().collect();
    super::atomic::write_atomically(path, |out| encode_rgb8(width, height, &bytes, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transfer_curve_hand_values() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // ((0.5 + 0.055) / 1.055)^2.4 = 0.2140411...
        assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
        // Linear segment: 0.04 / 12.92.
        assert!((srgb_to_linear(0.04) - 0.003_095_975).abs() < 1e-8);
        for i in 0..=100 {
            let v = i as f32 / 100.0;
            assert!((linear_to_srgb(srgb_to_linear(v)) - v).abs() < 1e-5, "{v}");
        }
    }

    #[test]
    fn u8_encoding_clamps() {
        assert_eq!(to_u8(-1.0), 0);
        assert_eq!(to_u8(f32::NAN), 0);
        assert_eq!(to_u8(0.0), 0);
        assert_eq!(to_u8(1.0), 255);
        assert_eq!(to_u8(100.0), 255);
        assert_eq!(to_u8(0.214_041_14), 128);
    }

    #[test]
    fn round_trip_within_quantisation() {
        let mut im = Image::new(4, 2);
        im.set(1, 0, [0.5, 0.2, 0.01]);
        im.set(3, 1, [1.0, 2.0, -1.0]);
        let mut bytes = Vec::new();
        encode(&im, &mut bytes).unwrap();
        let back = decode(&bytes).unwrap();
        assert_eq!((back.width, back.height), (4, 2));
        let p = back.get(1, 0);
        for (a, b) in p.iter().zip([0.5, 0.2, 0.01]) {
            assert!((a - b).abs() < 0.01 * b + 0.001, "{a} vs {b}");
        }
        assert_eq!(back.get(3, 1), [1.0, 1.0, 0.0]);
    }

    #[test]
    fn junk_is_an_error() {
        assert!(decode(b"\x89PNG\r\n\x1a\nnot really").is_err());
        assert!(decode(b"").is_err());
    }
}
