//! STAGE 5 (shading): pbrt-v3's `DiffuseAreaLight` on triangles — one light per triangle of an emitting
//! mesh, sampled uniformly by area (its `UniformSampleTriangle`), with the emission side pbrt-v3 gives the
//! triangle: the geometric normal faced to the interpolated shading normal when the mesh has normals,
//! else flipped by ReverseOrientation ⊕ a handedness-swapping transform (the same rule as the surface
//! interaction at a hit, so a sampled point and a hit point agree on which side emits).
//!
//! Depends on the scene's mesh type and glam; never on the renderer.

use glam::Vec3A;

use crate::scene::mesh::TriangleMesh;
use crate::scene::ray::{Ray, gamma};
use crate::shading::Spectrum;

/// A point on an emitter: position, its absolute error bound and the emitting-side normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// World position.
    pub p: Vec3A,
    /// Absolute error bound of `p`.
    pub p_error: Vec3A,
    /// Unit normal (pbrt-v3's `Interaction::n`: the side a one-sided emitter lights).
    pub n: Vec3A,
}

/// What an `AreaLightSource "diffuse"` emits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// Radiance L·scale.
    pub l: Spectrum,
    /// Whether both sides emit.
    pub two_sided: bool,
}

impl Emission {
    /// pbrt-v3 `DiffuseAreaLight::L`: the radiance leaving a point with normal `n` toward `w`.
    #[inline]
    pub fn l(&self, n: Vec3A, w: Vec3A) -> Spectrum {
        if self.two_sided || n.dot(w) > 0.0 { self.l } else { Spectrum::ZERO }
    }

    /// pbrt-v3 `DiffuseAreaLight::Power` for a shape of the given area.
    pub fn power(&self, area: f32) -> Spectrum {
        self.l * (if self.two_sided { 2.0 } else { 1.0 } * area * std::f32::consts::PI)
    }
}

/// Area of triangle `tri` of `mesh`.
pub fn triangle_area(mesh: &TriangleMesh, tri: usize) -> f32 {
    let [p0, p1, p2] = mesh.triangle(tri).map(Vec3A::from);
    0.5 * (p1 - p0).cross(p2 - p0).length()
}

/// The unit normal of triangle `tri`'s plane, (p1 − p0) × (p2 − p0) normalised (zero when degenerate); lights
/// compute it once and pass it to [`sample_triangle`] and [`intersect_triangle`].
#[inline]
pub fn face_normal(mesh: &TriangleMesh, tri: usize) -> Vec3A {
    let [p0, p1, p2] = mesh.triangle(tri).map(Vec3A::from);
    (p1 - p0).cross(p2 - p0).normalize_or_zero()
}

/// The emitting-side normal at barycentrics (b0, b1) of triangle `tri` with face normal `n` (pbrt-v3's rule,
/// see the module doc).
#[inline]
fn triangle_normal(mesh: &TriangleMesh, tri: usize, n: Vec3A, b0: f32, b1: f32) -> Vec3A {
    if !mesh.normals.is_empty() {
        let idx = &mesh.indices[3 * tri..3 * tri + 3];
        let v = |k: usize| Vec3A::from(mesh.normals[idx[k] as usize]);
        let ns = v(0) * b0 + v(1) * b1 + v(2) * (1.0 - b0 - b1);
        if n.dot(ns) < 0.0 { -n } else { n }
    } else if mesh.flip_normals {
        -n
    } else {
        n
    }
}

/// A point uniformly distributed by area on triangle `tri` for sample `u` (pdf = 1/area).
#[inline]
pub fn sample_triangle(mesh: &TriangleMesh, tri: usize, n: Vec3A, u: [f32; 2]) -> SurfacePoint {
    let v = mesh.triangle(tri).map(Vec3A::from);
    let (p, n, [b0, b1, b2]) = triangle_point(mesh, tri, v, n, u);
    let abs_sum = (b0 * v[0]).abs() + (b1 * v[1]).abs() + (b2 * v[2]).abs();
    SurfacePoint { p, p_error: abs_sum * gamma(6), n }
}

/// [`sample_triangle`] without the error bound, for a triangle whose vertices `v` the caller has fetched:
/// the point, its emitting-side normal and its barycentrics.
#[inline]
pub fn triangle_point(
    mesh: &TriangleMesh,
    tri: usize,
    v: [Vec3A; 3],
    n: Vec3A,
    u: [f32; 2],
) -> (Vec3A, Vec3A, [f32; 3]) {
    let su0 = u[0].sqrt();
    let (b0, b1) = (1.0 - su0, u[1] * su0);
    let b2 = 1.0 - b0 - b1;
    let p = b0 * v[0] + b1 * v[1] + b2 * v[2];
    (p, triangle_normal(mesh, tri, n, b0, b1), [b0, b1, b2])
}

/// Where `ray` first crosses triangle `tri` (either side), with the emitting-side normal there.
#[inline]
pub fn intersect_triangle(mesh: &TriangleMesh, tri: usize, n: Vec3A, ray: &Ray) -> Option<SurfacePoint> {
    let [p0, p1, p2] = mesh.triangle(tri).map(Vec3A::from);
    let (e1, e2) = (p1 - p0, p2 - p0);
    let pv = ray.d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.o - p0;
    let b1 = tv.dot(pv) * inv;
    let qv = tv.cross(e1);
    let b2 = ray.d.dot(qv) * inv;
    if b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    if !(t > 0.0 && t < ray.t_max) {
        return None;
    }
    let b0 = 1.0 - b1 - b2;
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    Some(SurfacePoint { p, p_error: Vec3A::ZERO, n: triangle_normal(mesh, tri, n, b0, b1) })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_tri(normals: bool, flip: bool) -> TriangleMesh {
        TriangleMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: if normals { vec![[0.0, 0.0, -1.0]; 3] } else { vec![] },
            indices: vec![0, 1, 2],
            flip_normals: flip,
            ..Default::default()
        }
    }

    #[test]
    fn samples_stay_on_the_triangle_and_face_the_stated_side() {
        let m = quad_tri(false, false);
        assert!((triangle_area(&m, 0) - 0.5).abs() < 1e-6);
        for i in 0..50 {
            let s = sample_triangle(&m, 0, face_normal(&m, 0), [(i as f32 + 0.5) / 50.0, ((i * 7) % 50) as f32 / 50.0]);
            assert!(s.p.z == 0.0 && s.p.x >= 0.0 && s.p.y >= 0.0 && s.p.x + s.p.y <= 1.0 + 1e-6);
            assert_eq!(s.n, Vec3A::Z);
        }
        assert_eq!(
            sample_triangle(&quad_tri(false, true), 0, face_normal(&quad_tri(false, true), 0), [0.3, 0.3]).n,
            -Vec3A::Z
        );
        // With normals, the normals decide (and ReverseOrientation does not), as in pbrt-v3.
        assert_eq!(
            sample_triangle(&quad_tri(true, false), 0, face_normal(&quad_tri(true, false), 0), [0.3, 0.3]).n,
            -Vec3A::Z
        );
        assert_eq!(
            sample_triangle(&quad_tri(true, true), 0, face_normal(&quad_tri(true, true), 0), [0.3, 0.3]).n,
            -Vec3A::Z
        );
    }

    #[test]
    fn rays_find_the_triangle_from_both_sides() {
        let m = quad_tri(false, false);
        let r = Ray::new(Vec3A::new(0.2, 0.2, 1.0), -Vec3A::Z);
        let h = intersect_triangle(&m, 0, face_normal(&m, 0), &r).unwrap();
        assert!((h.p - Vec3A::new(0.2, 0.2, 0.0)).length() < 1e-6);
        let r = Ray::new(Vec3A::new(0.2, 0.2, -1.0), Vec3A::Z);
        assert!(intersect_triangle(&m, 0, face_normal(&m, 0), &r).is_some());
        let r = Ray::new(Vec3A::new(0.8, 0.8, 1.0), -Vec3A::Z);
        assert!(intersect_triangle(&m, 0, face_normal(&m, 0), &r).is_none());
    }
}
