//! STAGE 5 (shading): reading an `imagemap` texture's file into a [`MipMap`], as pbrt-v3's
//! `ImageTexture::GetTexture` does.
//!
//! - Formats by extension (any case): PNG and TGA (8-bit, values ÷ 255), EXR and PFM (linear floats).
//! - `gamma` (default: true for .png and .tga) applies pbrt-v3's `InverseGammaCorrect` (the sRGB curve)
//!   to each channel; a float texture takes the luminance of the stored values first, then the curve.
//!   Both are then multiplied by `scale`.
//! - Rows are flipped so that t = 0 is the image's bottom row.
//! - A file that cannot be decoded (truncated, not an image, an unknown format, 0 pixels) becomes what
//!   pbrt-v3 makes of it: a single grey texel 0.5, through the same gamma and scale.
//!
//! Depends on `crate::image` (EXR and PFM readers) and the `image` crate (PNG, TGA); never panics on a
//! file's contents.

use std::path::Path;

use super::mipmap::{MipMap, Wrap};

/// What makes two image textures share one [`MipMap`] (pbrt-v3's `TexInfo`, less the lookup settings,
/// which are kept per texture).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ImageKey {
    /// The resolved file name.
    pub path: String,
    /// Wrap mode (it changes the power-of-two resampling).
    pub wrap: Wrap,
    /// `scale`, as bits.
    pub scale_bits: u32,
    /// Whether values are sRGB-decoded.
    pub gamma: bool,
    /// Float texture (luminance) rather than colour.
    pub float: bool,
}

impl ImageKey {
    /// The key for an image texture's parameters.
    pub fn new(path: &str, wrap: Wrap, scale: f32, gamma: bool, float: bool) -> ImageKey {
        ImageKey { path: path.to_string(), wrap, scale_bits: scale.to_bits(), gamma, float }
    }
}

/// pbrt-v3's default for `gamma`: true for 8-bit formats (.png, .tga, any case).
pub fn default_gamma(path: &str) -> bool {
    let lower = path.to_ascii_lowercase();
    lower.ends_with(".png") || lower.ends_with(".tga")
}

/// pbrt-v3's `InverseGammaCorrect`: sRGB-encoded value → linear.
#[inline]
pub fn inverse_gamma(v: f32) -> f32 {
    if v <= 0.04045 { v * (1.0 / 12.92) } else { ((v + 0.055) * (1.0 / 1.055)).powf(2.4) }
}

/// pbrt-v3's `RGBSpectrum::y` of a texel.
#[inline]
fn luminance(c: [f32; 3]) -> f32 {
    crate::shading::luminance(crate::shading::Spectrum::from(c))
}

/// Loads the image `key` names. On failure the result is pbrt-v3's grey fallback and the message says
/// why the file could not be used.
pub fn load(key: &ImageKey) -> (MipMap, Option<String>) {
    let scale = f32::from_bits(key.scale_bits);
    let (width, height, mut texels, err) = match read_texels(Path::new(&key.path)) {
        Ok((w, h, t)) => (w, h, t, None),
        Err(e) => (1, 1, vec![[0.5; 3]], Some(e)),
    };
    // Texture space has t = 0 at the bottom: flip the rows.
    for y in 0..height / 2 {
        for x in 0..width {
            texels.swap(y * width + x, (height - 1 - y) * width + x);
        }
    }
    let convert = |v: f32| scale * if key.gamma { inverse_gamma(v) } else { v };
    for t in &mut texels {
        *t = if key.float { [convert(luminance(*t)); 3] } else { t.map(convert) };
    }
    match MipMap::new(width, height, texels, key.wrap) {
        Some(m) => (m, err),
        None => {
            let grey = [convert(if key.float { luminance([0.5; 3]) } else { 0.5 }); 3];
            let m = MipMap::new(1, 1, vec![grey], key.wrap).expect("a 1×1 image is valid");
            (m, Some(err.unwrap_or_else(|| format!("the image has {width}×{height} pixels"))))
        }
    }
}

/// The file's pixels, top row first, as stored (8-bit values ÷ 255, floats as they are).
fn read_texels(path: &Path) -> Result<(usize, usize, Vec<[f32; 3]>), String> {
    let lower = path.to_string_lossy().to_ascii_lowercase();
    let eight_bit = if lower.ends_with(".png") {
        Some(image::ImageFormat::Png)
    } else if lower.ends_with(".tga") {
        Some(image::ImageFormat::Tga)
    } else {
        None
    };
    let (w, h, texels) = match eight_bit {
        Some(format) => {
            let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
            let img = image::load_from_memory_with_format(&bytes, format).map_err(|e| e.to_string())?.to_rgb8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            (w, h, img.pixels().map(|p| p.0.map(|c| f32::from(c) / 255.0)).collect())
        }
        None if lower.ends_with(".exr") || lower.ends_with(".pfm") => {
            let img = crate::image::read(path).map_err(|e| e.to_string())?;
            (img.width, img.height, img.pixels)
        }
        None => {
            let ext = path.extension().map_or("(none)".into(), |e| e.to_string_lossy().into_owned());
            return Err(format!("unknown image format \".{ext}\"; expected .png, .tga, .exr or .pfm"));
        }
    };
    if w == 0 || h == 0 {
        return Err(format!("the image has {w}×{h} pixels"));
    }
    Ok((w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_gamma_is_pbrt_v3s_srgb_curve() {
        assert_eq!(inverse_gamma(0.0), 0.0);
        assert!((inverse_gamma(0.04045) - 0.04045 / 12.92).abs() < 1e-9);
        assert!((inverse_gamma(0.5) - 0.214_041_14).abs() < 1e-6);
        assert!((inverse_gamma(1.0) - 1.0).abs() < 1e-6);
        // 8-bit 188 (0.7373) → 0.5029, the value sRGB tables give.
        assert!((inverse_gamma(188.0 / 255.0) - 0.502_886).abs() < 1e-5);
    }

    #[test]
    fn default_gamma_follows_the_extension() {
        assert!(default_gamma("a/b.png") && default_gamma("B.TGA"));
        assert!(!default_gamma("x.exr") && !default_gamma("x.pfm") && !default_gamma("png"));
    }

    #[test]
    fn unreadable_files_become_pbrt_v3s_grey() {
        let key = ImageKey::new("/nonexistent/cachert-test.png", Wrap::Repeat, 2.0, true, false);
        let (m, err) = load(&key);
        assert!(err.is_some());
        assert_eq!(m.size(), [1, 1]);
        let v = m.texel(0, 0);
        assert!((v[0] - 2.0 * 0.214_041_14).abs() < 1e-6, "{v:?}");
        let key = ImageKey::new("/nonexistent/x.jpg", Wrap::Repeat, 1.0, false, true);
        let (m, err) = load(&key);
        assert!(err.unwrap().contains("unknown image format"));
        assert!((m.texel(0, 0)[0] - 0.5).abs() < 1e-6);
    }
}
