//! HDR-FLIP's exposure handling (Andersson et al., "Visualizing Errors in Rendered High Dynamic Range
//! Images", Eurographics 2021, §4): the exposure range comes from the reference's luminance and the ACES
//! filmic tone curve, each exposure is tone mapped and clamped to [0, 1], LDR-FLIP is computed per
//! exposure and the per-pixel maximum over exposures is the HDR-FLIP value.
//!
//! Exposure range, as in NVIDIA's reference: with t(x) = (k₀x² + k₁x)/(k₃x² + k₄x + k₅) (ACES with the
//! 0.6 pre-exposure cancelled) and x* the positive root of t(x) = 0.85, start = log₂(x*/max Y) and
//! stop = log₂(x*/median Y), where Y is the reference's luminance and the median is the element at
//! index ⌊n/2⌋ of the sorted values. The count is max(2, ⌈stop − start⌉), evenly spaced, both ends
//! included. Two cases the reference does not handle get a defined answer here: a median ≤ 0 (more
//! than half of the reference black) uses the median of the positive luminances, and a reference
//! without any positive luminance uses the single exposure 0 (twice).
//!
//! Depends on nothing else in the crate but the [`Image`] type.

use serde::Serialize;

use crate::image::Image;

/// ACES fit coefficients (k₀ … k₅ with k₂ = 0), including the 0.6 pre-exposure cancellation.
const ACES: [f32; 6] = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14];

/// The tone-mapped value whose input defines the bright end of the exposure range.
const TARGET: f32 = 0.85;

/// The exposures HDR-FLIP evaluates: `count` values evenly spaced from `start` to `stop` (in stops, i.e.
/// the image is scaled by 2^exposure before tone mapping).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ExposureRange {
    /// First exposure (makes the brightest reference pixel map to 0.85).
    pub start: f32,
    /// Last exposure (makes the median reference pixel map to 0.85).
    pub stop: f32,
    /// Number of exposures, at least 1 (the automatic range has at least 2).
    pub count: usize,
}

impl ExposureRange {
    /// The i-th exposure, as the reference computes it: start + i · (stop − start)/(count − 1).
    pub fn exposure(&self, i: usize) -> f32 {
        if self.count <= 1 {
            return self.start;
        }
        let step = (self.stop - self.start) / (self.count - 1) as f32;
        self.start + i as f32 * step
    }
}

/// The ACES tone curve applied to one channel (no clamping).
pub(crate) fn tone_map(v: f32) -> f32 {
    let k = ACES;
    ((v * v) * k[0] + v * k[1] + k[2]) / (v * v * k[3] + v * k[4] + k[5])
}

/// Linear luminance with the Rec. 709 / sRGB weights.
fn luminance(p: [f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// x* with t(x*) = 0.85: the larger root of (k₀ − 0.85k₃)x² + (k₁ − 0.85k₄)x + (k₂ − 0.85k₅) = 0.
fn bright_input() -> f32 {
    let k = ACES;
    let a = k[0] - TARGET * k[3];
    let b = k[1] - TARGET * k[4];
    let c = k[2] - TARGET * k[5];
    if a == 0.0 {
        return -c / b;
    }
    let d1 = -0.5 * (b / a);
    let d2 = ((d1 * d1) - (c / a)).sqrt();
    d1 + d2
}

/// The median as the reference takes it: the element at index ⌊n/2⌋ of the sorted values.
fn upper_median(values: &mut [f32]) -> f32 {
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The automatic exposure range of HDR-FLIP for `reference` (which should be finite; see the module
/// documentation for the two degenerate cases).
pub fn exposure_range(reference: &Image) -> ExposureRange {
    let mut lum: Vec<f32> = reference.pixels.iter().map(|&p| luminance(p)).collect();
    let max = lum.iter().fold(f32::NEG_INFINITY, |m, &v| if v > m { v } else { m });
    if lum.is_empty() || max <= 0.0 || max.is_nan() {
        return ExposureRange { start: 0.0, stop: 0.0, count: 2 };
    }
    let mut median = upper_median(&mut lum);
    if median <= 0.0 {
        lum.retain(|&v| v > 0.0);
        median = upper_median(&mut lum);
    }
    let x = bright_input();
    let start = (x / max).log2();
    let stop = (x / median).log2();
    let count = (stop - start).ceil().max(2.0) as usize;
    ExposureRange { start, stop, count }
}

/// The per-pixel preparation for exposure `e`: scale by 2^e, tone map, clamp to [0, 1] (NaN → 0).
pub(crate) fn exposer(e: f32) -> impl Fn([f32; 3]) -> [f32; 3] + Sync {
    let m = 2.0f32.powf(e);
    move |p: [f32; 3]| p.map(|v| super::colour::clamp01(tone_map(v * m)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_curve_and_its_target() {
        assert_eq!(tone_map(0.0), 0.0);
        // t(1) = (0.9036 + 0.018) / (0.8748 + 0.354 + 0.14) = 0.673290…
        assert!((tone_map(1.0) - 0.673_290).abs() < 1e-5);
        let x = bright_input();
        assert!((x - 2.118_872).abs() < 1e-4, "{x}");
        assert!((tone_map(x) - TARGET).abs() < 1e-5);
    }

    #[test]
    fn range_from_max_and_median() {
        // Luminance of grey v is v. Values 0.25, 0.5, 1, 4: max 4, median (index 2) 1.
        let mut im = Image::new(4, 1);
        for (i, v) in [0.25f32, 4.0, 1.0, 0.5].into_iter().enumerate() {
            im.set(i, 0, [v; 3]);
        }
        let r = exposure_range(&im);
        let x = bright_input();
        assert!((r.start - (x / 4.0).log2()).abs() < 1e-6);
        assert!((r.stop - x.log2()).abs() < 1e-6);
        assert_eq!(r.count, 2); // ceil(2) = 2
        assert_eq!(r.exposure(0), r.start);
        assert!((r.exposure(1) - r.stop).abs() < 1e-6);
    }

    #[test]
    fn many_stops_give_many_exposures() {
        let mut im = Image::new(3, 1);
        im.set(0, 0, [1000.0; 3]);
        im.set(1, 0, [0.001; 3]);
        im.set(2, 0, [0.001; 3]);
        let r = exposure_range(&im);
        // log2(1000 / 0.001) = 19.93 stops → 20 exposures.
        assert_eq!(r.count, 20);
    }

    #[test]
    fn degenerate_references() {
        let black = Image::new(4, 4);
        assert_eq!(exposure_range(&black), ExposureRange { start: 0.0, stop: 0.0, count: 2 });
        // Mostly black: the median of the positive luminances (here 2, of {1, 2, 8}) is used.
        let mut im = Image::new(8, 1);
        im.set(0, 0, [1.0; 3]);
        im.set(1, 0, [8.0; 3]);
        im.set(2, 0, [2.0; 3]);
        let r = exposure_range(&im);
        assert!((r.stop - (bright_input() / 2.0).log2()).abs() < 1e-6);
        assert!(r.start.is_finite() && r.start < r.stop);
        // A flat image has start = stop and still two exposures.
        let flat = Image::from_pixels(2, 2, vec![[0.5; 3]; 4]).unwrap();
        let r = exposure_range(&flat);
        assert_eq!((r.start, r.count), (r.stop, 2));
    }

    #[test]
    fn exposer_clamps() {
        let f = exposer(0.0);
        assert_eq!(f([0.0, 1e9, f32::NAN]), [0.0, 1.0, 0.0]);
        let g = exposer(1.0);
        assert!((g([0.5; 3])[0] - tone_map(1.0)).abs() < 1e-7);
    }
}
