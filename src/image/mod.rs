//! Images: linear f32 RGB in memory; EXR, PFM and PNG in and out.
//!
//! [`Image`] is what the renderer fills and what the metrics compare. [`read`] and [`write()`] pick the
//! file format from the extension (`.exr`, `.pfm`, `.png`, any case). The readers accept what other
//! tools commonly write (EXR with R, G, B and optionally A, or Y channels in half, float or uint,
//! scanline or tiled; PFM colour `PF` and grey `Pf` in either byte order; 8- and 16-bit PNG); the
//! writers produce one fixed form each (float RGB scanline EXR, little-endian `PF` PFM, 8-bit sRGB PNG).
//! Writes go to a temporary file in the target directory that is renamed at the end, so a failed write
//! never leaves a partial file.
//!
//! EXR files also carry a [`Metadata`]: where the image sits in a larger film (a [`Window`], as pbrt-v3
//! writes a crop) and text attributes; [`write_with`] writes them and [`read_metadata`] reads them back.
//!
//! Every problem with a file is an [`Error::file`] naming it; no input file makes the readers panic.
//!
//! This module depends only on [`crate::error`]; it knows nothing of scenes, rendering or metrics.

mod atomic;
mod exr;
mod exr_header;
mod pfm;
mod png;

use std::path::Path;

use crate::error::{Error, Result};

pub use atomic::check_output;
pub use png::{linear_to_srgb, png_bytes, rgb8_png_bytes, srgb_to_linear, write_rgb8_png};

/// Linear f32 RGB, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// `width * height` pixels, row by row from the top, each linear RGB.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// A black image of the given size.
    pub fn new(width: usize, height: usize) -> Image {
        Image { width, height, pixels: vec![[0.0; 3]; width * height] }
    }

    /// An image made from its pixels (row-major, top row first); `None` when the count is not
    /// `width * height`.
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<[f32; 3]>) -> Option<Image> {
        (width.checked_mul(height) == Some(pixels.len())).then_some(Image { width, height, pixels })
    }

    /// The pixel in column `x`, row `y` (row 0 is the top). Panics when outside the image.
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside a {}×{} image", self.width, self.height);
        self.pixels[y * self.width + x]
    }

    /// Sets the pixel in column `x`, row `y`. Panics when outside the image.
    pub fn set(&mut self, x: usize, y: usize, c: [f32; 3]) {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside a {}×{} image", self.width, self.height);
        self.pixels[y * self.width + x] = c;
    }

    /// Adds `other` pixel by pixel. Panics when the sizes differ.
    pub fn add(&mut self, other: &Image) {
        assert!(self.width == other.width && self.height == other.height, "adding images of different sizes");
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            (0..3).for_each(|k| a[k] += b[k]);
        }
    }

    /// The mean of each channel over all pixels, accumulated in f64 row by row and then over rows in
    /// order, so the result does not depend on anything but the pixels. An empty image gives zeros.
    pub fn mean(&self) -> [f64; 3] {
        if self.pixels.is_empty() {
            return [0.0; 3];
        }
        let mut total = [0.0f64; 3];
        for row in self.pixels.chunks(self.width) {
            let mut sum = [0.0f64; 3];
            for p in row {
                for c in 0..3 {
                    sum[c] += f64::from(p[c]);
                }
            }
            for c in 0..3 {
                total[c] += sum[c];
            }
        }
        let n = self.pixels.len() as f64;
        total.map(|t| t / n)
    }

    /// The `width`×`height` block whose top-left pixel is column `x`, row `y`; `None` when it does not lie
    /// inside the image.
    pub fn crop(&self, x: usize, y: usize, width: usize, height: usize) -> Option<Image> {
        if x.checked_add(width)? > self.width || y.checked_add(height)? > self.height {
            return None;
        }
        let pixels = (y..y + height).flat_map(|row| &self.pixels[row * self.width + x..][..width]).copied().collect();
        Some(Image { width, height, pixels })
    }

    /// The first pixel (in row-major order) with a NaN or infinite channel: `(x, y, channel, value)`.
    pub fn first_non_finite(&self) -> Option<(usize, usize, usize, f32)> {
        self.pixels.iter().enumerate().find_map(|(i, p)| {
            let c = p.iter().position(|v| !v.is_finite())?;
            Some((i % self.width, i / self.width, c, p[c]))
        })
    }
}

/// The file formats [`read`] and [`write()`] know, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// OpenEXR (`.exr`).
    Exr,
    /// Portable float map (`.pfm`), pbrt-v3's other output format.
    Pfm,
    /// PNG (`.png`): 8-bit sRGB-encoded, for previews.
    Png,
}

impl Format {
    /// The format for `path`'s extension (any case), or a usage error naming the allowed extensions.
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(Format::Exr),
            Some("pfm") => Ok(Format::Pfm),
            Some("png") => Ok(Format::Png),
            _ => Err(Error::usage(format!(
                "\"{}\": unknown image file extension; use .exr, .pfm or .png",
                path.display()
            ))),
        }
    }
}

/// Reads an image by extension: `.exr`, `.pfm` (values kept linear) or `.png` (decoded sRGB → linear).
pub fn read(path: &Path) -> Result<Image> {
    let format = Format::from_path(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    let decoded = match format {
        Format::Exr => exr::decode(&bytes),
        Format::Pfm => pfm::decode(&bytes),
        Format::Png => png::decode(&bytes),
    };
    decoded.map_err(|msg| Error::file(path, msg))
}

/// Writes `bytes` (a JSON or CSV report, say) to `path` all-or-nothing: a failed write leaves no file.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    atomic::write_atomically(path, |out| {
        std::io::Write::write_all(out, bytes).map_err(|e| format!("cannot write: {e}"))
    })
}

/// Writes an image by extension: `.exr` (float RGB, scanline, ZIP), `.pfm` (float32 `PF`, little-endian,
/// rows bottom to top like pbrt-v3) or `.png` (8-bit sRGB, clamped to [0, 1]). The file appears only
/// when complete; an unknown extension is a usage error naming the allowed ones. The same as
/// [`write_with`] with [`Metadata::default`], byte for byte.
pub fn write(image: &Image, path: &Path) -> Result<()> {
    write_with(image, path, &Metadata::default())
}

/// Where an image sits in a larger film: pbrt-v3 writes a cropped render as an EXR whose display window is the full film and whose data window is the crop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Window {
    /// full film size [width, height] in pixels
    pub full: [usize; 2],
    /// top-left pixel of the image within the film
    pub origin: [usize; 2],
}

/// What an image file records beside its pixels (EXR keeps all of it; PFM and PNG drop it).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Metadata {
    /// Where the image sits in a larger film; `None` for an image that is the whole film. Reading gives
    /// `None` when the data window is the display window.
    pub window: Option<Window>,
    /// text attributes, name → value, in order
    pub attributes: Vec<(String, String)>,
}

/// Writes `image` to `path` (format from the extension, atomically, as `write` does) with `meta`.
///
/// EXR: the display window is (0,0)..(full-1) and the data window origin..origin+size-1, as pbrt-v3's
/// `WriteImageEXR` does for a crop window; the text attributes become `string` attributes in their order
/// (OpenEXR's standard text attributes such as `owner` or `software` go in their own places; names must be
/// distinct, Latin-1, and not reserved for another kind of attribute). A window that does not hold the
/// image is a usage error, for every format.
pub fn write_with(image: &Image, path: &Path, meta: &Metadata) -> Result<()> {
    let format = Format::from_path(path)?;
    if image.width == 0 || image.height == 0 || image.pixels.len() != image.width * image.height {
        return Err(Error::file(
            path,
            format!("cannot write a {}×{} image with {} pixels", image.width, image.height, image.pixels.len()),
        ));
    }
    if let Some(w) = meta.window {
        let fits = |axis: usize, size: usize| w.origin[axis].checked_add(size).is_some_and(|end| end <= w.full[axis]);
        if !fits(0, image.width) || !fits(1, image.height) {
            return Err(Error::usage(format!(
                "\"{}\": a {}×{} image at ({}, {}) does not fit in a {}×{} film",
                path.display(),
                image.width,
                image.height,
                w.origin[0],
                w.origin[1],
                w.full[0],
                w.full[1]
            )));
        }
    }
    atomic::write_atomically(path, |out| match format {
        Format::Exr => exr::encode(image, meta, out),
        Format::Pfm => pfm::encode(image, out),
        Format::Png => png::encode(image, out),
    })
}

/// Reads the metadata of an image file (EXR: display/data window and every text attribute; PFM/PNG: the default).
pub fn read_metadata(path: &Path) -> Result<Metadata> {
    let format = Format::from_path(path)?;
    if format != Format::Exr {
        // Nothing to read, but a missing or unreadable file is still an error.
        std::fs::File::open(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
        return Ok(Metadata::default());
    }
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    exr::metadata(&bytes).map_err(|msg| Error::file(path, msg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_get_set_mean() {
        let mut im = Image::new(3, 2);
        assert_eq!(im.get(2, 1), [0.0; 3]);
        im.set(2, 1, [6.0, 12.0, -6.0]);
        assert_eq!(im.get(2, 1), [6.0, 12.0, -6.0]);
        assert_eq!(im.pixels[5], [6.0, 12.0, -6.0]);
        assert_eq!(im.mean(), [1.0, 2.0, -1.0]);
        assert_eq!(Image::new(0, 0).mean(), [0.0; 3]);
    }

    #[test]
    fn from_pixels_checks_the_count() {
        assert!(Image::from_pixels(2, 2, vec![[0.0; 3]; 4]).is_some());
        assert!(Image::from_pixels(2, 2, vec![[0.0; 3]; 3]).is_none());
    }

    #[test]
    fn first_non_finite_names_the_pixel() {
        let mut im = Image::new(4, 3);
        assert_eq!(im.first_non_finite(), None);
        im.set(3, 2, [0.0, f32::INFINITY, 0.0]);
        im.set(1, 1, [0.0, 0.0, f32::NAN]);
        let (x, y, c, v) = im.first_non_finite().unwrap();
        assert_eq!((x, y, c), (1, 1, 2));
        assert!(v.is_nan());
    }

    #[test]
    fn formats_come_from_extensions() {
        assert_eq!(Format::from_path(Path::new("a/b.EXR")).unwrap(), Format::Exr);
        assert_eq!(Format::from_path(Path::new("b.pfm")).unwrap(), Format::Pfm);
        assert_eq!(Format::from_path(Path::new("b.png")).unwrap(), Format::Png);
        let e = Format::from_path(Path::new("b.jpg")).unwrap_err();
        assert!(matches!(e, Error::Usage(_)));
        assert!(e.to_string().contains(".exr, .pfm or .png"), "{e}");
        assert!(Format::from_path(Path::new("noext")).is_err());
    }
}
