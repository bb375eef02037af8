//! STAGE 2 (scene): rays and pbrt-v3's robust spawning of secondary rays from surface points.

use glam::Vec3A;

/// A ray `o + t·d` for t in (0, `t_max`). `d` need not be normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3A,
    /// Direction.
    pub d: Vec3A,
    /// Largest parameter considered.
    pub t_max: f32,
}

impl Ray {
    /// An unbounded ray.
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        Ray { o, d, t_max: f32::INFINITY }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3A {
        self.o + self.d * t
    }
}

/// The origin for a ray leaving surface point `p` (with absolute error bound `p_error`, geometric normal
/// `n`) in direction `w`: pbrt-v3's `OffsetRayOrigin` — push along the normal by the error bound projected
/// onto it, to the side `w` leaves from, then round away from the surface.
#[inline]
pub fn offset_ray_origin(p: Vec3A, p_error: Vec3A, n: Vec3A, w: Vec3A) -> Vec3A {
    let d = n.abs().dot(p_error);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    round_away3(p + offset, offset)
}

/// [`round_away`] on the three lanes of `x` with the offsets `off`: in SSE2 lanes on x86-64 (the same bit
/// operations, all lanes at once; a lane that is not finite sends the whole vector to the scalar code).
/// Every secondary ray's origin goes through here, several per path vertex.
#[inline]
fn round_away3(x: Vec3A, off: Vec3A) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    if x.is_finite() {
        return round_away3_sse2(x, off);
    }
    round_away3_scalar(x, off)
}

#[inline]
fn round_away3_scalar(x: Vec3A, off: Vec3A) -> Vec3A {
    let (x, off) = (x.to_array(), off.to_array());
    Vec3A::from([0, 1, 2].map(|i| round_away(x[i], off[i])))
}

/// [`round_away`] of each lane for finite `x` (SSE2 is part of x86-64, so no feature check is needed).
#[cfg(target_arch = "x86_64")]
#[inline]
fn round_away3_sse2(x: Vec3A, off: Vec3A) -> Vec3A {
    use std::arch::x86_64::*;
    let (x, off): (__m128, __m128) = (x.into(), off.into());
    // SAFETY: SSE2 is always available on x86-64; these intrinsics only compute on registers.
    unsafe {
        let zero = _mm_setzero_ps();
        let bits = _mm_castps_si128(x);
        let up = _mm_castps_si128(_mm_cmpgt_ps(off, zero)); // off > 0 (false for NaN)
        let moves = _mm_castps_si128(_mm_cmpneq_ps(off, zero)); // off != 0 (true for NaN)
        let non_negative = _mm_cmpgt_epi32(bits, _mm_set1_epi32(-1));
        // step = +1 where the sign of x is the step's direction, −1 otherwise: 1 + 2·(0 or −1).
        let differ = _mm_xor_si128(non_negative, up);
        let stepped = _mm_add_epi32(bits, _mm_add_epi32(_mm_set1_epi32(1), _mm_add_epi32(differ, differ)));
        // From ±0: the smallest subnormal of the offset's sign.
        let from_zero = _mm_or_si128(
            _mm_and_si128(up, _mm_set1_epi32(1)),
            _mm_andnot_si128(up, _mm_set1_epi32(0x8000_0001u32 as i32)),
        );
        let is_zero = _mm_castps_si128(_mm_cmpeq_ps(x, zero));
        let moved = _mm_or_si128(_mm_and_si128(is_zero, from_zero), _mm_andnot_si128(is_zero, stepped));
        let out = _mm_or_si128(_mm_and_si128(moves, moved), _mm_andnot_si128(moves, bits));
        Vec3A::from(_mm_castsi128_ps(out))
    }
}

/// `x.next_up()` where `off` > 0, `x.next_down()` where `off` < 0, else `x` — for the finite `x` of a
/// spawned origin, by selects on its bits rather than branches on the offset's sign (which varies from
/// ray to ray and mispredicts): one step of the bit pattern toward +∞ or −∞, and from ±0 the smallest
/// subnormal of the offset's sign. Non-finite `x` (not reached by geometry within ±1e9) are returned as
/// they are, as `next_up`/`next_down` return NaN and the infinity in their direction.
#[inline]
fn round_away(x: f32, off: f32) -> f32 {
    if !x.is_finite() {
        return if off > 0.0 {
            x.next_up()
        } else if off < 0.0 {
            x.next_down()
        } else {
            x
        };
    }
    let b = x.to_bits() as i32;
    let toward_up = off > 0.0;
    // Away from zero when the step's direction is the sign of x, toward zero otherwise.
    let step = if (b >= 0) == toward_up { 1 } else { -1 };
    let from_zero = if toward_up { 1u32 } else { 0x8000_0001 };
    let moved = if x == 0.0 { from_zero } else { (b + step) as u32 };
    if off != 0.0 { f32::from_bits(moved) } else { x }
}

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Nearest-hit rays (camera rays and their continuations).
    pub camera: u64,
    /// Any-hit (shadow/occlusion) rays.
    pub shadow: u64,
}

impl RayCounters {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.shadow
    }

    /// Adds another count.
    pub fn add(&mut self, o: &RayCounters) {
        self.camera += o.camera;
        self.shadow += o.shadow;
    }
}

/// `γ(n)` of pbrt-v3: the bound on the relative error of `n` floating-point operations.
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_away_by_bits_equals_next_up_and_next_down() {
        let reference = |x: f32, off: f32| {
            if off > 0.0 {
                x.next_up()
            } else if off < 0.0 {
                x.next_down()
            } else {
                x
            }
        };
        let mut xs = vec![0.0f32, -0.0, 1.0, -1.0, f32::MIN_POSITIVE, -f32::MIN_POSITIVE, f32::from_bits(1)];
        xs.extend([f32::from_bits(0x8000_0001), f32::MAX, f32::MIN, 1e9, -1e9, f32::INFINITY, f32::NEG_INFINITY]);
        // Every bit pattern's neighbourhood at a stride, both signs.
        xs.extend((0..(1u32 << 31)).step_by(9973).flat_map(|b| [f32::from_bits(b), f32::from_bits(b | 1 << 31)]));
        for &x in &xs {
            for off in [1e-3f32, -1e-3, 0.0, -0.0, f32::from_bits(1), -f32::from_bits(1)] {
                let (a, b) = (round_away(x, off), reference(x, off));
                assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "{x:e} {off:e}: {a:e} vs {b:e}");
            }
        }
    }

    #[test]
    fn the_lane_wise_rounding_is_the_scalar_one_bit_for_bit() {
        let mut xs = vec![0.0f32, -0.0, 1.0, -1.0, f32::MIN_POSITIVE, -f32::MIN_POSITIVE, f32::from_bits(1)];
        xs.extend([f32::from_bits(0x8000_0001), f32::MAX, f32::MIN, 1e9, -1e9, f32::INFINITY, f32::NAN]);
        xs.extend((0..(1u32 << 31)).step_by(99991).flat_map(|b| [f32::from_bits(b), f32::from_bits(b | 1 << 31)]));
        let offs = [1e-3f32, -1e-3, 0.0, -0.0, f32::from_bits(1), -f32::from_bits(1), f32::NAN];
        for (i, &x) in xs.iter().enumerate() {
            for (j, &o) in offs.iter().enumerate() {
                // Mix lanes: each lane its own value and offset.
                let x3 = Vec3A::new(x, xs[(i + 7) % xs.len()], xs[(i + 13) % xs.len()]);
                let o3 = Vec3A::new(o, offs[(j + 1) % offs.len()], offs[(j + 3) % offs.len()]);
                let (a, b) = (round_away3(x3, o3).to_array(), round_away3_scalar(x3, o3).to_array());
                for k in 0..3 {
                    assert!(a[k].to_bits() == b[k].to_bits() || (a[k].is_nan() && b[k].is_nan()), "{x3} {o3}");
                }
            }
        }
    }

    #[test]
    fn offset_moves_to_the_side_the_ray_leaves() {
        let p = Vec3A::new(1.0, 2.0, 3.0);
        let err = Vec3A::splat(1e-6);
        let n = Vec3A::Z;
        assert!(offset_ray_origin(p, err, n, Vec3A::Z).z > p.z);
        assert!(offset_ray_origin(p, err, n, -Vec3A::Z).z < p.z);
        // Even with a zero error bound the origin is rounded off the surface.
        assert!(offset_ray_origin(p, Vec3A::ZERO, n, Vec3A::Z).z >= p.z);
    }
}
