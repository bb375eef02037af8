//! STAGE 2 (scene): pbrt-v3's analytic shapes — sphere, disk, cylinder — intersected exactly in object
//! space (in f64, so a ray leaving the surface never re-hits it at t ≈ 0), not tessellated: ambient
//! occlusion next to a sphere depends on its true curvature.

use glam::{Affine3A, DVec3, Vec3A};

use crate::scene::ray::{Ray, gamma};

/// The shape in its own object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum QuadricKind {
    /// Sphere of `radius` around the origin, cut to z ∈ [z_min, z_max] and φ ∈ [0, phi_max].
    Sphere {
        /// Radius.
        radius: f64,
        /// Lower z cut.
        z_min: f64,
        /// Upper z cut.
        z_max: f64,
        /// Sweep angle in radians.
        phi_max: f64,
    },
    /// Annulus in the plane z = `height` with radii in [inner_radius, radius], φ ∈ [0, phi_max].
    Disk {
        /// z of the plane.
        height: f64,
        /// Outer radius.
        radius: f64,
        /// Inner radius.
        inner_radius: f64,
        /// Sweep angle in radians.
        phi_max: f64,
    },
    /// Cylinder of `radius` around z, z ∈ [z_min, z_max], φ ∈ [0, phi_max].
    Cylinder {
        /// Radius.
        radius: f64,
        /// Lower z.
        z_min: f64,
        /// Upper z.
        z_max: f64,
        /// Sweep angle in radians.
        phi_max: f64,
    },
}

/// An analytic shape placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadric {
    /// The shape in object space.
    pub kind: QuadricKind,
    /// Object → world (for shapes inside an object definition: object → instance space).
    pub world_from_object: Affine3A,
    /// World → object.
    pub object_from_world: Affine3A,
    /// Whether the outward normal is flipped (ReverseOrientation xor a handedness-swapping transform).
    pub flip_normal: bool,
}

/// Where a ray hit a quadric, in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricHit {
    /// Ray parameter (same in object and world space: directions are not renormalised).
    pub t: f32,
    /// Hit point on the surface, object space.
    pub p: DVec3,
}

/// Surface data of a quadric hit, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricSurface {
    /// World position.
    pub p: Vec3A,
    /// Absolute error bound of `p`.
    pub p_error: Vec3A,
    /// Unit geometric normal (outward unless flipped).
    pub n: Vec3A,
    /// ∂p/∂u.
    pub dpdu: Vec3A,
    /// Surface parameters.
    pub uv: [f32; 2],
}

fn phi_of(p: DVec3) -> f64 {
    let phi = p.y.atan2(p.x);
    if phi < 0.0 { phi + std::f64::consts::TAU } else { phi }
}

fn solve_quadratic(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let q = if b < 0.0 { -0.5 * (b - root) } else { -0.5 * (b + root) };
    let (t0, t1) = (q / a, c / q);
    Some(if t0 > t1 { (t1, t0) } else { (t0, t1) })
}

impl QuadricKind {
    /// The first hit of the object-space ray (o, d) with t in (0, t_max).
    pub fn intersect(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, DVec3)> {
        match *self {
            QuadricKind::Sphere { radius: r, z_min, z_max, phi_max } => {
                let (t0, t1) = solve_quadratic(d.length_squared(), 2.0 * d.dot(o), o.length_squared() - r * r)?;
                let accept = |t: f64| -> Option<DVec3> {
                    if t <= 0.0 || t >= t_max {
                        return None;
                    }
                    let mut p = o + d * t;
                    p *= r / p.length();
                    if p.x == 0.0 && p.y == 0.0 {
                        p.x = 1e-5 * r;
                    }
                    let clipped = (z_min > -r && p.z < z_min) || (z_max < r && p.z > z_max) || phi_of(p) > phi_max;
                    (!clipped).then_some(p)
                };
                accept(t0).map(|p| (t0, p)).or_else(|| accept(t1).map(|p| (t1, p)))
            }
            QuadricKind::Disk { height, radius, inner_radius, phi_max } => {
                if d.z == 0.0 {
                    return None;
                }
                let t = (height - o.z) / d.z;
                if t <= 0.0 || t >= t_max {
                    return None;
                }
                let mut p = o + d * t;
                p.z = height;
                let r2 = p.x * p.x + p.y * p.y;
                if r2 > radius * radius || r2 < inner_radius * inner_radius || phi_of(p) > phi_max {
                    return None;
                }
                Some((t, p))
            }
            QuadricKind::Cylinder { radius: r, z_min, z_max, phi_max } => {
                let a = d.x * d.x + d.y * d.y;
                let b = 2.0 * (d.x * o.x + d.y * o.y);
                let c = o.x * o.x + o.y * o.y - r * r;
                let (t0, t1) = solve_quadratic(a, b, c)?;
                let accept = |t: f64| -> Option<DVec3> {
                    if t <= 0.0 || t >= t_max {
                        return None;
                    }
                    let mut p = o + d * t;
                    let h = (p.x * p.x + p.y * p.y).sqrt();
                    p.x *= r / h;
                    p.y *= r / h;
                    (p.z >= z_min && p.z <= z_max && phi_of(p) <= phi_max).then_some(p)
                };
                accept(t0).map(|p| (t0, p)).or_else(|| accept(t1).map(|p| (t1, p)))
            }
        }
    }

    /// Object-space bounding box (min, max).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match *self {
            QuadricKind::Sphere { radius: r, z_min, z_max, .. }
            | QuadricKind::Cylinder { radius: r, z_min, z_max, .. } => {
                (DVec3::new(-r, -r, z_min), DVec3::new(r, r, z_max))
            }
            QuadricKind::Disk { height, radius: r, .. } => (DVec3::new(-r, -r, height), DVec3::new(r, r, height)),
        }
    }

    /// Outward normal, ∂p/∂u, (u, v) and the absolute error bound of an object-space hit point.
    fn surface(&self, p: DVec3) -> (DVec3, DVec3, [f64; 2], DVec3) {
        let phi = phi_of(p);
        match *self {
            QuadricKind::Sphere { radius: r, z_min, z_max, phi_max } => {
                let theta = (p.z / r).clamp(-1.0, 1.0).acos();
                let (th0, th1) = ((z_min / r).clamp(-1.0, 1.0).acos(), (z_max / r).clamp(-1.0, 1.0).acos());
                let v = if th1 != th0 { (theta - th0) / (th1 - th0) } else { 0.0 };
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                (p / r, dpdu, [phi / phi_max, v], p.abs() * gamma(5) as f64)
            }
            QuadricKind::Disk { radius, inner_radius, phi_max, .. } => {
                let rh = (p.x * p.x + p.y * p.y).sqrt();
                let v = (radius - rh) / (radius - inner_radius);
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                (DVec3::Z, dpdu, [phi / phi_max, v], DVec3::ZERO)
            }
            QuadricKind::Cylinder { radius: r, z_min, z_max, phi_max } => {
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                let v = (p.z - z_min) / (z_max - z_min);
                (
                    DVec3::new(p.x / r, p.y / r, 0.0),
                    dpdu,
                    [phi / phi_max, v],
                    DVec3::new(p.x, p.y, 0.0).abs() * gamma(3) as f64,
                )
            }
        }
    }
}

impl Quadric {
    /// The first hit of world-space `ray` with t in (0, ray.t_max).
    pub fn intersect(&self, ray: &Ray) -> Option<QuadricHit> {
        let o = self.object_from_world.transform_point3a(ray.o);
        let d = self.object_from_world.transform_vector3a(ray.d);
        let (t, p) = self.kind.intersect(o.as_dvec3(), d.as_dvec3(), ray.t_max as f64)?;
        let t = t as f32;
        (t < ray.t_max && t > 0.0).then_some(QuadricHit { t, p })
    }

    /// World-space surface data at a hit.
    pub fn surface(&self, hit: &QuadricHit) -> QuadricSurface {
        let (n, dpdu, uv, err) = self.kind.surface(hit.p);
        let (p, p_error) =
            transform_point_with_error(&self.world_from_object, hit.p.as_vec3().into(), err.as_vec3().into());
        let mut n = transform_normal(&self.world_from_object, n.as_vec3().into());
        if self.flip_normal {
            n = -n;
        }
        QuadricSurface {
            p,
            p_error,
            n,
            dpdu: self.world_from_object.transform_vector3a(dpdu.as_vec3().into()),
            uv: [uv[0] as f32, uv[1] as f32],
        }
    }

    /// World-space bounding box (min, max) of the transformed object-space box.
    pub fn world_bounds(&self) -> (Vec3A, Vec3A) {
        let (lo, hi) = self.kind.bounds();
        transform_bounds(&self.world_from_object, lo.as_vec3().into(), hi.as_vec3().into())
    }
}

/// Transforms a point and its absolute error bound, adding the rounding error of the transform itself
/// (pbrt-v3 `Transform::operator()(Point3, Vector3, Vector3*)`).
pub fn transform_point_with_error(m: &Affine3A, p: Vec3A, err: Vec3A) -> (Vec3A, Vec3A) {
    let a = m.matrix3;
    let abs_cols = [a.x_axis.abs(), a.y_axis.abs(), a.z_axis.abs()];
    let g3 = gamma(3);
    let from_err = abs_cols[0] * err.x + abs_cols[1] * err.y + abs_cols[2] * err.z;
    let from_p = (a.x_axis * p.x).abs() + (a.y_axis * p.y).abs() + (a.z_axis * p.z).abs() + m.translation.abs();
    (m.transform_point3a(p), from_err * (g3 + 1.0) + from_p * g3)
}

/// Transforms a normal by the inverse transpose and normalises it.
pub fn transform_normal(m: &Affine3A, n: Vec3A) -> Vec3A {
    (m.matrix3.inverse().transpose() * n).normalize()
}

/// The axis-aligned box of the 8 transformed corners of (lo, hi).
pub fn transform_bounds(m: &Affine3A, lo: Vec3A, hi: Vec3A) -> (Vec3A, Vec3A) {
    let mut bmin = Vec3A::splat(f32::INFINITY);
    let mut bmax = Vec3A::splat(f32::NEG_INFINITY);
    for i in 0..8 {
        let c = Vec3A::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let w = m.transform_point3a(c);
        bmin = bmin.min(w);
        bmax = bmax.max(w);
    }
    (bmin, bmax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn placed(kind: QuadricKind, m: Affine3A) -> Quadric {
        Quadric { kind, world_from_object: m, object_from_world: m.inverse(), flip_normal: false }
    }

    #[test]
    fn sphere_hits_front_then_back_and_respects_cuts() {
        let s = placed(
            QuadricKind::Sphere { radius: 2.0, z_min: -2.0, z_max: 2.0, phi_max: TAU },
            Affine3A::from_translation(glam::Vec3::new(0.0, 0.0, 10.0)),
        );
        let h = s.intersect(&Ray::new(Vec3A::ZERO, Vec3A::Z)).unwrap();
        assert!((h.t - 8.0).abs() < 1e-5);
        let surf = s.surface(&h);
        assert!((surf.n - -Vec3A::Z).length() < 1e-4);
        // From inside, the far side.
        let h = s.intersect(&Ray::new(Vec3A::new(0.0, 0.0, 10.0), Vec3A::Z)).unwrap();
        assert!((h.t - 2.0).abs() < 1e-5);
        let cut = placed(QuadricKind::Sphere { radius: 2.0, z_min: 0.0, z_max: 2.0, phi_max: TAU }, Affine3A::IDENTITY);
        let h = cut.intersect(&Ray::new(Vec3A::new(0.0, 0.0, -5.0), Vec3A::Z)).unwrap();
        assert!((h.t - 7.0).abs() < 1e-5, "lower half removed: hit the top from inside");
    }

    #[test]
    fn rays_leaving_a_sphere_do_not_hit_it_again() {
        let s = placed(
            QuadricKind::Sphere { radius: 1.0, z_min: -1.0, z_max: 1.0, phi_max: TAU },
            Affine3A::from_translation(glam::Vec3::new(3.0, -2.0, 7.0)),
        );
        let mut misses = 0;
        for i in 0..500 {
            let a = i as f32 * 0.37;
            let dir = Vec3A::new(a.cos(), a.sin(), 0.3 * (a * 1.7).sin()).normalize();
            let from = Vec3A::new(3.0, -2.0, 7.0) - dir * 5.0;
            let h = s.intersect(&Ray::new(from, dir)).unwrap();
            let surf = s.surface(&h);
            let out = surf.n.dot(-dir).signum() * surf.n;
            let o = crate::scene::ray::offset_ray_origin(surf.p, surf.p_error, surf.n, out);
            let bounce = (out + Vec3A::new(0.1, -0.2, 0.05)).normalize();
            if s.intersect(&Ray::new(o, bounce)).is_none() {
                misses += 1;
            }
        }
        assert_eq!(misses, 500);
    }

    #[test]
    fn disk_and_cylinder() {
        let d =
            placed(QuadricKind::Disk { height: 1.0, radius: 2.0, inner_radius: 0.5, phi_max: TAU }, Affine3A::IDENTITY);
        assert!(d.intersect(&Ray::new(Vec3A::new(1.0, 0.0, 0.0), Vec3A::Z)).is_some());
        assert!(d.intersect(&Ray::new(Vec3A::new(0.2, 0.0, 0.0), Vec3A::Z)).is_none(), "hole");
        let c = placed(QuadricKind::Cylinder { radius: 1.0, z_min: 0.0, z_max: 1.0, phi_max: TAU }, Affine3A::IDENTITY);
        let h = c.intersect(&Ray::new(Vec3A::new(-5.0, 0.0, 0.5), Vec3A::X)).unwrap();
        assert!((h.t - 4.0).abs() < 1e-5);
        assert!(c.intersect(&Ray::new(Vec3A::new(-5.0, 0.0, 1.5), Vec3A::X)).is_none());
    }
}
