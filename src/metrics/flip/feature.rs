//! FLIP's feature pipeline, per pixel: the achromatic channel normalised to [0, 1] goes through the
//! edge (first derivative) and point (second derivative) detectors of [`super::filters`]; the feature
//! difference is √(max(|Δedge|, |Δpoint|) / √2) ∈ [0, 1] (q_f = ½), and it lowers the exponent of the
//! colour error: ΔE = ΔE_c^(1 − ΔE_f) (Andersson et al. 2020, §3.2–3.3).
//!
//! Depends on nothing else in the crate.

use super::filters::Lanes;

/// Exponent of the feature difference (q_f).
const QF: f32 = 0.5;

/// The lanes the horizontal feature pass reads: YCxCz's Y mapped to [0, 1] in every lane.
pub(crate) fn lanes(ycxcz: [f32; 3]) -> Lanes {
    let one_over_116 = 1.0f32 / 116.0;
    let sixteen_over_116 = 16.0f32 / 116.0;
    let y = ycxcz[0] * one_over_116 + sixteen_over_116;
    [y; 4]
}

/// Feature difference in [0, 1] from the vertical pass's lanes (∂x, ∂²x, ∂y, ∂²y) of both images.
pub(crate) fn difference(reference: Lanes, test: Lanes) -> f32 {
    let edge = |l: Lanes| (l[0] * l[0] + l[2] * l[2]).sqrt();
    let point = |l: Lanes| (l[1] * l[1] + l[3] * l[3]).sqrt();
    let edge_difference = (edge(reference) - edge(test)).abs();
    let point_difference = (point(reference) - point(test)).abs();
    let largest = if edge_difference > point_difference { edge_difference } else { point_difference };
    let normalisation = 1.0 / 2.0f32.sqrt();
    (normalisation * largest).powf(QF)
}

/// The final FLIP value of a pixel: the colour error raised to 1 − feature difference.
pub(crate) fn combine(colour_error: f32, feature_difference: f32) -> f32 {
    colour_error.powf(1.0 - feature_difference)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalised_luminance() {
        assert_eq!(lanes([-16.0, 5.0, 5.0]), [0.0; 4]);
        assert!((lanes([100.0, 0.0, 0.0])[0] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn difference_by_hand() {
        // Edge strengths 5 and 0 (3-4-5 triangle), point strengths 0 and 1: max(5, 1) = 5,
        // sqrt(5/√2) = 1.88030.
        let d = difference([3.0, 0.0, 4.0, 0.0], [0.0, 1.0, 0.0, 0.0]);
        assert!((d - 1.880_302).abs() < 1e-5, "{d}");
        assert_eq!(difference([0.1, 0.2, 0.3, 0.4], [0.1, 0.2, 0.3, 0.4]), 0.0);
    }

    #[test]
    fn combining() {
        assert_eq!(combine(0.25, 0.0), 0.25);
        assert_eq!(combine(0.25, 0.5), 0.5);
        assert_eq!(combine(0.0, 0.0), 0.0);
        assert_eq!(combine(0.3, 1.0), 1.0);
    }
}
