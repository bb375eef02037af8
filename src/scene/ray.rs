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
    let po = p + offset;
    let (out, off) = (po.to_array(), offset.to_array());
    Vec3A::from([0, 1, 2].map(|i| round_away(out[i], off[i])))
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
