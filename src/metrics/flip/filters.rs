//! FLIP's separable filters and the two convolution passes that apply them.
//!
//! * The *spatial* (contrast sensitivity) filters depend on the pixels per degree: a Gaussian for the
//!   achromatic channel Y, one for the red–green channel Cx, and a sum of two Gaussians for the
//!   blue–yellow channel Cz, which is separated into two 1-D kernels whose outer products are summed
//!   (Andersson et al. 2020, eq. 2–3; `misc/separatedConvolutions.pdf` in NVIDIA's repository).
//! * The *feature* filters are a Gaussian with σ = ½ · 0.082 · ppd and its first and second derivatives,
//!   normalised so the Gaussian sums to 1 and each derivative's positive and negative weights to ±1
//!   (Andersson et al. 2020, §3.2).
//!
//! Both pipelines move four values per pixel ("lanes") through a horizontal pass and then a vertical pass,
//! each lane with its own 1-D kernel; edges are clamped. Every output sums its taps in increasing
//! offset, starting from zero, as the reference does, so results depend only on the inputs, not on how
//! rows are split between threads. Depends on nothing else in the crate.

/// π in f32 (the reference's 3.14159265358979f rounds to the same value).
const PI: f32 = std::f32::consts::PI;

/// Gaussian parameters of the contrast sensitivity functions (a, b) per channel, from the FLIP paper:
/// Y: (1, 0.0047); Cx: (1, 0.0053); Cz: (34.1, 0.04) + (13.5, 0.025).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2_CZ: f32 = 13.5;
const B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];

/// Width of the feature detector relative to a degree of visual angle (w).
const FEATURE_WIDTH: f32 = 0.082;

/// Four lanes of one pixel.
pub(crate) type Lanes = [f32; 4];

/// A 1-D kernel of `2 * radius + 1` taps, one weight per lane per tap.
#[derive(Clone, Debug)]
pub(crate) struct Kernel {
    pub(crate) radius: usize,
    pub(crate) taps: Vec<Lanes>,
}

/// The contrast sensitivity Gaussian in the frequency-derived spatial form: a·√(π/b)·exp(−π²x²/b).
fn csf_gaussian(x2: f32, a: f32, b: f32) -> f32 {
    let pi_sq = PI * PI;
    a * (PI / b).sqrt() * (-pi_sq * x2 / b).exp()
}

/// The square-root-weighted form used to separate the sum of two Gaussians.
fn csf_gaussian_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    let pi_sq = PI * PI;
    (a * (PI / b).sqrt()).sqrt() * (-pi_sq * x2 / b).exp()
}

/// Radius of the spatial filters: three standard deviations of the widest Gaussian, in pixels.
fn spatial_radius(ppd: f32) -> usize {
    let pi_sq = PI * PI;
    let widest = B1.iter().chain(B2.iter()).fold(f32::MIN, |m, &b| m.max(b));
    (3.0 * (widest / (2.0 * pi_sq)).sqrt() * ppd).ceil() as usize
}

/// The spatial filter for lanes (Y, Cx, Cz, Cz): Y and Cx kernels normalised to sum 1; the two Cz
/// kernels scaled together by 1 / ‖(Σ first, Σ second)‖. The same kernel serves both directions.
pub(crate) fn spatial_kernel(ppd: f32) -> Kernel {
    let radius = spatial_radius(ppd);
    let dx = 1.0 / ppd;
    let mut taps: Vec<Lanes> = (0..2 * radius + 1)
        .map(|i| {
            let x = (i as f32 - radius as f32) * dx;
            let x2 = x * x;
            [
                csf_gaussian(x2, A1[0], B1[0]),
                csf_gaussian(x2, A1[1], B1[1]),
                csf_gaussian_sqrt(x2, A1[2], B1[2]),
                csf_gaussian_sqrt(x2, A2_CZ, B2[2]),
            ]
        })
        .collect();
    let mut sum = [0.0f32; 4];
    for t in &taps {
        for l in 0..4 {
            sum[l] += t[l];
        }
    }
    let cz_norm = 1.0 / (sum[2] * sum[2] + sum[3] * sum[3]).sqrt();
    let norm = [1.0 / sum[0], 1.0 / sum[1], cz_norm, cz_norm];
    for t in &mut taps {
        for l in 0..4 {
            t[l] *= norm[l];
        }
    }
    Kernel { radius, taps }
}

/// The feature filters as (Gaussian, first derivative, second derivative) per tap, normalised.
fn feature_taps(ppd: f32) -> Vec<[f32; 3]> {
    let sigma = 0.5 * FEATURE_WIDTH * ppd;
    let radius = (3.0 * sigma).ceil() as i64;
    let (mut g_sum, mut dg_pos, mut dg_neg, mut ddg_pos, mut ddg_neg) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let mut taps: Vec<[f32; 3]> = (-radius..=radius)
        .map(|i| {
            let x = i as f32;
            let g = (-(x * x) / (2.0 * sigma * sigma)).exp();
            let dg = -x * g;
            let ddg = (x * x / (sigma * sigma) - 1.0) * g;
            g_sum += g;
            if dg > 0.0 {
                dg_pos += dg
            } else {
                dg_neg -= dg
            }
            if ddg > 0.0 {
                ddg_pos += ddg
            } else {
                ddg_neg -= ddg
            }
            [g, dg, ddg]
        })
        .collect();
    // Below about 1.7 pixels per degree the off-centre taps underflow to zero and the derivative sums
    // vanish; the reference then divides 0 by 0 (NaN everywhere), here those weights stay zero.
    let divide = |v: f32, sum: f32| if sum > 0.0 { v / sum } else { 0.0 };
    for t in &mut taps {
        t[0] /= g_sum;
        t[1] = divide(t[1], if t[1] > 0.0 { dg_pos } else { dg_neg });
        t[2] = divide(t[2], if t[2] > 0.0 { ddg_pos } else { ddg_neg });
    }
    taps
}

/// The two feature kernels. Horizontal: lanes (Y, Y, Y, Y) → (∂x, ∂²x, G, G). Vertical: lanes
/// (∂x, ∂²x, G, G) → (∂x·G, ∂²x·G, G·∂y, G·∂²y), i.e. the four 2-D derivative-of-Gaussian responses.
pub(crate) fn feature_kernels(ppd: f32) -> (Kernel, Kernel) {
    let taps = feature_taps(ppd);
    let radius = taps.len() / 2;
    let horizontal = taps.iter().map(|&[g, dg, ddg]| [dg, ddg, g, g]).collect();
    let vertical = taps.iter().map(|&[g, dg, ddg]| [g, g, dg, ddg]).collect();
    (Kernel { radius, taps: horizontal }, Kernel { radius, taps: vertical })
}

/// Pixels filtered together. Their sums are independent, which keeps the floating-point units busy,
/// while each pixel still adds its taps in order.
const BLOCK: usize = 8;

/// `acc += t · p`, lane by lane.
#[inline(always)]
fn mul_add(acc: &mut Lanes, t: &Lanes, p: &Lanes) {
    for l in 0..4 {
        acc[l] += t[l] * p[l];
    }
}

/// Filters one row horizontally: `out[x] = Σ_k taps[k] · row[clamp(x + k − r)]`, lane by lane.
/// `padded` is scratch space, reused between calls.
pub(crate) fn horizontal(row: &[Lanes], kernel: &Kernel, padded: &mut Vec<Lanes>, out: &mut [Lanes]) {
    let (w, r, n) = (row.len(), kernel.radius, kernel.taps.len());
    padded.clear();
    padded.extend((0..w + 2 * r).map(|i| row[(i.saturating_sub(r)).min(w - 1)]));
    let mut blocks = out.chunks_exact_mut(BLOCK);
    for (b, block) in (&mut blocks).enumerate() {
        let x0 = b * BLOCK;
        let mut acc = [[0.0f32; 4]; BLOCK];
        for (k, t) in kernel.taps.iter().enumerate() {
            let src = &padded[x0 + k..x0 + k + BLOCK];
            for j in 0..BLOCK {
                mul_add(&mut acc[j], t, &src[j]);
            }
        }
        block.copy_from_slice(&acc);
    }
    let x0 = w - w % BLOCK;
    for (j, o) in blocks.into_remainder().iter_mut().enumerate() {
        let mut acc = [0.0f32; 4];
        for (t, p) in kernel.taps.iter().zip(&padded[x0 + j..x0 + j + n]) {
            mul_add(&mut acc, t, p);
        }
        *o = acc;
    }
}

/// Filters row `y` of a `width`-wide plane vertically: `out[x] = Σ_k taps[k] · plane[clamp(y + k − r)][x]`.
/// `rows` is scratch space, reused between calls.
pub(crate) fn vertical<'a>(
    plane: &'a [Lanes],
    width: usize,
    y: usize,
    kernel: &Kernel,
    rows: &mut Vec<&'a [Lanes]>,
    out: &mut [Lanes],
) {
    let height = plane.len() / width;
    let r = kernel.radius;
    rows.clear();
    rows.extend((0..kernel.taps.len()).map(|k| {
        let yy = (y + k).saturating_sub(r).min(height - 1);
        &plane[yy * width..(yy + 1) * width]
    }));
    let mut blocks = out.chunks_exact_mut(BLOCK);
    for (b, block) in (&mut blocks).enumerate() {
        let x0 = b * BLOCK;
        let mut acc = [[0.0f32; 4]; BLOCK];
        for (t, row) in kernel.taps.iter().zip(rows.iter()) {
            let src = &row[x0..x0 + BLOCK];
            for j in 0..BLOCK {
                mul_add(&mut acc[j], t, &src[j]);
            }
        }
        block.copy_from_slice(&acc);
    }
    let x0 = width - width % BLOCK;
    for (j, o) in blocks.into_remainder().iter_mut().enumerate() {
        let mut acc = [0.0f32; 4];
        for (t, row) in kernel.taps.iter().zip(rows.iter()) {
            mul_add(&mut acc, t, &row[x0 + j]);
        }
        *o = acc;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PPD: f32 = 67.020_645;

    #[test]
    fn radii_at_67_ppd() {
        // Spatial: ceil(3 · sqrt(0.04 / 2π²) · 67.02) = ceil(9.05) = 10. Feature: σ = 2.748, ceil(8.24) = 9.
        assert_eq!(spatial_kernel(PPD).radius, 10);
        let (h, v) = feature_kernels(PPD);
        assert_eq!((h.radius, v.radius, h.taps.len()), (9, 9, 19));
    }

    #[test]
    fn normalisation() {
        let s = spatial_kernel(PPD);
        let sum = |l: usize| s.taps.iter().map(|t| t[l] as f64).sum::<f64>();
        assert!((sum(0) - 1.0).abs() < 1e-6 && (sum(1) - 1.0).abs() < 1e-6);
        assert!(((sum(2).powi(2) + sum(3).powi(2)).sqrt() - 1.0).abs() < 1e-6);
        let taps = feature_taps(PPD);
        let g: f64 = taps.iter().map(|t| t[0] as f64).sum();
        let pos = |l: usize| taps.iter().map(|t| t[l].max(0.0) as f64).sum::<f64>();
        let neg = |l: usize| taps.iter().map(|t| t[l].min(0.0) as f64).sum::<f64>();
        assert!((g - 1.0).abs() < 1e-6);
        for l in [1, 2] {
            assert!((pos(l) - 1.0).abs() < 1e-6 && (neg(l) + 1.0).abs() < 1e-6);
        }
        // Symmetry: the Gaussians are even, the first derivative odd; the middle tap of ∂ is zero.
        let n = taps.len();
        for i in 0..n {
            assert_eq!(taps[i][0], taps[n - 1 - i][0]);
            // Positive and negative sums are accumulated in different orders, so allow rounding.
            assert!((taps[i][1] + taps[n - 1 - i][1]).abs() < 1e-7);
        }
        assert_eq!(taps[n / 2][1], 0.0);
        // The first derivative is −x·G: positive on the left (x < 0).
        assert!(taps[0][1] > 0.0);
    }

    /// The blocked loops give exactly the tap-ordered sums, in the interior, at edges and in remainders.
    #[test]
    fn blocked_passes_equal_plain_sums() {
        let k = spatial_kernel(PPD);
        let (w, h) = (2 * BLOCK + 5, 23);
        let plane: Vec<Lanes> = (0..w * h)
            .map(|i| {
                let v = ((i * 7919) % 101) as f32 / 37.0;
                [v, -v, v * v, 1.0 / (1.0 + v)]
            })
            .collect();
        let naive = |at: &dyn Fn(i64) -> Lanes| {
            let mut acc = [0.0f32; 4];
            for (i, t) in k.taps.iter().enumerate() {
                let p = at(i as i64 - k.radius as i64);
                for l in 0..4 {
                    acc[l] += t[l] * p[l];
                }
            }
            acc
        };
        let clamp = |v: i64, n: usize| v.clamp(0, n as i64 - 1) as usize;
        let mut out = vec![[0.0; 4]; w];
        for y in [0, 5, h - 1] {
            let row = &plane[y * w..(y + 1) * w];
            horizontal(row, &k, &mut Vec::new(), &mut out);
            for x in 0..w {
                assert_eq!(out[x], naive(&|d| row[clamp(x as i64 + d, w)]), "h {x} {y}");
            }
            vertical(&plane, w, y, &k, &mut Vec::new(), &mut out);
            for x in 0..w {
                assert_eq!(out[x], naive(&|d| plane[clamp(y as i64 + d, h) * w + x]), "v {x} {y}");
            }
        }
    }

    #[test]
    fn tiny_ppd_gives_finite_weights() {
        for ppd in [0.01, 0.5, 1.0, 2.0] {
            let taps = feature_taps(ppd);
            assert!(taps.iter().flatten().all(|v| v.is_finite()), "{ppd}: {taps:?}");
            assert!(spatial_kernel(ppd).taps.iter().flatten().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn passes_clamp_edges_and_keep_constants() {
        let k = Kernel { radius: 1, taps: vec![[0.25; 4], [0.5; 4], [0.25; 4]] };
        let row: Vec<Lanes> = [1.0, 2.0, 4.0].iter().map(|&v| [v, v, -v, 0.0]).collect();
        let mut out = vec![[0.0; 4]; 3];
        horizontal(&row, &k, &mut Vec::new(), &mut out);
        // Left edge: 0.25·1 + 0.5·1 + 0.25·2 = 1.25; middle 2.25; right 0.25·2 + 0.5·4 + 0.25·4 = 3.5.
        assert_eq!(out.iter().map(|o| o[0]).collect::<Vec<_>>(), vec![1.25, 2.25, 3.5]);
        assert_eq!(out[2][2], -3.5);
        // Vertical on a 1-wide, 3-tall plane is the same computation.
        let mut col = vec![[0.0; 4]; 1];
        vertical(&row, 1, 0, &k, &mut Vec::new(), &mut col);
        assert_eq!(col[0][0], 1.25);
        vertical(&row, 1, 2, &k, &mut Vec::new(), &mut col);
        assert_eq!(col[0][0], 3.5);
        // A single-pixel image works.
        let mut one = vec![[0.0; 4]; 1];
        horizontal(&row[..1], &spatial_kernel(PPD), &mut Vec::new(), &mut one);
        assert!((one[0][0] - 1.0).abs() < 1e-6);
    }
}
