//! Warps from the unit square to disks and hemispheres, with their densities (pbrt-v3's sampling.h
//! conventions: local z is the normal).

use glam::Vec3A;
use std::f32::consts::{FRAC_PI_4, PI};

/// Shirley–Chiu concentric map from [0,1)² to the unit disk (area-preserving up to a constant).
#[inline]
pub fn concentric_disk(u: [f32; 2]) -> [f32; 2] {
    concentric_disk_polar(u).0
}

/// [`concentric_disk`] and the point's radius r (|r|, signed as the map's square coordinate it came from),
/// which it computes on the way: a caller that needs 1 − x² − y² gets it as 1 − r² without waiting for x and y.
#[inline(always)]
fn concentric_disk_polar(u: [f32; 2]) -> ([f32; 2], f32) {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    // The angle is π/4·(b/a) or π/2 − π/4·(a/b); both reduce to sin/cos of an angle in [−π/4, π/4]. The
    // two cases are chosen by selects, not a branch (which half a sample falls in is a coin toss, so a
    // branch mispredicts half the time); each computes exactly what its branch did.
    let wide = a.abs() > b.abs();
    let (num, den) = if wide { (b, a) } else { (a, b) };
    let (s, c) = sin_cos_quarter(FRAC_PI_4 * (num / den));
    let (x, y) = if wide { (c, s) } else { (s, c) };
    if a == 0.0 && b == 0.0 { ([0.0, 0.0], 0.0) } else { ([den * x, den * y], den) }
}

/// sin and cos of x ∈ [−π/4, π/4] by the minimax polynomials of Cephes's `sinf`/`cosf` for that range
/// (degree 7 and 8; error below 2·10⁻⁷ against the library, the test checks it), each written as two
/// independent halves so the dependent chain is short: cheaper than the general library routine, which must
/// reduce arbitrary arguments, and than the Taylor series it replaced (degree 9 and 10, one long chain).
#[inline]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let z = x * x;
    let z2 = z * z;
    let s = x + x * z * ((-1.666_665_5e-1 + 8.332_161e-3 * z) + -1.951_529_6e-4 * z2);
    let c = (1.0 - 0.5 * z) + z2 * ((4.166_664_6e-2 + -1.388_731_6e-3 * z) + 2.443_315_7e-5 * z2);
    (s, c)
}

/// Cosine-weighted direction on the hemisphere around +z (Malley's method), density cosθ/π.
#[inline]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3A {
    // z = √(1 − r²): the same as √(1 − x² − y²) up to rounding, and computed alongside the sine and cosine
    // rather than after them (a path's next ray waits on this direction).
    let ([x, y], r) = concentric_disk_polar(u);
    Vec3A::new(x, y, (1.0 - r * r).max(0.0).sqrt())
}

/// [`cosine_hemisphere`] for up to 8 points at once (`out[i]` from `u[i]`, same values bit for bit), written
/// without branches so the compiler turns the loop into vector instructions.
#[inline]
pub fn cosine_hemisphere_batch(u: &[[f32; 2]], out: &mut [[f32; 3]; 8]) {
    let mut a = [0.0f32; 8];
    let mut b = [0.0f32; 8];
    for (i, ui) in u.iter().take(8).enumerate() {
        a[i] = 2.0 * ui[0] - 1.0;
        b[i] = 2.0 * ui[1] - 1.0;
    }
    for i in 0..8 {
        let (ai, bi) = (a[i], b[i]);
        let a_major = ai.abs() > bi.abs();
        let r = if a_major { ai } else { bi };
        let minor = if a_major { bi } else { ai };
        // r = 0 only at the centre, where both are 0 and the point maps to the pole.
        let q = if r != 0.0 { minor / r } else { 0.0 };
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * q);
        let (x, y) = if a_major { (r * c, r * s) } else { (r * s, r * c) };
        out[i] = [x, y, (1.0 - r * r).max(0.0).sqrt()];
    }
}

/// The density of [`cosine_hemisphere`] for a direction with cosine `cos_theta` to +z.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta * (1.0 / PI)
}

/// Uniform direction on the hemisphere around +z, density 1/(2π).
#[inline]
pub fn uniform_hemisphere(u: [f32; 2]) -> Vec3A {
    let z = u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction on the whole sphere, density 1/(4π) (pbrt-v3 `UniformSampleSphere`).
#[inline]
pub fn uniform_sphere(u: [f32; 2]) -> Vec3A {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle acos(`cos_max`) around +z, density 1/(2π(1 − cos_max))
/// (pbrt-v3 `UniformSampleCone`).
#[inline]
pub fn uniform_cone(u: [f32; 2], cos_max: f32) -> Vec3A {
    let z = (1.0 - u[0]) + u[0] * cos_max;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Clarberg's equal-area map from [0,1)² to the hemisphere around +z (ALGORITHMS.md §3.2): the concentric
/// map to the disk, then the Lambert azimuthal equal-area lift z = 1 − r², (x, y) = r·sqrt(2 − r²)·(cos φ,
/// sin φ). Equal areas of the square map to equal solid angles, so an n×n grid of cells gives n² directions
/// of 2π/n² sr each.
#[inline]
pub fn equal_area_hemisphere(u: [f32; 2]) -> Vec3A {
    let [dx, dy] = concentric_disk(u);
    let r2 = dx * dx + dy * dy;
    let s = (2.0 - r2).max(0.0).sqrt();
    Vec3A::new(dx * s, dy * s, 1.0 - r2)
}

/// The density of [`uniform_hemisphere`].
pub const UNIFORM_HEMISPHERE_PDF: f32 = 1.0 / (2.0 * PI);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cosine_batch_equals_the_single_map_bit_for_bit() {
        let mut rng = crate::sampling::Rng::new(9);
        let mut pts: Vec<[f32; 2]> = (0..61).map(|_| rng.uniform2()).collect();
        pts.extend([[0.5, 0.5], [0.0, 0.0], [1.0, 0.5], [0.5, 1.0], [0.25, 0.75], [0.75, 0.75], [0.5, 0.0]]);
        let mut out = [[0.0; 3]; 8];
        for chunk in pts.chunks(8) {
            cosine_hemisphere_batch(chunk, &mut out);
            for (u, w) in chunk.iter().zip(&out) {
                assert_eq!(cosine_hemisphere(*u).to_array(), *w, "at {u:?}");
            }
        }
    }

    fn grid(n: usize) -> impl Iterator<Item = [f32; 2]> {
        (0..n * n).map(move |i| [((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32])
    }

    #[test]
    fn cosine_hemisphere_is_unit_upper_and_integrates_cosine() {
        // E[cos θ / pdf] over the cosine density equals ∫cos dω = π.
        let n = 64;
        let mut sum = 0.0f64;
        for u in grid(n) {
            let w = cosine_hemisphere(u);
            assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0);
            if w.z > 0.0 {
                sum += (w.z / cosine_hemisphere_pdf(w.z)) as f64;
            }
        }
        assert!((sum / (n * n) as f64 - std::f64::consts::PI).abs() < 1e-4);
        // The mean of cos θ under the cosine density is 2/3.
        let mean: f64 = grid(n).map(|u| cosine_hemisphere(u).z as f64).sum::<f64>() / (n * n) as f64;
        assert!((mean - 2.0 / 3.0).abs() < 2e-3, "{mean}");
    }

    #[test]
    fn uniform_hemisphere_has_mean_cosine_one_half() {
        let n = 64;
        let mean: f64 = grid(n).map(|u| uniform_hemisphere(u).z as f64).sum::<f64>() / (n * n) as f64;
        assert!((mean - 0.5).abs() < 1e-3);
    }

    #[test]
    fn quarter_sin_cos_matches_the_library() {
        for i in 0..=1000 {
            let x = -FRAC_PI_4 + i as f32 / 1000.0 * 2.0 * FRAC_PI_4;
            let (s, c) = sin_cos_quarter(x);
            assert!((s - x.sin()).abs() < 2e-7 && (c - x.cos()).abs() < 2e-7, "{x}");
        }
    }

    #[test]
    fn equal_area_cells_have_equal_solid_angles_and_integrate_cosine() {
        // Σ_k cos θ_k · 2π/n² ≈ π (ALGORITHMS.md §12) over the 32×32 cell centres.
        let n = 32;
        let sum: f64 = grid(n).map(|u| equal_area_hemisphere(u).z as f64).sum::<f64>() * 2.0 * std::f64::consts::PI
            / (n * n) as f64;
        assert!((sum - std::f64::consts::PI).abs() < 0.01 * std::f64::consts::PI, "{sum}");
        for u in grid(n) {
            let w = equal_area_hemisphere(u);
            assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0);
        }
        // Equal area ⇔ uniform square samples give uniform directions; on the hemisphere that means
        // z = cos θ is uniform on [0, 1] and so is φ/2π. Histogram a fine grid of square points.
        let m = 512;
        let mut hz = [0u32; 10];
        let mut hphi = [0u32; 8];
        for u in grid(m) {
            let w = equal_area_hemisphere(u);
            hz[((w.z * 10.0) as usize).min(9)] += 1;
            let phi = w.y.atan2(w.x).rem_euclid(2.0 * PI);
            hphi[((phi / (2.0 * PI) * 8.0) as usize).min(7)] += 1;
        }
        let total = (m * m) as f64;
        for c in hz {
            assert!((c as f64 / total - 0.1).abs() < 0.002, "{hz:?}");
        }
        for c in hphi {
            assert!((c as f64 / total - 0.125).abs() < 0.002, "{hphi:?}");
        }
    }

    #[test]
    fn the_branch_free_disk_equals_the_branching_one_bit_for_bit() {
        let branching = |u: [f32; 2]| {
            let a = 2.0 * u[0] - 1.0;
            let b = 2.0 * u[1] - 1.0;
            if a == 0.0 && b == 0.0 {
                return [0.0, 0.0];
            }
            if a.abs() > b.abs() {
                let (s, c) = sin_cos_quarter(FRAC_PI_4 * (b / a));
                [a * c, a * s]
            } else {
                let (s, c) = sin_cos_quarter(FRAC_PI_4 * (a / b));
                [b * s, b * c]
            }
        };
        let mut rng = crate::sampling::Rng::new(3);
        let mut us: Vec<[f32; 2]> = (0..200_000).map(|_| [rng.uniform(), rng.uniform()]).collect();
        us.extend(grid(65));
        us.extend([[0.5, 0.5], [0.5, 0.0], [0.0, 0.5], [0.25, 0.75], [0.75, 0.75], [0.0, 0.0], [ONE, ONE]]);
        for u in us {
            assert_eq!(concentric_disk(u).map(f32::to_bits), branching(u).map(f32::to_bits), "{u:?}");
        }
    }

    /// The largest sample value below 1.
    const ONE: f32 = 1.0 - f32::EPSILON / 2.0;

    #[test]
    fn concentric_disk_stays_in_the_disk() {
        for u in grid(33) {
            let [x, y] = concentric_disk(u);
            assert!(x * x + y * y <= 1.0 + 1e-6);
        }
    }
}
