//! ꟻLIP, NVIDIA's perceptual image difference, in pure Rust: LDR-FLIP (Andersson et al., HPG 2020) and
//! HDR-FLIP (Andersson et al., Eurographics 2021), ported from the published reference implementation
//! (`src/cpp/FLIP.h` of github.com/NVlabs/flip, BSD-3-Clause; the `flip-evaluator` 1.7 Python package
//! wraps the same code) with every constant and operation order kept, in f32 like the reference.
//!
//! | piece | file |
//! |---|---|
//! | colour transforms, Hunt, HyAB, error mapping | `colour.rs` |
//! | spatial (CSF) and feature filters, separable passes | `filters.rs` |
//! | edge/point feature difference | `feature.rs` |
//! | the two passes of LDR-FLIP | `ldr.rs` |
//! | exposure range, tone mapping | `hdr.rs` |
//!
//! Inputs are linear RGB. LDR-FLIP clamps both images to [0, 1] and treats them as linear (what the
//! reference does with `inputsRGB=False`; the default of its Python API would sRGB-decode them first).
//! HDR-FLIP takes the exposure range from the reference ([`exposure_range`]), and per exposure tone maps
//! with ACES and clamps; the older Python description also sRGB-encodes the tone-mapped image, but LDR-FLIP
//! then decodes it again, so neither the reference nor this port does either.
//!
//! The map is the mean-able per-pixel error in [0, 1]; report its [`FlipMap::mean`]. The default viewing
//! condition is [`DEFAULT_PPD`]. Depends on nothing in the crate but [`crate::image`] and
//! [`crate::error`]; it knows nothing of scenes or rendering.

mod colour;
mod feature;
mod filters;
mod hdr;
mod ldr;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::image::Image;

pub use hdr::{ExposureRange, exposure_range};

/// Pixels per degree of visual angle for an observer `distance` metres from a monitor `monitor_width`
/// metres wide showing `resolution_x` pixels across, as the reference computes it (in f32; its π
/// literal rounds to `f32::consts::PI`).
pub const fn pixels_per_degree(distance: f32, resolution_x: f32, monitor_width: f32) -> f32 {
    distance * (resolution_x / monitor_width) * (std::f32::consts::PI / 180.0)
}

/// FLIP's default viewing condition: 0.7 m from a 0.7 m wide 4K (3840 pixels) monitor, ≈ 67.02 pixels per
/// degree.
pub const DEFAULT_PPD: f32 = pixels_per_degree(0.7, 3840.0, 0.7);

/// Largest pixels-per-degree value accepted (filters grow linearly with it).
const MAX_PPD: f32 = 10_000.0;

/// A per-pixel FLIP error map, values in [0, 1], row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// `width * height` error values.
    pub values: Vec<f32>,
}

impl FlipMap {
    /// The mean error: f64 sums per row, then over rows in order (independent of threading).
    pub fn mean(&self) -> f64 {
        if self.values.is_empty() {
            return 0.0;
        }
        let total: f64 = self.values.chunks(self.width).map(|r| r.iter().map(|&v| f64::from(v)).sum::<f64>()).sum();
        total / self.values.len() as f64
    }

    /// The map as a grey linear image (each channel the error), for writing as EXR or PFM.
    pub fn to_image(&self) -> Image {
        Image { width: self.width, height: self.height, pixels: self.values.iter().map(|&v| [v; 3]).collect() }
    }
}

/// HDR-FLIP's result: the map (per-pixel maximum over exposures) and the exposures used.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrFlip {
    /// Per-pixel HDR-FLIP.
    pub map: FlipMap,
    /// The exposures evaluated.
    pub exposures: ExposureRange,
}

/// Summary of an HDR-FLIP evaluation, for reports.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HdrFlipInfo {
    /// Pixels per degree used.
    pub ppd: f32,
    /// The exposures evaluated.
    pub exposures: ExposureRange,
}

/// LDR-FLIP of `test` against `reference` at `ppd` pixels per degree; both are clamped to [0, 1] and taken
/// as linear. Errors: different or zero sizes, a ppd that is not in (0, 10000].
pub fn ldr_flip_map(test: &Image, reference: &Image, ppd: f32) -> Result<FlipMap> {
    check(test, reference, ppd)?;
    let clamp = |p: [f32; 3]| p.map(colour::clamp01);
    let values = ldr::Pipeline::new(ppd).run(reference.width, &reference.pixels, &test.pixels, &clamp);
    Ok(FlipMap { width: reference.width, height: reference.height, values })
}

/// HDR-FLIP of `test` against `reference` at `ppd` pixels per degree, with the automatic exposure range
/// of the reference. Errors as for [`ldr_flip_map`], and a non-finite value in the reference.
pub fn hdr_flip_map(test: &Image, reference: &Image, ppd: f32) -> Result<HdrFlip> {
    check(test, reference, ppd)?;
    if let Some((x, y, c, v)) = reference.first_non_finite() {
        return Err(Error::usage(format!(
            "the reference has a non-finite value {v} at pixel ({x}, {y}), channel {}",
            ["R", "G", "B"][c]
        )));
    }
    hdr_flip_map_with(test, reference, ppd, exposure_range(reference))
}

/// HDR-FLIP with a given exposure range (for example the same one for several references). Errors as
/// for [`ldr_flip_map`], and a range that is not finite, has start > stop or a count of 0.
pub fn hdr_flip_map_with(test: &Image, reference: &Image, ppd: f32, exposures: ExposureRange) -> Result<HdrFlip> {
    check(test, reference, ppd)?;
    let ExposureRange { start, stop, count } = exposures;
    if !(start.is_finite() && stop.is_finite() && start <= stop && count >= 1) {
        return Err(Error::usage(format!("bad exposure range: {count} exposures from {start} to {stop}")));
    }
    let pipeline = ldr::Pipeline::new(ppd);
    let mut values = vec![0.0f32; reference.pixels.len()];
    for i in 0..count {
        let prepare = hdr::exposer(exposures.exposure(i));
        let ldr = pipeline.run(reference.width, &reference.pixels, &test.pixels, &prepare);
        for (v, e) in values.iter_mut().zip(ldr) {
            if e > *v {
                *v = e;
            }
        }
    }
    Ok(HdrFlip { map: FlipMap { width: reference.width, height: reference.height, values }, exposures })
}

/// Same sizes, not empty, sensible ppd.
fn check(test: &Image, reference: &Image, ppd: f32) -> Result<()> {
    super::check_sizes(test, reference)?;
    if !(ppd > 0.0 && ppd <= MAX_PPD) {
        return Err(Error::usage(format!("pixels per degree must be in (0, {MAX_PPD}], not {ppd}")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_ppd_matches_the_reference() {
        // flip-evaluator reports ppd 67.02064514160156.
        assert_eq!(DEFAULT_PPD, 67.020_645);
    }

    #[test]
    fn identical_images_give_zero() {
        let mut im = Image::new(20, 12);
        for y in 0..12 {
            for x in 0..20 {
                im.set(x, y, [x as f32 / 10.0, y as f32 / 3.0, 0.3]);
            }
        }
        let ldr = ldr_flip_map(&im, &im, DEFAULT_PPD).unwrap();
        assert!(ldr.values.iter().all(|&v| v == 0.0));
        let hdr = hdr_flip_map(&im, &im, DEFAULT_PPD).unwrap();
        assert!(hdr.map.values.iter().all(|&v| v == 0.0));
        assert_eq!(hdr.map.mean(), 0.0);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let a = Image::new(4, 4);
        let b = Image::new(4, 5);
        assert!(ldr_flip_map(&a, &b, DEFAULT_PPD).unwrap_err().to_string().contains("4×4 but the reference is 4×5"));
        assert!(ldr_flip_map(&a, &a, 0.0).is_err());
        assert!(ldr_flip_map(&a, &a, f32::NAN).is_err());
        assert!(ldr_flip_map(&Image::new(0, 0), &Image::new(0, 0), DEFAULT_PPD).is_err());
        let mut r = Image::new(4, 4);
        r.set(2, 3, [0.0, f32::NAN, 0.0]);
        let e = hdr_flip_map(&a, &r, DEFAULT_PPD).unwrap_err().to_string();
        assert!(e.contains("(2, 3)") && e.contains("channel G"), "{e}");
        let bad = ExposureRange { start: 1.0, stop: 0.0, count: 2 };
        assert!(hdr_flip_map_with(&a, &a, DEFAULT_PPD, bad).is_err());
    }

    #[test]
    fn mean_and_grey_image() {
        let m = FlipMap { width: 2, height: 2, values: vec![0.0, 0.5, 1.0, 0.5] };
        assert_eq!(m.mean(), 0.5);
        assert_eq!(m.to_image().get(0, 1), [1.0; 3]);
    }
}
