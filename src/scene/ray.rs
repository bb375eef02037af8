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
    let mut out = po.to_array();
    let off = offset.to_array();
    for i in 0..3 {
        if off[i] > 0.0 {
            out[i] = out[i].next_up();
        } else if off[i] < 0.0 {
            out[i] = out[i].next_down();
        }
    }
    Vec3A::from(out)
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
