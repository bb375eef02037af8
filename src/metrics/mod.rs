//! Error metrics between a test image and a reference image — the numbers every experiment reports.
//!
//! | metric | name | what |
//! |---|---|---|
//! | [`rmse`] | `rmse` | root mean squared error on linear values (ALGORITHMS.md §8) |
//! | [`relmse`] | `relmse` | relative MSE, (t − r)² / (r² + 10⁻²) |
//! | [`flip::hdr_flip_map`] | `flip` | mean HDR-FLIP (the paper's perceptual metric) |
//! | [`flip::ldr_flip_map`] | `ldrflip` | mean LDR-FLIP of the images clamped to [0, 1] |
//!
//! [`pattern`] makes a synthetic HDR image for the metrics' tests and benchmarks.
//!
//! [`compare`] is the entry point experiments and golden tests call; [`evaluate`] also returns the FLIP
//! maps. Both check that the sizes match and that the reference is finite. A NaN or infinity in the
//! *test* image is not an error: it makes RMSE and relMSE NaN or infinite, and FLIP treats it exactly as
//! the reference implementation does (NaN and −∞ count as black; +∞ counts as white in LDR-FLIP and as
//! black in HDR-FLIP, where the tone curve turns it into NaN). Every computation is parallel over rows
//! and reduces per row, then over rows in order, so results are bit-identical for any
//! thread count.
//!
//! Depends on nothing in the crate but [`crate::image`] and [`crate::error`]; it knows nothing of scenes
//! or rendering.

pub mod colormap;
pub mod flip;
pub mod pattern;
mod rmse;

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::image::Image;

pub use rmse::{RELMSE_EPSILON, relmse, rmse};

/// A metric by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Metric {
    /// Root mean squared error (`rmse`).
    Rmse,
    /// Relative mean squared error (`relmse`).
    RelMse,
    /// Mean HDR-FLIP at the default viewing condition (`flip`).
    Flip,
    /// Mean LDR-FLIP of the clamped images at the default viewing condition (`ldrflip`).
    LdrFlip,
    /// The relative difference of the means, mean(test) / mean(reference) − 1, over all channels
    /// (`meandiff`): the bias a renderer shows in the image's energy, which RMSE mixes with noise.
    MeanDiff,
}

impl Metric {
    /// Every metric, in the order they are listed in messages.
    pub const ALL: [Metric; 5] = [Metric::Rmse, Metric::RelMse, Metric::Flip, Metric::LdrFlip, Metric::MeanDiff];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Rmse => "rmse",
            Metric::RelMse => "relmse",
            Metric::Flip => "flip",
            Metric::LdrFlip => "ldrflip",
            Metric::MeanDiff => "meandiff",
        }
    }

    /// Parses a comma-separated list such as `rmse,flip` (spaces allowed); duplicates are kept once.
    pub fn parse_list(list: &str) -> Result<Vec<Metric>> {
        let mut out = Vec::new();
        for name in list.split(',') {
            let m: Metric = name.parse()?;
            if !out.contains(&m) {
                out.push(m);
            }
        }
        Ok(out)
    }
}

impl FromStr for Metric {
    type Err = Error;

    /// A metric from its name (any case), or a usage error listing the valid names.
    fn from_str(s: &str) -> Result<Metric> {
        let wanted = s.trim().to_ascii_lowercase();
        Metric::ALL.into_iter().find(|m| m.name() == wanted).ok_or_else(|| {
            let names: Vec<&str> = Metric::ALL.iter().map(|m| m.name()).collect();
            Error::usage(format!("unknown metric \"{}\"; valid metrics: {}", s.trim(), names.join(", ")))
        })
    }
}

impl fmt::Display for Metric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Metric values together with the FLIP maps computed on the way.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// Each requested metric's value, in the requested order.
    pub values: Vec<(Metric, f64)>,
    /// The HDR-FLIP map and exposures, when `flip` was requested.
    pub hdr_flip: Option<flip::HdrFlip>,
    /// The LDR-FLIP map, when `ldrflip` was requested.
    pub ldr_flip: Option<flip::FlipMap>,
}

/// The requested metrics of `test` against `reference`.
///
/// Errors: different sizes, empty images, or a NaN or infinite value in the reference (the message
/// gives the first such pixel as x, y and channel).
pub fn compare(test: &Image, reference: &Image, metrics: &[Metric]) -> Result<Vec<(Metric, f64)>> {
    Ok(evaluate(test, reference, metrics)?.values)
}

/// Like [`compare`], and keeps the FLIP maps for pictures.
pub fn evaluate(test: &Image, reference: &Image, metrics: &[Metric]) -> Result<Evaluation> {
    check_inputs(test, reference)?;
    let mut eval = Evaluation { values: Vec::new(), hdr_flip: None, ldr_flip: None };
    for &m in metrics {
        let value = match m {
            Metric::Rmse => rmse(test, reference)?,
            Metric::RelMse => relmse(test, reference)?,
            Metric::Flip => {
                let hdr = flip::hdr_flip_map(test, reference, flip::DEFAULT_PPD)?;
                let mean = hdr.map.mean();
                eval.hdr_flip = Some(hdr);
                mean
            }
            Metric::LdrFlip => {
                let map = flip::ldr_flip_map(test, reference, flip::DEFAULT_PPD)?;
                let mean = map.mean();
                eval.ldr_flip = Some(map);
                mean
            }
            Metric::MeanDiff => {
                let mean = |im: &Image| im.mean().iter().sum::<f64>() / 3.0;
                mean(test) / mean(reference) - 1.0
            }
        };
        eval.values.push((m, value));
    }
    Ok(eval)
}

/// Sizes match, images are not empty, and the reference is finite everywhere.
pub fn check_inputs(test: &Image, reference: &Image) -> Result<()> {
    check_sizes(test, reference)?;
    match reference.first_non_finite() {
        Some((x, y, c, v)) => Err(Error::usage(format!(
            "the reference has a non-finite value {v} at pixel ({x}, {y}) (x, y from the top left), channel {}",
            ["R", "G", "B"][c]
        ))),
        None => Ok(()),
    }
}

/// Equal sizes and at least one pixel, or a usage error giving both sizes.
pub(crate) fn check_sizes(test: &Image, reference: &Image) -> Result<()> {
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(Error::usage(format!(
            "the test image is {}×{} but the reference is {}×{}",
            test.width, test.height, reference.width, reference.height
        )));
    }
    let n = reference.width * reference.height;
    if n == 0 || test.pixels.len() != n || reference.pixels.len() != n {
        return Err(Error::usage("images must be non-empty and hold width × height pixels"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meandiff_is_the_relative_difference_of_the_means() {
        let test = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [3.0, 2.0, 1.0]]).unwrap();
        let reference = Image::from_pixels(2, 1, vec![[2.0; 3], [2.5; 3]]).unwrap();
        let v = compare(&test, &reference, &[Metric::MeanDiff]).unwrap()[0].1;
        assert!((v - (2.0 / 2.25 - 1.0)).abs() < 1e-12, "{v}");
    }

    #[test]
    fn names_round_trip() {
        for m in Metric::ALL {
            assert_eq!(m.name().parse::<Metric>().unwrap(), m);
            assert_eq!(m.to_string(), m.name());
        }
        assert_eq!(" FLIP ".parse::<Metric>().unwrap(), Metric::Flip);
        let e = "psnr".parse::<Metric>().unwrap_err().to_string();
        assert!(e.contains("\"psnr\"") && e.contains("rmse, relmse, flip, ldrflip, meandiff"), "{e}");
        assert_eq!(Metric::parse_list("rmse, flip,rmse").unwrap(), vec![Metric::Rmse, Metric::Flip]);
        assert!(Metric::parse_list("rmse,").is_err());
    }

    #[test]
    fn compare_checks_inputs() {
        let a = Image::new(3, 3);
        let e = compare(&a, &Image::new(3, 4), &[Metric::Rmse]).unwrap_err().to_string();
        assert!(e.contains("3×3 but the reference is 3×4"), "{e}");
        let mut r = Image::new(3, 3);
        r.set(1, 2, [0.0, 0.0, f32::INFINITY]);
        let e = compare(&a, &r, &[Metric::Rmse]).unwrap_err().to_string();
        assert!(e.contains("pixel (1, 2)") && e.contains("channel B") && e.contains("inf"), "{e}");
        // A non-finite *test* value is not an error: it shows up in the numbers.
        assert!(compare(&r, &a, &[Metric::Rmse]).unwrap()[0].1.is_infinite());
    }

    #[test]
    fn values_come_in_the_requested_order() {
        let r = Image::from_pixels(2, 2, vec![[0.5; 3]; 4]).unwrap();
        let mut t = r.clone();
        t.set(0, 0, [0.6; 3]);
        let v = compare(&t, &r, &[Metric::LdrFlip, Metric::Rmse, Metric::Flip, Metric::RelMse]).unwrap();
        let names: Vec<Metric> = v.iter().map(|p| p.0).collect();
        assert_eq!(names, vec![Metric::LdrFlip, Metric::Rmse, Metric::Flip, Metric::RelMse]);
        assert!((v[1].1 - (0.01f64 * 3.0 / 12.0).sqrt()).abs() < 1e-6);
        assert!(v.iter().all(|p| p.1 > 0.0));
    }
}
