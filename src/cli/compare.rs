//! `cachert compare TEST REFERENCE`: reads two images, computes the requested metrics with
//! [`crate::metrics::evaluate`], optionally writes the FLIP map and the difference image, and returns the
//! report as text (one `name value` line per metric) or JSON. The binary prints it; any error (a missing
//! or unreadable file, different sizes, a non-finite reference value, a bad flag) is returned and becomes
//! exit status 2 there.
//!
//! Depends on [`crate::image`] and [`crate::metrics`] only; it knows nothing of scenes or rendering.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value, json};

use crate::error::{Error, Result};
use crate::image::{self, Format, Image};
use crate::metrics::{self, Metric, colormap, flip};

/// Flags of `cachert compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// The image to judge (.exr, .pfm or .png; PNG is decoded from sRGB to linear).
    pub test: PathBuf,
    /// The reference image (.exr, .pfm or .png); every value must be finite.
    pub reference: PathBuf,
    /// Metrics, comma separated: rmse, relmse, flip (mean HDR-FLIP), ldrflip (mean LDR-FLIP of the images
    /// clamped to [0, 1]), meandiff (mean(test) / mean(reference) − 1).
    #[arg(long, value_delimiter = ',', default_value = "rmse,flip")]
    pub metric: Vec<Metric>,
    /// Write the FLIP error map here: .png in the magma colour map, .exr or .pfm with the raw values. It is
    /// the HDR-FLIP map unless only ldrflip was requested.
    #[arg(long, value_name = "FILE")]
    pub flip_map: Option<PathBuf>,
    /// Write |test − reference| per channel here (.exr, .pfm or .png).
    #[arg(long, value_name = "FILE")]
    pub diff_map: Option<PathBuf>,
    /// Print one JSON object (metrics, sizes, HDR-FLIP exposures) instead of one line per metric.
    #[arg(long)]
    pub json: bool,
    /// Compare only the block of W×H pixels whose top-left pixel is column X, row Y (from the top left).
    /// An image that is already W×H pixels is taken as that block: pbrt writes only a crop window's pixels.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_window)]
    pub window: Option<Window>,
}

/// A block of pixels: `x`, `y` of its top-left pixel (row 0 at the top), `width`, `height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// Column of the block's left edge.
    pub x: usize,
    /// Row of the block's top edge.
    pub y: usize,
    /// Columns in the block (at least 1).
    pub width: usize,
    /// Rows in the block (at least 1).
    pub height: usize,
}

/// Reads `X,Y,W,H` (four non-negative integers, W and H at least 1).
fn parse_window(text: &str) -> std::result::Result<Window, String> {
    let values: Vec<usize> = text
        .split(',')
        .map(|v| v.trim().parse::<usize>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("expected X,Y,W,H (four non-negative integers), got {text:?}"))?;
    match values[..] {
        [x, y, width, height] if width > 0 && height > 0 => Ok(Window { x, y, width, height }),
        _ => Err(format!("expected X,Y,W,H (four non-negative integers, W and H at least 1), got {text:?}")),
    }
}

/// The window of `image`, or the image itself when it is already the window's size.
fn windowed(image: Image, window: Option<Window>, path: &Path) -> Result<Image> {
    let Some(w) = window else { return Ok(image) };
    if (image.width, image.height) == (w.width, w.height) {
        return Ok(image);
    }
    image.crop(w.x, w.y, w.width, w.height).ok_or_else(|| {
        Error::file(
            path,
            format!(
                "is {}×{} pixels: the window {},{},{},{} does not lie inside it",
                image.width, image.height, w.x, w.y, w.width, w.height
            ),
        )
    })
}

/// Runs the comparison and returns the text to print.
pub fn run(args: &CompareArgs) -> Result<String> {
    // Check output names before the expensive part, so a typo fails fast.
    for path in args.flip_map.iter().chain(&args.diff_map) {
        Format::from_path(path)?;
    }
    let mut wanted: Vec<Metric> = Vec::new();
    for &m in &args.metric {
        if !wanted.contains(&m) {
            wanted.push(m);
        }
    }
    if wanted.is_empty() {
        return Err(Error::usage("--metric needs at least one of rmse, relmse, flip, ldrflip, meandiff"));
    }
    let test = windowed(image::read(&args.test)?, args.window, &args.test)?;
    let reference = windowed(image::read(&args.reference)?, args.window, &args.reference)?;
    check_pair(&test, &reference, &args.test, &args.reference)?;

    let eval = metrics::evaluate(&test, &reference, &wanted)?;
    let mut hdr_info = eval.hdr_flip.as_ref().map(|h| h.exposures);
    if let Some(path) = &args.flip_map {
        match (&eval.hdr_flip, &eval.ldr_flip) {
            (Some(hdr), _) => write_flip_map(&hdr.map, path)?,
            (None, Some(ldr)) => write_flip_map(ldr, path)?,
            (None, None) => {
                let hdr = flip::hdr_flip_map(&test, &reference, flip::DEFAULT_PPD)?;
                hdr_info = Some(hdr.exposures);
                write_flip_map(&hdr.map, path)?;
            }
        }
    }
    if let Some(path) = &args.diff_map {
        image::write(&abs_difference(&test, &reference), path)?;
    }
    Ok(if args.json {
        json_report(args, &reference, &eval.values, hdr_info)
    } else {
        eval.values.iter().map(|(m, v)| format!("{m} {}", format_value(*v))).collect::<Vec<_>>().join("\n")
    })
}

/// Same size, and a finite reference; errors name the file at fault and the pixel.
fn check_pair(test: &Image, reference: &Image, test_path: &Path, reference_path: &Path) -> Result<()> {
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(Error::file(
            test_path,
            format!(
                "is {}×{} pixels but the reference {} is {}×{}",
                test.width,
                test.height,
                reference_path.display(),
                reference.width,
                reference.height
            ),
        ));
    }
    if let Some((x, y, c, v)) = reference.first_non_finite() {
        return Err(Error::file(
            reference_path,
            format!(
                "reference has a non-finite value {v} at pixel ({x}, {y}) (x, y from the top left), channel {}",
                ["R", "G", "B"][c]
            ),
        ));
    }
    Ok(())
}

/// Writes a FLIP map as a magma PNG, or as grey EXR/PFM values.
fn write_flip_map(map: &flip::FlipMap, path: &Path) -> Result<()> {
    match Format::from_path(path)? {
        Format::Png => colormap::write_magma_png(map.width, map.height, &map.values, path),
        Format::Exr | Format::Pfm => image::write(&map.to_image(), path),
    }
}

/// |test − reference| per pixel and channel.
fn abs_difference(test: &Image, reference: &Image) -> Image {
    let pixels =
        test.pixels.iter().zip(&reference.pixels).map(|(t, r)| [0, 1, 2].map(|c| (t[c] - r[c]).abs())).collect();
    Image { width: reference.width, height: reference.height, pixels }
}

/// A value with at least six significant digits: fixed-point with six decimals in [0.001, 10⁶), and
/// scientific notation outside (so small RMSEs keep their digits).
fn format_value(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&a) { format!("{v:.6}") } else { format!("{v:.6e}") }
}

/// The JSON report: files, size, metric values (full precision) and the HDR-FLIP exposures.
fn json_report(
    args: &CompareArgs,
    reference: &Image,
    values: &[(Metric, f64)],
    hdr: Option<flip::ExposureRange>,
) -> String {
    let metrics: Map<String, Value> = values.iter().map(|(m, v)| (m.name().to_string(), json!(v))).collect();
    let mut report = json!({
        "test": args.test.display().to_string(),
        "reference": args.reference.display().to_string(),
        "width": reference.width,
        "height": reference.height,
        "metrics": metrics,
    });
    if let Some(exposures) = hdr {
        report["hdr_flip"] = json!(flip::HdrFlipInfo { ppd: flip::DEFAULT_PPD, exposures });
    }
    serde_json::to_string_pretty(&report).expect("a JSON value always serialises")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_formatting() {
        assert_eq!(format_value(0.0), "0.000000");
        assert_eq!(format_value(0.0123456), "0.012346");
        assert_eq!(format_value(1.5), "1.500000");
        assert_eq!(format_value(0.00001234567), "1.234567e-5");
        assert_eq!(format_value(f64::NAN), "NaN");
    }

    #[test]
    fn a_window_is_four_integers_with_a_size() {
        assert_eq!(parse_window("96,14,64,14"), Ok(Window { x: 96, y: 14, width: 64, height: 14 }));
        assert!(parse_window("96,14,64").is_err());
        assert!(parse_window("96,14,0,14").is_err());
        assert!(parse_window("-1,14,64,14").is_err());
    }

    #[test]
    fn a_window_crops_or_takes_an_image_of_its_size() {
        let image = Image::from_pixels(3, 2, (0..6).map(|i| [i as f32; 3]).collect()).unwrap();
        let window = Some(Window { x: 1, y: 1, width: 2, height: 1 });
        let cropped = windowed(image.clone(), window, Path::new("a.pfm")).unwrap();
        assert_eq!(cropped.pixels, vec![[4.0; 3], [5.0; 3]]);
        let already = Image::from_pixels(2, 1, vec![[7.0; 3], [8.0; 3]]).unwrap();
        assert_eq!(windowed(already.clone(), window, Path::new("b.pfm")).unwrap(), already);
        let outside = Some(Window { x: 2, y: 0, width: 2, height: 1 });
        let err = windowed(image, outside, Path::new("c.pfm")).unwrap_err().to_string();
        assert!(err.contains("c.pfm") && err.contains("does not lie inside"), "{err}");
    }

    #[test]
    fn abs_difference_per_channel() {
        let a = Image::from_pixels(1, 1, vec![[1.0, 2.0, 3.0]]).unwrap();
        let b = Image::from_pixels(1, 1, vec![[2.0, 2.0, 1.0]]).unwrap();
        assert_eq!(abs_difference(&a, &b).pixels, vec![[1.0, 0.0, 2.0]]);
    }
}
