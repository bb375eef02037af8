//! STAGE 2 (scene): ray–triangle intersection, pbrt-v3's watertight algorithm (Woop, Benthin & Wald
//! 2013) with its conservative lower bound on t, so rays never leak through shared edges and never hit
//! the triangle they start on.

use glam::Vec3A;

use crate::scene::ray::gamma;

/// Per-ray constants of the watertight test: the axis permutation and shear that map the ray direction
/// onto +z. Computed once per ray (and once per instance the ray enters).
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    o: Vec3A,
    k: [usize; 3],
    s: [f32; 3],
}

impl RayShear {
    /// The shear for a ray with origin `o` and direction `d` (non-zero).
    #[inline]
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let kx = if kz == 2 { 0 } else { kz + 1 };
        let ky = if kx == 2 { 0 } else { kx + 1 };
        let dz = d[kz];
        RayShear { o, k: [kx, ky, kz], s: [-d[kx] / dz, -d[ky] / dz, 1.0 / dz] }
    }
}

/// The parameter t ∈ (0, t_max) and barycentrics (b1, b2) of the hit of the sheared ray with triangle
/// (p0, p1, p2), or `None`.
#[inline]
pub fn intersect(sh: &RayShear, p: &[[f32; 3]; 3], t_max: f32) -> Option<(f32, f32, f32)> {
    // One specialisation per dominant axis, so the permutation is done with constant indices.
    match sh.k[2] {
        0 => intersect_k::<1, 2, 0>(sh, p, t_max),
        1 => intersect_k::<2, 0, 1>(sh, p, t_max),
        _ => intersect_k::<0, 1, 2>(sh, p, t_max),
    }
}

#[inline(always)]
fn intersect_k<const KX: usize, const KY: usize, const KZ: usize>(
    sh: &RayShear,
    p: &[[f32; 3]; 3],
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let (v, [e0, e1, e2]) = edges::<KX, KY, KZ>(sh, p)?;
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    let sz = sh.s[2];
    let z = [v[0][2] * sz, v[1][2] * sz, v[2][2] * sz];
    let t_scaled = e0 * z[0] + e1 * z[1] + e2 * z[2];
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Conservative lower bound on t (pbrt-v3 §3.9.6): reject hits within the error of t = 0.
    let max_zt = z[0].abs().max(z[1].abs()).max(z[2].abs());
    let delta_z = gamma(3) * max_zt;
    let max_xt = v[0][0].abs().max(v[1][0].abs()).max(v[2][0].abs());
    let max_yt = v[0][1].abs().max(v[1][1].abs()).max(v[2][1].abs());
    let delta_x = gamma(5) * (max_xt + max_zt);
    let delta_y = gamma(5) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t <= delta_t {
        return None;
    }
    Some((t, e1 * inv_det, e2 * inv_det))
}

/// The vertices translated to the ray origin, permuted and sheared (z not yet scaled), and the three edge
/// functions, or `None` when the edge functions have mixed signs (the ray misses). On x86_64 [`edges`] is
/// the SSE version of this, which the tests hold to it bit for bit.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn edges<const KX: usize, const KY: usize, const KZ: usize>(
    sh: &RayShear,
    p: &[[f32; 3]; 3],
) -> Option<([[f32; 3]; 3], [f32; 3])> {
    edges_scalar::<KX, KY, KZ>(sh, p)
}

/// [`edges`] one vertex at a time.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn edges_scalar<const KX: usize, const KY: usize, const KZ: usize>(
    sh: &RayShear,
    p: &[[f32; 3]; 3],
) -> Option<([[f32; 3]; 3], [f32; 3])> {
    let [sx, sy, _] = sh.s;
    let o = [sh.o.x, sh.o.y, sh.o.z];
    // Translate to the ray origin, permute, shear in x and y.
    let tr = |q: &[f32; 3]| {
        let z = q[KZ] - o[KZ];
        [(q[KX] - o[KX]) + sx * z, (q[KY] - o[KY]) + sy * z, z]
    };
    let v = [tr(&p[0]), tr(&p[1]), tr(&p[2])];
    let e = [
        v[1][0] * v[2][1] - v[1][1] * v[2][0],
        v[2][0] * v[0][1] - v[2][1] * v[0][0],
        v[0][0] * v[1][1] - v[0][1] * v[1][0],
    ];
    edges_finish(v, e)
}

/// [`edges`] with the three vertices in the lanes of SSE registers: the same operations in the same order
/// per vertex (subtract, multiply, add; no fused multiply-add), so the values are bit for bit the scalar
/// ones, and a miss is told from the lane signs before anything is taken out of the registers.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn edges<const KX: usize, const KY: usize, const KZ: usize>(
    sh: &RayShear,
    p: &[[f32; 3]; 3],
) -> Option<([[f32; 3]; 3], [f32; 3])> {
    use std::arch::x86_64::*;
    let o = [sh.o.x, sh.o.y, sh.o.z];
    // SAFETY: SSE and SSE2 are part of the x86_64 baseline; only register arithmetic and stores to locals.
    unsafe {
        let axis = |k: usize| _mm_set_ps(0.0, p[2][k], p[1][k], p[0][k]);
        let z = _mm_sub_ps(axis(KZ), _mm_set1_ps(o[KZ]));
        let x = _mm_add_ps(_mm_sub_ps(axis(KX), _mm_set1_ps(o[KX])), _mm_mul_ps(_mm_set1_ps(sh.s[0]), z));
        let y = _mm_add_ps(_mm_sub_ps(axis(KY), _mm_set1_ps(o[KY])), _mm_mul_ps(_mm_set1_ps(sh.s[1]), z));
        // Lane i: v[i+1].x · v[i+2].y − v[i+1].y · v[i+2].x (indices mod 3), the scalar e_i.
        const NEXT: i32 = 0b11_00_10_01;
        const AFTER: i32 = 0b11_01_00_10;
        let e = _mm_sub_ps(
            _mm_mul_ps(_mm_shuffle_ps::<NEXT>(x, x), _mm_shuffle_ps::<AFTER>(y, y)),
            _mm_mul_ps(_mm_shuffle_ps::<NEXT>(y, y), _mm_shuffle_ps::<AFTER>(x, x)),
        );
        let zero = _mm_setzero_ps();
        let exact_zero = _mm_movemask_ps(_mm_cmpeq_ps(e, zero)) & 7;
        if exact_zero == 0 {
            let neg = _mm_movemask_ps(_mm_cmplt_ps(e, zero)) & 7;
            let pos = _mm_movemask_ps(_mm_cmpgt_ps(e, zero)) & 7;
            if neg != 0 && pos != 0 {
                return None;
            }
        }
        let mut lanes = [[0.0f32; 4]; 4];
        for (l, r) in lanes.iter_mut().zip([x, y, z, e]) {
            _mm_storeu_ps(l.as_mut_ptr(), r);
        }
        let [x, y, z, e] = lanes;
        let v = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]];
        edges_finish(v, [e[0], e[1], e[2]])
    }
}

/// The end of [`edges`]: an edge function of exactly zero is redone in double precision, as pbrt-v3 does,
/// and mixed signs are a miss.
#[inline(always)]
fn edges_finish(v: [[f32; 3]; 3], mut e: [f32; 3]) -> Option<([[f32; 3]; 3], [f32; 3])> {
    if e.contains(&0.0) {
        let d = |a: [f32; 3], b: [f32; 3]| (a[0] as f64 * b[1] as f64 - a[1] as f64 * b[0] as f64) as f32;
        e = [d(v[1], v[2]), d(v[2], v[0]), d(v[0], v[1])];
    }
    let [e0, e1, e2] = e;
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    Some((v, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sse_edge_functions_are_the_scalar_ones_bit_for_bit() {
        let mut rng = crate::sampling::Rng::new(21);
        let mut v = |scale: f32| Vec3A::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * scale;
        let bits = |r: Option<([[f32; 3]; 3], [f32; 3])>| {
            r.map(|(v, e)| (v.map(|q| q.map(f32::to_bits)), e.map(f32::to_bits)))
        };
        let (mut hits, mut exact_zero) = (0, 0);
        for i in 0..20000 {
            // Every fourth triangle has a vertex on the ray's line, so an edge function is exactly zero.
            let (o, d) = (v(4.0), v(2.0));
            let a = v(4.0);
            let p = [
                a.to_array(),
                (a + v(1.0)).to_array(),
                if i % 4 == 0 { (o + d * 3.0).to_array() } else { (a + v(1.0)).to_array() },
            ];
            let sh = RayShear::new(o, d);
            let (simd, scalar) = match sh.k[2] {
                0 => (edges::<1, 2, 0>(&sh, &p), edges_scalar::<1, 2, 0>(&sh, &p)),
                1 => (edges::<2, 0, 1>(&sh, &p), edges_scalar::<2, 0, 1>(&sh, &p)),
                _ => (edges::<0, 1, 2>(&sh, &p), edges_scalar::<0, 1, 2>(&sh, &p)),
            };
            assert_eq!(bits(simd), bits(scalar), "triangle {i}");
            hits += usize::from(simd.is_some());
            exact_zero += usize::from(i % 4 == 0 && simd.is_some());
        }
        assert!(hits > 500 && exact_zero > 100, "both paths exercised: {hits} passes, {exact_zero} with a zero edge");
    }

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn hits_inside_misses_outside_and_reports_barycentrics() {
        let sh = RayShear::new(Vec3A::new(0.25, 0.5, 1.0), -Vec3A::Z);
        let (t, b1, b2) = intersect(&sh, &TRI, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6 && (b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        assert!(intersect(&sh, &TRI, 0.5).is_none(), "beyond t_max");
        let miss = RayShear::new(Vec3A::new(0.75, 0.75, 1.0), -Vec3A::Z);
        assert!(intersect(&miss, &TRI, f32::INFINITY).is_none());
        let behind = RayShear::new(Vec3A::new(0.25, 0.25, 1.0), Vec3A::Z);
        assert!(intersect(&behind, &TRI, f32::INFINITY).is_none());
    }

    #[test]
    fn shared_edges_do_not_leak() {
        // Two triangles sharing the diagonal of the unit square; rays along the diagonal hit exactly one
        // or both, never neither.
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
        let b = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for i in 0..1000 {
            let s = i as f32 / 1000.0 * 0.999 + 0.0005;
            let d = Vec3A::new(0.013 * (i as f32).sin(), 0.017, -1.0).normalize();
            let o = Vec3A::new(s, s, 0.0) - d * 3.0;
            let sh = RayShear::new(o, d);
            let hit = intersect(&sh, &a, f32::INFINITY).is_some() || intersect(&sh, &b, f32::INFINITY).is_some();
            assert!(hit, "leak at s = {s}");
        }
    }
}
