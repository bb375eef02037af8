//! FLIP's per-pixel colour transforms: linear sRGB ↔ CIE XYZ (D65), XYZ ↔ YCxCz (the opponent space
//! the contrast sensitivity filters work in), XYZ → CIELAB, the Hunt adjustment, the HyAB distance, the
//! largest possible distance and the mapping of a colour distance to [0, 1].
//!
//! Everything is f32 in the same operation order as NVIDIA's reference (`FLIP.h`, Andersson et al.,
//! "FLIP: A Difference Evaluator for Alternating Images", HPG 2020, §3.1), so the per-pixel values
//! agree with it to rounding. Depends on nothing else in the crate.

/// The D65 white point in XYZ (Y = 1), the reference illuminant of every transform here. Literals are
/// the reference's, digit for digit, so they round to the same f32.
#[allow(clippy::excessive_precision)]
const WHITE: [f32; 3] = [0.950428545, 1.0, 1.088900371];
/// Its reciprocal, as tabulated by the reference (not recomputed, to keep the same rounding).
#[allow(clippy::excessive_precision)]
const INV_WHITE: [f32; 3] = [1.052156925, 1.0, 0.918357670];

/// Exponent applied to the HyAB distance (q_c).
pub(crate) const QC: f32 = 0.7;
/// Fraction of the largest distance below which errors are spread over [0, p_t] (p_c).
const PC: f32 = 0.4;
/// Share of the output range given to distances below p_c · c_max (p_t).
const PT: f32 = 0.95;

/// Linear sRGB → CIE XYZ (D65), with the exact rational matrix the reference uses.
pub(crate) fn linear_rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [10135552.0f32 / 24577794.0, 8788810.0f32 / 24577794.0, 4435075.0f32 / 24577794.0],
        [2613072.0f32 / 12288897.0, 8788810.0f32 / 12288897.0, 887015.0f32 / 12288897.0],
        [1425312.0f32 / 73733382.0, 8788810.0f32 / 73733382.0, 70074185.0f32 / 73733382.0],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

/// CIE XYZ (D65) → linear sRGB, with the reference's literals digit for digit.
#[allow(clippy::excessive_precision)]
pub(crate) fn xyz_to_linear_rgb(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [3.241003275f32, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

/// CIE XYZ → YCxCz: like CIELAB but without the cube root, so it is linear and filtering in it is
/// meaningful. Y ∈ [-16, 100] for colours in gamut.
pub(crate) fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [c[0] * INV_WHITE[0], c[1] * INV_WHITE[1], c[2] * INV_WHITE[2]];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// YCxCz → CIE XYZ, the inverse of [`xyz_to_ycxcz`].
pub(crate) fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let cx = c[1] / 500.0;
    let cz = c[2] / 200.0;
    [(y + cx) * WHITE[0], y * WHITE[1], (y - cz) * WHITE[2]]
}

/// Linear sRGB → YCxCz, the input transform of both FLIP pipelines.
pub(crate) fn linear_rgb_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    xyz_to_ycxcz(linear_rgb_to_xyz(c))
}

/// CIE XYZ → CIELAB (D65 white).
pub(crate) fn xyz_to_lab(c: [f32; 3]) -> [f32; 3] {
    let delta = 6.0f32 / 29.0;
    let delta_square = delta * delta;
    let delta_cube = delta * delta_square;
    let factor = 1.0 / (3.0 * delta_square);
    let term = 4.0f32 / 29.0;
    let f = |v: f32| {
        if v > delta_cube { v.powf(1.0 / 3.0) } else { factor * v + term }
    };
    let [x, y, z] = [f(c[0] * INV_WHITE[0]), f(c[1] * INV_WHITE[1]), f(c[2] * INV_WHITE[2])];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// The Hunt effect: chroma is scaled by 0.01 · L*, so dark colours differ less.
pub(crate) fn hunt(lab: [f32; 3]) -> [f32; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// HyAB distance (Abasi et al. 2020): |ΔL| plus the Euclidean distance in (a, b).
pub(crate) fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    let dl = (a[0] - b[0]).abs();
    let (da, db) = (a[1] - b[1], a[2] - b[2]);
    dl + (da * da + db * db).sqrt()
}

/// Linear RGB clamped to [0, 1] → Hunt-adjusted CIELAB. NaN channels clamp to 0, as in the reference.
pub(crate) fn clamped_rgb_to_hunt_lab(rgb: [f32; 3]) -> [f32; 3] {
    hunt(xyz_to_lab(linear_rgb_to_xyz(rgb.map(clamp01))))
}

/// The lanes the spatial filters read: (Y, Cx, Cz, Cz); Cz twice because its filter is a sum of two
/// separable kernels.
pub(crate) fn spatial_lanes(ycxcz: [f32; 3]) -> [f32; 4] {
    [ycxcz[0], ycxcz[1], ycxcz[2], ycxcz[2]]
}

/// Spatially filtered lanes → Hunt-adjusted CIELAB: YCxCz (summing the two Cz parts) → XYZ → linear
/// RGB, clamped to [0, 1] → CIELAB → Hunt.
pub(crate) fn filtered_to_hunt_lab(lanes: [f32; 4]) -> [f32; 3] {
    let ycxcz = [lanes[0], lanes[1], lanes[2] + lanes[3]];
    clamped_rgb_to_hunt_lab(xyz_to_linear_rgb(ycxcz_to_xyz(ycxcz)))
}

/// `min(max(v, 0), 1)` with the reference's NaN behaviour (NaN → 0).
pub(crate) fn clamp01(v: f32) -> f32 {
    if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) }
}

/// Constants of the colour-error mapping: the largest Hunt-adjusted HyAB distance raised to q_c (between
/// pure green and pure blue) and the knee p_c · c_max.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ColourScale {
    cmax: f32,
    knee: f32,
}

impl ColourScale {
    /// Computes c_max from the primaries, as the reference does.
    pub(crate) fn new() -> ColourScale {
        let green = clamped_rgb_to_hunt_lab([0.0, 1.0, 0.0]);
        let blue = clamped_rgb_to_hunt_lab([0.0, 0.0, 1.0]);
        let cmax = hyab(green, blue).powf(QC);
        ColourScale { cmax, knee: PC * cmax }
    }

    /// The largest distance, c_max.
    #[cfg(test)]
    pub(crate) fn cmax(&self) -> f32 {
        self.cmax
    }

    /// Colour error in [0, 1] between two Hunt-adjusted CIELAB colours: HyAB^q_c, with [0, p_c·c_max)
    /// mapped linearly onto [0, p_t) and the rest onto [p_t, 1].
    pub(crate) fn error(&self, reference: [f32; 3], test: [f32; 3]) -> f32 {
        let d = hyab(reference, test).powf(QC);
        if d < self.knee { d * (PT / self.knee) } else { PT + ((d - self.knee) / (self.cmax - self.knee)) * (1.0 - PT) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    }

    #[test]
    fn white_and_black() {
        // sRGB white is the D65 white point; its YCxCz and Lab are (100, 0, 0).
        assert!(close(linear_rgb_to_xyz([1.0; 3]), WHITE, 1e-6));
        assert!(close(linear_rgb_to_ycxcz([1.0; 3]), [100.0, 0.0, 0.0], 1e-4));
        assert!(close(xyz_to_lab(WHITE), [100.0, 0.0, 0.0], 1e-4));
        assert!(close(linear_rgb_to_ycxcz([0.0; 3]), [-16.0, 0.0, 0.0], 1e-6));
        assert!(close(xyz_to_lab([0.0; 3]), [0.0, 0.0, 0.0], 1e-5));
    }

    #[test]
    fn primaries_by_hand() {
        // Red's XYZ is the first matrix column: (10135552/24577794, 2613072/12288897, 1425312/73733382).
        assert!(close(linear_rgb_to_xyz([1.0, 0.0, 0.0]), [0.412_386_6, 0.212_636_8, 0.019_330_6], 1e-6));
        // Its YCxCz: Y = 116·0.2126368 − 16 = 8.665871; Cx = 500·(0.4123866·1.0521569 − 0.2126368) =
        // 110.62928; Cz = 200·(0.2126368 − 0.0193306·0.9183577) = 38.97688.
        assert!(close(linear_rgb_to_ycxcz([1.0, 0.0, 0.0]), [8.665_871, 110.629_28, 38.976_88], 1e-3));
        // Green's CIELAB: (87.7362, −86.1787, 83.1826).
        let green = xyz_to_lab(linear_rgb_to_xyz([0.0, 1.0, 0.0]));
        assert!(close(green, [87.7362, -86.1787, 83.1826], 1e-3), "{green:?}");
    }

    #[test]
    fn inverses() {
        for c in [[0.2f32, 0.5, 0.9], [1.0, 0.0, 0.3], [0.01, 0.02, 0.0]] {
            assert!(close(xyz_to_linear_rgb(linear_rgb_to_xyz(c)), c, 1e-5));
            let xyz = linear_rgb_to_xyz(c);
            assert!(close(ycxcz_to_xyz(xyz_to_ycxcz(xyz)), xyz, 1e-5));
        }
    }

    #[test]
    fn hunt_and_hyab() {
        assert_eq!(hunt([50.0, 20.0, -10.0]), [50.0, 10.0, -5.0]);
        // |10 − 7| + sqrt(3² + 4²) = 8.
        assert_eq!(hyab([10.0, 1.0, 1.0], [7.0, 4.0, 5.0]), 8.0);
    }

    #[test]
    fn cmax_from_green_and_blue() {
        // Green (87.7362, −75.6099, 72.9812) and blue (32.2982, 25.5781, −34.8364) after Hunt:
        // HyAB = 55.4380 + sqrt(101.1880² + 107.8176²) = 203.3017; c_max = 203.3017^0.7 = 41.2761.
        let s = ColourScale::new();
        assert!((s.cmax() - 41.2761).abs() < 1e-3, "{}", s.cmax());
        assert_eq!(s.error([50.0, 0.0, 0.0], [50.0, 0.0, 0.0]), 0.0);
        let blue = clamped_rgb_to_hunt_lab([0.0, 0.0, 1.0]);
        let green = clamped_rgb_to_hunt_lab([0.0, 1.0, 0.0]);
        assert!((s.error(green, blue) - 1.0).abs() < 1e-6);
        // Exactly at the knee the error is p_t.
        let d = (s.knee).powf(1.0 / QC);
        assert!((s.error([50.0, 0.0, 0.0], [50.0 + d, 0.0, 0.0]) - PT).abs() < 1e-4);
    }

    #[test]
    fn clamp_maps_nan_to_zero() {
        assert_eq!(clamp01(f32::NAN), 0.0);
        assert_eq!(clamp01(-3.0), 0.0);
        assert_eq!(clamp01(3.0), 1.0);
        assert_eq!(clamp01(0.25), 0.25);
    }
}
