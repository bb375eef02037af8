//! Pixel-wise error on linear values: RMSE (ALGORITHMS.md §8, the paper's numeric metric) and relative
//! MSE as an extra. Both average over all pixels and all three channels, background included, with f64
//! sums per row combined in row order, so the result is the same whatever the thread count.
//!
//! Depends on nothing in the crate but [`crate::image`] and [`crate::error`]; it knows nothing of scenes
//! or rendering.

use rayon::prelude::*;

use crate::error::Result;
use crate::image::Image;

/// The ε in relMSE's denominator, (t − r)² / (r² + ε): keeps black reference pixels from dominating.
pub const RELMSE_EPSILON: f64 = 1e-2;

/// Root mean squared error: √(mean over pixels and channels of (test − reference)²).
pub fn rmse(test: &Image, reference: &Image) -> Result<f64> {
    Ok(mean_over_channels(test, reference, |t, r| (t - r) * (t - r))?.sqrt())
}

/// Relative mean squared error: mean over pixels and channels of (test − reference)² / (reference² + ε),
/// with ε = [`RELMSE_EPSILON`] = 10⁻².
pub fn relmse(test: &Image, reference: &Image) -> Result<f64> {
    mean_over_channels(test, reference, |t, r| (t - r) * (t - r) / (r * r + RELMSE_EPSILON))
}

/// Mean of `f(test, reference)` over all channel values, in f64, reduced per row then over rows in order.
fn mean_over_channels(test: &Image, reference: &Image, f: impl Fn(f64, f64) -> f64 + Sync) -> Result<f64> {
    super::check_sizes(test, reference)?;
    let width = reference.width;
    let rows: Vec<f64> = test
        .pixels
        .par_chunks(width)
        .zip(reference.pixels.par_chunks(width))
        .map(|(t, r)| {
            let mut sum = 0.0;
            for (pt, pr) in t.iter().zip(r) {
                for c in 0..3 {
                    sum += f(f64::from(pt[c]), f64::from(pr[c]));
                }
            }
            sum
        })
        .collect();
    let total: f64 = rows.iter().sum();
    Ok(total / (3 * reference.pixels.len()) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed() {
        let r = Image::new(2, 1);
        let mut t = Image::new(2, 1);
        t.set(0, 0, [1.0, 0.0, 0.0]);
        t.set(1, 0, [0.0, 2.0, 0.0]);
        // Squared errors 1 and 4 over 6 values: mean 5/6.
        assert!((rmse(&t, &r).unwrap() - (5.0f64 / 6.0).sqrt()).abs() < 1e-12);
        // relMSE with r = 0: (1 + 4) / 0.01 / 6.
        assert!((relmse(&t, &r).unwrap() - 500.0 / 6.0).abs() < 1e-9);
        assert_eq!(rmse(&r, &r).unwrap(), 0.0);
        assert_eq!(relmse(&t, &t).unwrap(), 0.0);
    }

    #[test]
    fn relmse_is_relative() {
        let r = Image::from_pixels(1, 1, vec![[10.0; 3]]).unwrap();
        let t = Image::from_pixels(1, 1, vec![[11.0; 3]]).unwrap();
        assert!((relmse(&t, &r).unwrap() - 1.0 / 100.01).abs() < 1e-12);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let e = rmse(&Image::new(3, 2), &Image::new(2, 3)).unwrap_err();
        assert!(e.to_string().contains("3×2 but the reference is 2×3"), "{e}");
        assert!(rmse(&Image::new(0, 0), &Image::new(0, 0)).is_err());
    }
}
