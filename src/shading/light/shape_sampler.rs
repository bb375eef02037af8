//! STAGE 5 (shading): sampling points on emitting analytic shapes. A full sphere under a similarity
//! transform seen from outside is sampled as pbrt-v3 does it, uniformly in the cone it subtends. Every
//! other case (inside the sphere, partial spheres, disks, cylinders, cones, paraboloids) samples the
//! shape's (z or r, φ) parameters with a known object-space area density and converts it exactly to world
//! area (|det M|·|M⁻ᵀn| for the placement M) and then to solid angle, so it stays exact where pbrt-v3 samples
//! only the full shape (its disk ignores the inner radius and φmax, its sphere the z cuts) or aborts
//! (cones, paraboloids). Hyperboloids are not sampled (see [`ShapeSampler::new`]).
//!
//! Depends on the scene's quadric type and glam; never on the renderer.

use std::f32::consts::PI;

use glam::{DVec3, Mat3A, Vec3A};

use super::area::SurfacePoint;
use crate::sampling::warp::concentric_disk;
use crate::scene::ray::{Ray, gamma, offset_ray_origin};
use crate::scene::shapes::quadric::{Quadric, QuadricKind};

/// How points on one analytic emitter are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeSampler {
    /// World-space sphere (centre, radius) when cone sampling applies from outside.
    sphere: Option<(Vec3A, f32)>,
    /// |det M| of the placement.
    det: f32,
    /// M⁻ᵀ for object normals.
    normal_matrix: Mat3A,
    /// World-space area (exact for similarity transforms; |det|^(2/3) × object area otherwise).
    area: f32,
    /// A disk's world-area density, the same at every point ([`ShapeSampler::area_density`] computed once).
    disk_density: Option<f32>,
}

/// Object-space area of a quadric (pbrt-v3's `Area`), or `None` for a hyperboloid.
fn object_area(kind: &QuadricKind) -> Option<f64> {
    Some(match *kind {
        QuadricKind::Sphere { radius, z_min, z_max, phi_max } => phi_max * radius * (z_max - z_min),
        QuadricKind::Disk { radius, inner_radius, phi_max, .. } => {
            phi_max * 0.5 * (radius * radius - inner_radius * inner_radius)
        }
        QuadricKind::Cylinder { radius, z_min, z_max, phi_max } => (z_max - z_min) * radius * phi_max,
        QuadricKind::Cone { height, radius, phi_max } => {
            radius * (height * height + radius * radius).sqrt() * phi_max / 2.0
        }
        QuadricKind::Paraboloid { radius, z_min, z_max, phi_max } => {
            // ∫ g(z) dz · φmax with g(z) = sqrt(R²z/zmax + R⁴/4zmax²) (see `object_density`).
            let (a, b) = (radius * radius / z_max, radius.powi(4) / (4.0 * z_max * z_max));
            let prim = |z: f64| (2.0 / (3.0 * a)) * (a * z + b).max(0.0).powf(1.5);
            phi_max * (prim(z_max) - prim(z_min)).abs()
        }
        QuadricKind::Hyperboloid { .. } => return None,
    })
}

/// The object-space normal direction at object point `p` (any length, outward before any flip).
fn object_normal(kind: &QuadricKind, p: DVec3) -> DVec3 {
    match *kind {
        QuadricKind::Sphere { .. } => p,
        QuadricKind::Disk { .. } => DVec3::Z,
        QuadricKind::Cylinder { .. } => DVec3::new(p.x, p.y, 0.0),
        QuadricKind::Cone { height, radius, .. } => {
            let k = (radius / height) * (radius / height);
            DVec3::new(p.x, p.y, k * (height - p.z))
        }
        QuadricKind::Paraboloid { radius, z_max, .. } => DVec3::new(p.x, p.y, -0.5 * radius * radius / z_max),
        QuadricKind::Hyperboloid { .. } => DVec3::Z,
    }
}

/// Object-space area density of [`sample_object`] at object point `p`.
fn object_density(kind: &QuadricKind, p: DVec3) -> f64 {
    match *kind {
        QuadricKind::Paraboloid { radius, z_min, z_max, phi_max } => {
            let g = (radius * radius * p.z / z_max + radius.powi(4) / (4.0 * z_max * z_max)).max(0.0).sqrt();
            1.0 / ((z_max - z_min).abs() * phi_max * g)
        }
        _ => object_area(kind).map_or(0.0, |a| 1.0 / a),
    }
}

/// An object-space point for sample `u` (uniform by area except the paraboloid: uniform in z and φ).
fn sample_object(kind: &QuadricKind, u: [f32; 2]) -> DVec3 {
    let (u0, u1) = (u[0] as f64, u[1] as f64);
    match *kind {
        QuadricKind::Sphere { radius, z_min, z_max, phi_max } => {
            let z = z_min + u0 * (z_max - z_min);
            let rho = (radius * radius - z * z).max(0.0).sqrt();
            let phi = u1 * phi_max;
            DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
        }
        QuadricKind::Disk { height, radius, inner_radius, phi_max } => {
            if inner_radius == 0.0 && phi_max >= std::f64::consts::TAU {
                let [x, y] = concentric_disk(u);
                DVec3::new(x as f64 * radius, y as f64 * radius, height)
            } else {
                let r = (inner_radius * inner_radius + u0 * (radius * radius - inner_radius * inner_radius)).sqrt();
                let phi = u1 * phi_max;
                DVec3::new(r * phi.cos(), r * phi.sin(), height)
            }
        }
        QuadricKind::Cylinder { radius, z_min, z_max, phi_max } => {
            let phi = u1 * phi_max;
            DVec3::new(radius * phi.cos(), radius * phi.sin(), z_min + u0 * (z_max - z_min))
        }
        QuadricKind::Cone { height, radius, phi_max } => {
            let v = u0.sqrt();
            let phi = u1 * phi_max;
            DVec3::new(radius * v * phi.cos(), radius * v * phi.sin(), height * (1.0 - v))
        }
        QuadricKind::Paraboloid { radius, z_min, z_max, phi_max } => {
            let z = z_min + u0 * (z_max - z_min);
            let rho = radius * (z / z_max).max(0.0).sqrt();
            let phi = u1 * phi_max;
            DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
        }
        QuadricKind::Hyperboloid { .. } => DVec3::ZERO,
    }
}

impl ShapeSampler {
    /// The sampler for `q`, or `None` for a hyperboloid (pbrt-v3 cannot sample it either).
    pub fn new(q: &Quadric) -> Option<Self> {
        let obj_area = object_area(&q.kind)? as f32;
        let m = q.world_from_object.matrix3;
        let det = m.determinant().abs();
        let (cx, cy, cz) = (m.x_axis, m.y_axis, m.z_axis);
        let s = cx.length();
        let similar = (cy.length() - s).abs() <= 1e-5 * s
            && (cz.length() - s).abs() <= 1e-5 * s
            && cx.dot(cy).abs() <= 1e-5 * s * s
            && cx.dot(cz).abs() <= 1e-5 * s * s
            && cy.dot(cz).abs() <= 1e-5 * s * s;
        let sphere = match q.kind {
            QuadricKind::Sphere { radius, z_min, z_max, phi_max }
                if similar && z_min <= -radius && z_max >= radius && phi_max >= std::f64::consts::TAU =>
            {
                Some((q.world_from_object.translation, radius as f32 * s))
            }
            _ => None,
        };
        let area = if similar { obj_area * s * s } else { obj_area * det.powf(2.0 / 3.0) };
        let mut s = ShapeSampler { sphere, det, normal_matrix: m.inverse().transpose(), area, disk_density: None };
        if matches!(q.kind, QuadricKind::Disk { .. }) {
            // A disk's object normal and density do not depend on the point.
            s.disk_density = Some(s.area_density(q, DVec3::ZERO));
        }
        Some(s)
    }

    /// World-space area (for the light's power).
    pub fn area(&self) -> f32 {
        self.area
    }

    /// World-area density of the parametric sampler at object point `p_obj`.
    fn area_density(&self, q: &Quadric, p_obj: DVec3) -> f32 {
        if let Some(d) = self.disk_density {
            return d;
        }
        let n = object_normal(&q.kind, p_obj).normalize_or_zero().as_vec3();
        let jac = self.det * (self.normal_matrix * Vec3A::from(n)).length();
        let d = object_density(&q.kind, p_obj) as f32 / jac;
        if d.is_finite() { d } else { 0.0 }
    }

    /// The world point for object point `p_obj` of `q`, with its error bound and pbrt-v3's normal.
    fn world_point(q: &Quadric, p_obj: DVec3) -> SurfacePoint {
        let (p, p_error, n) = q.surface_point(p_obj);
        SurfacePoint { p, p_error, n }
    }

    /// The cone about the sphere's centre seen from `p`: (unit axis toward the centre, distance,
    /// cos θmax, 1 − cos θmax) when `p` (offset as pbrt-v3 offsets it) is outside the sphere.
    #[inline]
    fn cone(&self, p: Vec3A, p_error: Vec3A, n: Vec3A) -> Option<(Vec3A, f32, f32, f32)> {
        let (c, r) = self.sphere?;
        let origin = offset_ray_origin(p, p_error, n, c - p);
        if origin.distance_squared(c) <= r * r {
            return None;
        }
        let dc = p.distance(c);
        let sin2 = (r / dc) * (r / dc);
        let cos_max = (1.0 - sin2).max(0.0).sqrt();
        Some(((c - p) / dc, dc, cos_max, sin2 / (1.0 + cos_max)))
    }

    /// A point on `q` for the reference point (p, p_error, n) and sample `u`, with the solid-angle pdf
    /// seen from p; `None` where the pdf is 0 or infinite.
    pub fn sample(&self, q: &Quadric, r: (Vec3A, Vec3A, Vec3A), u: [f32; 2]) -> Option<(SurfacePoint, f32)> {
        let (p, p_error, n) = r;
        if let Some((wc, dc, cos_max, one_minus)) = self.cone(p, p_error, n) {
            let (c, radius) = self.sphere?;
            let sin_max2 = 1.0 - cos_max * cos_max;
            let sin_max = (radius / dc).min(1.0);
            let (mut cos_t, mut sin2_t) = {
                let c = (cos_max - 1.0) * u[0] + 1.0;
                (c, 1.0 - c * c)
            };
            if sin_max2 < 0.000_685_23 {
                // Small cones: pbrt-v3's series form avoids the cancellation in 1 − cos².
                sin2_t = sin_max2 * u[0];
                cos_t = (1.0 - sin2_t).sqrt();
            }
            let inv_sin_max = 1.0 / sin_max;
            let cos_alpha = sin2_t * inv_sin_max + cos_t * (1.0 - sin2_t * inv_sin_max * inv_sin_max).max(0.0).sqrt();
            let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
            let phi = u[1] * 2.0 * PI;
            let f = crate::sampling::Frame::from_normal(-wc);
            let nw = f.to_world(Vec3A::new(sin_alpha * phi.cos(), sin_alpha * phi.sin(), cos_alpha));
            let pw = c + radius * nw;
            let pdf = 1.0 / (2.0 * PI * one_minus);
            let n_out = if q.flip_normal { -nw } else { nw };
            return pdf.is_finite().then_some((SurfacePoint { p: pw, p_error: pw.abs() * gamma(5), n: n_out }, pdf));
        }
        let p_obj = sample_object(&q.kind, u);
        let sp = Self::world_point(q, p_obj);
        let pdf = self.area_density(q, p_obj) * solid_angle_factor(p, &sp)?;
        (pdf.is_finite() && pdf > 0.0).then_some((sp, pdf))
    }

    /// A point on `q` from its parametric sampler with its world-area density (pbrt-v3's `Shape::Sample(u)`,
    /// where light paths start); `None` where the density is 0 or infinite.
    pub fn sample_area(&self, q: &Quadric, u: [f32; 2]) -> Option<(SurfacePoint, f32)> {
        let p_obj = sample_object(&q.kind, u);
        let pdf = self.area_density(q, p_obj);
        (pdf > 0.0 && pdf.is_finite()).then(|| (Self::world_point(q, p_obj), pdf))
    }

    /// The solid-angle pdf of [`ShapeSampler::sample`] from reference (p, p_error, n) toward a point `hit`
    /// on `q` (world position and normal).
    pub fn pdf_at(&self, q: &Quadric, r: (Vec3A, Vec3A, Vec3A), hit: &SurfacePoint) -> f32 {
        let (p, p_error, n) = r;
        if let Some((_, _, _, one_minus)) = self.cone(p, p_error, n) {
            let pdf = 1.0 / (2.0 * PI * one_minus);
            return if pdf.is_finite() { pdf } else { 0.0 };
        }
        let p_obj = q.object_from_world.transform_point3a(hit.p).as_dvec3();
        let pdf = self.area_density(q, p_obj) * solid_angle_factor(p, hit).unwrap_or(0.0);
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// The pdf toward direction `wi` from reference `r`: finds where the ray meets `q` (0 if it does not).
    pub fn pdf_dir(&self, q: &Quadric, r: (Vec3A, Vec3A, Vec3A), wi: Vec3A) -> f32 {
        let (p, p_error, n) = r;
        if let Some((wc, _, cos_max, one_minus)) = self.cone(p, p_error, n) {
            let pdf = 1.0 / (2.0 * PI * one_minus);
            return if wi.dot(wc) >= cos_max && pdf.is_finite() { pdf } else { 0.0 };
        }
        let ray = Ray::new(offset_ray_origin(p, p_error, n, wi), wi);
        match q.intersect(&ray) {
            Some(h) => {
                let (p, p_error, n) = q.hit_point(&h);
                self.pdf_at(q, r, &SurfacePoint { p, p_error, n })
            }
            None => 0.0,
        }
    }
}

/// d²/|cos θ'| from `p` to point `s`, converting an area density to solid angle (`None` when degenerate).
#[inline]
pub fn solid_angle_factor(p: Vec3A, s: &SurfacePoint) -> Option<f32> {
    let d = s.p - p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return None;
    }
    // d² / (|n·d| / d) written as d²·d / |n·d|: one division, and the square root no longer waits before it
    // (a light sample's density is on the path's critical chain). Equal up to rounding.
    let f = d2 * d2.sqrt() / s.n.dot(d).abs();
    f.is_finite().then_some(f)
}
