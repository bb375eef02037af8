//! STAGE 2 (scene): pbrt-v3's analytic shapes — sphere, disk, cylinder, cone, paraboloid, hyperboloid —
//! intersected exactly in object space, not tessellated: ambient occlusion next to a sphere depends on its
//! true curvature. Each shape's implicit equation, clipping (z range, φ ≤ φmax) and normal orientation
//! (pbrt-v3's `cross(∂p/∂u, ∂p/∂v)`) follow pbrt-v3's `src/shapes/*.cpp`.
//!
//! Sphere, disk and cylinder are solved in f64 (so a ray leaving the surface never re-hits it at t ≈ 0).
//! Cone, paraboloid and hyperboloid are solved as pbrt-v3 solves them, in f32 interval arithmetic (its
//! `EFloat`), with its error bounds for the hit point: pbrt-v3's hyperboloid fit can give a surface its
//! own normal does not fit, and only the same root rejection reproduces its images there.
//! [`QuadricKind::intersect`] is the plain f64 solution of all six (the unit tests check the two agree).
//!
//! Depends only on the ray and glam, never on the scene builder or renderer.

use glam::{Affine3A, DVec3, Mat3A, Vec3A};

use crate::scene::ray::{Ray, gamma};
use crate::scene::shapes::efloat::{EFloat, efloat_quadratic};
use crate::scene::transform::{transform_bounds, transform_point_with_error};

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
    /// Cone with its base circle of `radius` at z = 0 and its apex at z = `height`, φ ∈ [0, phi_max].
    Cone {
        /// Height of the apex (positive).
        height: f64,
        /// Radius at z = 0.
        radius: f64,
        /// Sweep angle in radians.
        phi_max: f64,
    },
    /// Paraboloid z = z_max·(x² + y²)/radius² (radius `radius` at z = z_max), cut to z ∈ [z_min, z_max] and
    /// φ ∈ [0, phi_max].
    Paraboloid {
        /// Radius at z = z_max.
        radius: f64,
        /// Lower z cut.
        z_min: f64,
        /// Upper z cut (also sets the curvature; never 0).
        z_max: f64,
        /// Sweep angle in radians.
        phi_max: f64,
    },
    /// Hyperboloid ah·(x² + y²) − ch·z² = 1 swept by the line p1–p2 around z, φ ∈ [0, phi_max] measured from
    /// the line (pbrt-v3's `Hyperboloid`; build it with [`QuadricKind::hyperboloid`]).
    Hyperboloid {
        /// First end of the line (pbrt-v3 swaps the ends when p2.z = 0).
        p1: DVec3,
        /// Second end of the line.
        p2: DVec3,
        /// Largest distance of p1/p2 from the axis.
        r_max: f64,
        /// Lower z.
        z_min: f64,
        /// Upper z.
        z_max: f64,
        /// Coefficient of x² + y².
        ah: f64,
        /// Coefficient of z².
        ch: f64,
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
    /// Object → world for normals: the inverse transpose of `world_from_object`'s linear part.
    pub normal_from_object: Mat3A,
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
    /// Object-space error bound of `p` when the intersection computed one (cone, paraboloid, hyperboloid:
    /// pbrt-v3's interval bound of o + t·d); zero for the shapes whose bound comes from `p` alone.
    pub p_error: Vec3A,
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

/// Roots of a·t² + b·t + c with a = 0 allowed: a ray parallel to a cone's side or a paraboloid's axis
/// meets it once (pbrt-v3's `Quadratic` gives that root and an infinite one).
fn solve_quadratic_or_linear(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    if a == 0.0 {
        return (b != 0.0).then(|| (-c / b, f64::INFINITY));
    }
    solve_quadratic(a, b, c)
}

/// pbrt-v3's choice between the two roots: the nearer one in (0, t_max) whose point `accept` keeps, else
/// the farther one.
fn nearest_kept(
    (t0, t1): (f64, f64),
    t_max: f64,
    accept: impl Fn(DVec3) -> bool,
    at: impl Fn(f64) -> DVec3,
) -> Option<(f64, DVec3)> {
    [t0, t1].into_iter().filter(|&t| t > 0.0 && t < t_max).map(|t| (t, at(t))).find(|&(_, p)| accept(p))
}

/// pbrt-v3's hyperboloid φ: the angle of `p` around z measured from the point of the line p1–p2 at the
/// same height, in [0, 2π).
fn hyperboloid_phi(p: DVec3, p1: DVec3, p2: DVec3) -> f64 {
    let v = (p.z - p1.z) / (p2.z - p1.z);
    let pr = p1.lerp(p2, v);
    let phi = (pr.x * p.y - p.x * pr.y).atan2(p.x * pr.x + p.y * pr.y);
    if phi < 0.0 { phi + std::f64::consts::TAU } else { phi }
}

impl QuadricKind {
    /// pbrt-v3's hyperboloid through the line `p1`–`p2` (its constructor: radii, z range, and the implicit
    /// coefficients fitted in f32 through p2 and a point further along the line). `None` where pbrt-v3 finds
    /// no finite coefficients (its loop would never end, e.g. a line through the axis, or p1.z = p2.z) or the
    /// line is degenerate.
    pub fn hyperboloid(p1: [f64; 3], p2: [f64; 3], phi_max: f64) -> Option<QuadricKind> {
        let (a, b) = (DVec3::from(p1), DVec3::from(p2));
        if a == b || a.z == b.z || !a.is_finite() || !b.is_finite() {
            return None;
        }
        let r_max = a.truncate().length().max(b.truncate().length());
        let (z_min, z_max) = (a.z.min(b.z), a.z.max(b.z));
        let (p1, p2) = if b.z == 0.0 { (b, a) } else { (a, b) };
        // The fit in pbrt-v3's f32 arithmetic, so the same lines fail and the same coefficients come out.
        let (q1, q2) = (p1.as_vec3(), p2.as_vec3());
        let mut pp = q1;
        for _ in 0..64 {
            pp += 2.0 * (q2 - q1);
            let xy1 = pp.x * pp.x + pp.y * pp.y;
            let xy2 = q2.x * q2.x + q2.y * q2.y;
            let ah =
                (1.0 / xy1 - (pp.z * pp.z) / (xy1 * q2.z * q2.z)) / (1.0 - (xy2 * pp.z * pp.z) / (xy1 * q2.z * q2.z));
            let ch = (ah * xy2 - 1.0) / (q2.z * q2.z);
            if ah.is_finite() && ch.is_finite() {
                return Some(QuadricKind::Hyperboloid {
                    p1,
                    p2,
                    r_max,
                    z_min,
                    z_max,
                    ah: ah as f64,
                    ch: ch as f64,
                    phi_max,
                });
            }
        }
        None
    }

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
            QuadricKind::Cone { height: h, radius: r, phi_max } => {
                let k = (r / h) * (r / h);
                let a = d.x * d.x + d.y * d.y - k * d.z * d.z;
                let b = 2.0 * (d.x * o.x + d.y * o.y - k * d.z * (o.z - h));
                let c = o.x * o.x + o.y * o.y - k * (o.z - h) * (o.z - h);
                let roots = solve_quadratic_or_linear(a, b, c)?;
                nearest_kept(roots, t_max, |p| p.z >= 0.0 && p.z <= h && phi_of(p) <= phi_max, |t| o + d * t)
            }
            QuadricKind::Paraboloid { radius: r, z_min, z_max, phi_max } => {
                let k = z_max / (r * r);
                let a = k * (d.x * d.x + d.y * d.y);
                let b = 2.0 * k * (d.x * o.x + d.y * o.y) - d.z;
                let c = k * (o.x * o.x + o.y * o.y) - o.z;
                let roots = solve_quadratic_or_linear(a, b, c)?;
                nearest_kept(roots, t_max, |p| p.z >= z_min && p.z <= z_max && phi_of(p) <= phi_max, |t| o + d * t)
            }
            QuadricKind::Hyperboloid { p1, p2, z_min, z_max, ah, ch, phi_max, .. } => {
                let a = ah * (d.x * d.x + d.y * d.y) - ch * d.z * d.z;
                let b = 2.0 * (ah * (d.x * o.x + d.y * o.y) - ch * d.z * o.z);
                let c = ah * (o.x * o.x + o.y * o.y) - ch * o.z * o.z - 1.0;
                let roots = solve_quadratic_or_linear(a, b, c)?;
                let keep = |p: DVec3| p.z >= z_min && p.z <= z_max && hyperboloid_phi(p, p1, p2) <= phi_max;
                nearest_kept(roots, t_max, keep, |t| o + d * t)
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
            QuadricKind::Cone { height, radius: r, .. } => (DVec3::new(-r, -r, 0.0), DVec3::new(r, r, height)),
            QuadricKind::Paraboloid { radius: r, z_min, z_max, .. } => {
                (DVec3::new(-r, -r, z_min), DVec3::new(r, r, z_max))
            }
            QuadricKind::Hyperboloid { r_max: r, z_min, z_max, .. } => {
                (DVec3::new(-r, -r, z_min), DVec3::new(r, r, z_max))
            }
        }
    }

    /// Outward normal, ∂p/∂u, (u, v) and the absolute error bound of an object-space hit point.
    ///
    /// Without `want_uv` the (u, v) returned are 0: sampling a point on a light needs only its position and
    /// normal, and φ (an atan2) and the sphere's θ (three acos) were most of the cost of each sample.
    fn surface(&self, p: DVec3, want_uv: bool) -> (DVec3, DVec3, [f64; 2], DVec3) {
        let phi = if want_uv { phi_of(p) } else { 0.0 };
        match *self {
            QuadricKind::Sphere { radius: r, z_min, z_max, phi_max } => {
                let v = if want_uv {
                    let theta = (p.z / r).clamp(-1.0, 1.0).acos();
                    let (th0, th1) = ((z_min / r).clamp(-1.0, 1.0).acos(), (z_max / r).clamp(-1.0, 1.0).acos());
                    if th1 != th0 { (theta - th0) / (th1 - th0) } else { 0.0 }
                } else {
                    0.0
                };
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                (p / r, dpdu, [phi / phi_max, v], p.abs() * gamma(5) as f64)
            }
            QuadricKind::Disk { radius, inner_radius, phi_max, .. } => {
                let v = if want_uv { (radius - (p.x * p.x + p.y * p.y).sqrt()) / (radius - inner_radius) } else { 0.0 };
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
            // The three below: the error bound used is the intersection's (pbrt-v3's interval bound of
            // o + t·d, in `QuadricHit::p_error`); γ(5)·|p| is only the fallback for an f64 hit.
            QuadricKind::Cone { height: h, radius: r, phi_max } => {
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                // cross(∂p/∂u, ∂p/∂v) = φmax·h·(x, y, k·(h − z)): outward, defined up to the apex.
                let k = (r / h) * (r / h);
                let n = DVec3::new(p.x, p.y, k * (h - p.z)).try_normalize().unwrap_or(DVec3::Z);
                (n, dpdu, [phi / phi_max, p.z / h], p.abs() * gamma(5) as f64)
            }
            QuadricKind::Paraboloid { radius: r, z_min, z_max, phi_max } => {
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                // cross(∂p/∂u, ∂p/∂v) = φmax·(z_max − z_min)·(x, y, −(x² + y²)/2z), and on the surface
                // (x² + y²)/z = 1/k: (x, y, −1/2k), defined at the apex too.
                let k = z_max / (r * r);
                let n = DVec3::new(p.x, p.y, -0.5 / k).try_normalize().unwrap_or(-DVec3::Z);
                let v = if z_max > z_min { (p.z - z_min) / (z_max - z_min) } else { 0.0 };
                (n, dpdu, [phi / phi_max, v], p.abs() * gamma(5) as f64)
            }
            QuadricKind::Hyperboloid { p1, p2, ah, ch, phi_max, .. } => {
                let phi = hyperboloid_phi(p, p1, p2);
                let v = (p.z - p1.z) / (p2.z - p1.z);
                let (sin, cos) = phi.sin_cos();
                let dpdu = DVec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
                let e = p2 - p1;
                let dpdv = DVec3::new(e.x * cos - e.y * sin, e.x * sin + e.y * cos, e.z);
                // pbrt-v3's orientation; where ∂p/∂u vanishes (on the axis, or φmax = 0) the implicit
                // gradient gives the line of the normal and ∂p/∂v × ẑ its side.
                let n = dpdu.cross(dpdv).try_normalize().unwrap_or_else(|| {
                    let g = DVec3::new(ah * p.x, ah * p.y, -ch * p.z);
                    let side = DVec3::Z.cross(dpdv).dot(g).signum();
                    (g * side).try_normalize().unwrap_or(DVec3::Z)
                });
                (n, dpdu, [phi / phi_max, v], p.abs() * gamma(5) as f64)
            }
        }
    }

    /// The interval coefficients (a, b, c) of a·t² + b·t + c = 0 for the object-space ray o + t·d, as pbrt-v3
    /// computes them for the shapes it solves in interval arithmetic (cone, paraboloid, hyperboloid; `None`
    /// for the others).
    fn efloat_coefficients(&self, o: [EFloat; 3], d: [EFloat; 3]) -> Option<(EFloat, EFloat, EFloat)> {
        let ([ox, oy, oz], [dx, dy, dz]) = (o, d);
        let two = EFloat::exact(2.0);
        Some(match *self {
            QuadricKind::Cone { height, radius, .. } => {
                let h = EFloat::exact(height as f32);
                let k = EFloat::exact(radius as f32) / h;
                let k = k * k;
                (
                    dx * dx + dy * dy - k * dz * dz,
                    two * (dx * ox + dy * oy - k * dz * (oz - h)),
                    ox * ox + oy * oy - k * (oz - h) * (oz - h),
                )
            }
            QuadricKind::Paraboloid { radius, z_max, .. } => {
                let r = EFloat::exact(radius as f32);
                let k = EFloat::exact(z_max as f32) / (r * r);
                (k * (dx * dx + dy * dy), two * k * (dx * ox + dy * oy) - dz, k * (ox * ox + oy * oy) - oz)
            }
            QuadricKind::Hyperboloid { ah, ch, .. } => {
                let (ah, ch) = (EFloat::exact(ah as f32), EFloat::exact(ch as f32));
                (
                    ah * dx * dx + ah * dy * dy - ch * dz * dz,
                    two * (ah * dx * ox + ah * dy * oy - ch * dz * oz),
                    ah * ox * ox + ah * oy * oy - ch * oz * oz - EFloat::exact(1.0),
                )
            }
            _ => return None,
        })
    }

    /// Whether pbrt-v3 keeps the object-space hit `p` of a cone, paraboloid or hyperboloid: inside its z range
    /// and φ ≤ φmax (false for the other shapes).
    fn kept_as_pbrt_v3(&self, p: DVec3) -> bool {
        match *self {
            QuadricKind::Cone { height, phi_max, .. } => p.z >= 0.0 && p.z <= height && phi_of(p) <= phi_max,
            QuadricKind::Paraboloid { z_min, z_max, phi_max, .. } => {
                p.z >= z_min && p.z <= z_max && phi_of(p) <= phi_max
            }
            QuadricKind::Hyperboloid { p1, p2, z_min, z_max, phi_max, .. } => {
                p.z >= z_min && p.z <= z_max && hyperboloid_phi(p, p1, p2) <= phi_max
            }
            _ => false,
        }
    }
}

impl Quadric {
    /// The first hit of world-space `ray` with t in (0, ray.t_max).
    pub fn intersect(&self, ray: &Ray) -> Option<QuadricHit> {
        if matches!(
            self.kind,
            QuadricKind::Cone { .. } | QuadricKind::Paraboloid { .. } | QuadricKind::Hyperboloid { .. }
        ) {
            return self.intersect_as_pbrt_v3(ray);
        }
        let o = self.object_from_world.transform_point3a(ray.o);
        let d = self.object_from_world.transform_vector3a(ray.d);
        let (t, p) = self.kind.intersect(o.as_dvec3(), d.as_dvec3(), ray.t_max as f64)?;
        let t = t as f32;
        (t < ray.t_max && t > 0.0).then_some(QuadricHit { t, p, p_error: Vec3A::ZERO })
    }

    /// Cone, paraboloid and hyperboloid exactly as pbrt-v3 intersects them: in f32 interval arithmetic
    /// (`EFloat`) on the object-space ray with the transform's rounding error, keeping a root only where its
    /// whole interval is past 0. The hyperboloid needs this: pbrt-v3's fit can make a surface the
    /// line p1–p2 does not lie on, whose pbrt-v3 normal is not the surface's, so rays leaving it cross
    /// it again right away unless the crossing is within the root's error interval, as pbrt-v3 rejects it.
    fn intersect_as_pbrt_v3(&self, ray: &Ray) -> Option<QuadricHit> {
        let m = &self.object_from_world;
        let o = m.transform_point3a(ray.o);
        let d = m.transform_vector3a(ray.d);
        let cols = [m.matrix3.x_axis.abs(), m.matrix3.y_axis.abs(), m.matrix3.z_axis.abs()];
        let g3 = gamma(3);
        let o_err =
            (cols[0] * ray.o.x.abs() + cols[1] * ray.o.y.abs() + cols[2] * ray.o.z.abs() + m.translation.abs()) * g3;
        let d_err = (cols[0] * ray.d.x.abs() + cols[1] * ray.d.y.abs() + cols[2] * ray.d.z.abs()) * g3;
        // pbrt-v3 moves the origin to the far edge of its error box along d.
        let len2 = d.length_squared();
        let o = if len2 > 0.0 { o + d * (d.abs().dot(o_err) / len2) } else { o };
        let (ox, oy, oz) = (EFloat::new(o.x, o_err.x), EFloat::new(o.y, o_err.y), EFloat::new(o.z, o_err.z));
        let (dx, dy, dz) = (EFloat::new(d.x, d_err.x), EFloat::new(d.y, d_err.y), EFloat::new(d.z, d_err.z));
        let (a, b, c) = self.kind.efloat_coefficients([ox, oy, oz], [dx, dy, dz])?;
        let (t0, t1) = efloat_quadratic(a, b, c)?;
        let t_max = ray.t_max;
        if t0.high > t_max || t1.low <= 0.0 {
            return None;
        }
        let keep = |p: Vec3A| self.kind.kept_as_pbrt_v3(p.as_dvec3());
        let mut t = t0;
        if t.low <= 0.0 {
            t = t1;
            if t.high > t_max {
                return None;
            }
        }
        let mut p = o + d * t.v;
        if !keep(p) {
            if t.v == t1.v {
                return None;
            }
            t = t1;
            if t1.high > t_max {
                return None;
            }
            p = o + d * t.v;
            if !keep(p) {
                return None;
            }
        }
        let err = |o: EFloat, d: EFloat| (o + t * d).abs_error();
        let p_error = Vec3A::new(err(ox, dx), err(oy, dy), err(oz, dz));
        (t.v > 0.0 && t.v < t_max).then_some(QuadricHit { t: t.v, p: p.as_dvec3(), p_error })
    }

    /// A quadric placed by `world_from_object`; `flip_normal` as the field says.
    pub fn new(kind: QuadricKind, world_from_object: Affine3A, flip_normal: bool) -> Quadric {
        let object_from_world = world_from_object.inverse();
        let normal_from_object = world_from_object.matrix3.inverse().transpose();
        Quadric { kind, world_from_object, object_from_world, normal_from_object, flip_normal }
    }

    /// World-space surface data at a hit.
    pub fn surface(&self, hit: &QuadricHit) -> QuadricSurface {
        self.surface_at(hit, true)
    }

    /// World-space position, error bound and normal of the object-space surface point `p`: what sampling a
    /// point on an emitting quadric needs, [`Quadric::surface`] without computing (u, v).
    pub fn surface_point(&self, p: DVec3) -> (Vec3A, Vec3A, Vec3A) {
        self.hit_point(&QuadricHit { t: 0.0, p, p_error: Vec3A::ZERO })
    }

    /// [`Quadric::surface_point`] of a hit (keeping the hit's own error bound where it has one): what a
    /// light's density toward a direction that meets it needs.
    pub fn hit_point(&self, hit: &QuadricHit) -> (Vec3A, Vec3A, Vec3A) {
        let s = self.surface_at(hit, false);
        (s.p, s.p_error, s.n)
    }

    #[inline]
    fn surface_at(&self, hit: &QuadricHit, want_uv: bool) -> QuadricSurface {
        let (n, dpdu, uv, err) = self.kind.surface(hit.p, want_uv);
        let err = if hit.p_error == Vec3A::ZERO { err } else { hit.p_error.as_dvec3() };
        let (p, p_error) =
            transform_point_with_error(&self.world_from_object, hit.p.as_vec3().into(), err.as_vec3().into());
        // transform_normal with the inverse transpose made once, at construction.
        let mut n = (self.normal_from_object * Vec3A::from(n.as_vec3())).normalize();
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn placed(kind: QuadricKind, m: Affine3A) -> Quadric {
        Quadric::new(kind, m, false)
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

    fn cone(phi_deg: f64) -> QuadricKind {
        QuadricKind::Cone { height: 1.0, radius: 1.0, phi_max: phi_deg.to_radians() }
    }

    fn paraboloid(phi_deg: f64) -> QuadricKind {
        QuadricKind::Paraboloid { radius: 1.0, z_min: 0.0, z_max: 1.0, phi_max: phi_deg.to_radians() }
    }

    /// The line (1, −1, −1)–(1, 1, 1) sweeps x² + y² − z² = 1.
    fn hyperboloid(phi_deg: f64) -> QuadricKind {
        QuadricKind::hyperboloid([1.0, -1.0, -1.0], [1.0, 1.0, 1.0], phi_deg.to_radians()).unwrap()
    }

    fn hit_and_normal(kind: QuadricKind, o: [f32; 3], d: [f32; 3], t: f32, n: [f32; 3]) {
        let q = placed(kind, Affine3A::IDENTITY);
        let h = q.intersect(&Ray::new(Vec3A::from(o), Vec3A::from(d))).unwrap();
        assert!((h.t - t).abs() < 1e-5, "{kind:?}: t {} vs {t}", h.t);
        let s = q.surface(&h);
        assert!((s.n - Vec3A::from(n).normalize()).length() < 1e-4, "{kind:?}: n {:?} vs {n:?}", s.n);
        assert!(s.dpdu.dot(s.n).abs() < 1e-4);
    }

    #[test]
    fn cone_hits_and_normals() {
        // Radius 0.5 at z = 0.5; the normal (x, y, k(h − z)) leans up.
        hit_and_normal(cone(360.0), [-5.0, 0.0, 0.5], [1.0, 0.0, 0.0], 4.5, [-1.0, 0.0, 1.0]);
        // Straight down at ρ = 0.3√2: z = 1 − ρ.
        let down = Ray::new(Vec3A::new(0.3, -0.3, 5.0), -Vec3A::Z);
        let h = placed(cone(360.0), Affine3A::IDENTITY).intersect(&down).unwrap();
        assert!((h.t as f64 - (4.0 + 0.3 * 2f64.sqrt())).abs() < 1e-5);
        assert!(placed(cone(270.0), Affine3A::IDENTITY).intersect(&down).is_none(), "φ = 315° is in the gap");
        // Above the apex the other nappe is cut away.
        assert!(
            placed(cone(360.0), Affine3A::IDENTITY)
                .intersect(&Ray::new(Vec3A::new(-5.0, 0.0, 1.5), Vec3A::X))
                .is_none()
        );
    }

    #[test]
    fn paraboloid_hits_and_normals() {
        // z = x² + y²; a ray along the axis is the linear case (a = 0).
        hit_and_normal(paraboloid(360.0), [0.5, 0.0, 5.0], [0.0, 0.0, -1.0], 4.75, [1.0, 0.0, -1.0]);
        hit_and_normal(paraboloid(360.0), [-5.0, 0.0, 0.25], [1.0, 0.0, 0.0], 4.5, [-1.0, 0.0, -1.0]);
        let down = Ray::new(Vec3A::new(0.3, -0.3, 5.0), -Vec3A::Z);
        assert!(placed(paraboloid(360.0), Affine3A::IDENTITY).intersect(&down).is_some());
        assert!(placed(paraboloid(270.0), Affine3A::IDENTITY).intersect(&down).is_none(), "gap");
        // Above z_max: nothing.
        assert!(
            placed(paraboloid(360.0), Affine3A::IDENTITY)
                .intersect(&Ray::new(Vec3A::new(-5.0, 0.0, 1.5), Vec3A::X))
                .is_none()
        );
    }

    #[test]
    fn hyperboloid_fit_hits_and_normals() {
        let QuadricKind::Hyperboloid { ah, ch, r_max, z_min, z_max, .. } = hyperboloid(360.0) else { panic!() };
        assert!((ah - 1.0).abs() < 1e-6 && (ch - 1.0).abs() < 1e-6, "ah {ah} ch {ch}");
        assert!((r_max - 2f64.sqrt()).abs() < 1e-12 && z_min == -1.0 && z_max == 1.0);
        hit_and_normal(hyperboloid(360.0), [-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], 4.0, [-1.0, 0.0, 0.0]);
        // At z = 0.75 the radius is 1.25; the normal is (ah·x, ah·y, −ch·z).
        hit_and_normal(hyperboloid(360.0), [-5.0, 0.0, 0.75], [1.0, 0.0, 0.0], 3.75, [-1.25, 0.0, -0.75]);
        // φ is measured from the line: (−1, 0, 0) is at 180°, outside φmax = 90°, so the ray goes through to
        // the inside of (1, 0, 0) at φ = 0.
        let q = placed(hyperboloid(90.0), Affine3A::IDENTITY);
        let h = q.intersect(&Ray::new(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X)).unwrap();
        assert!((h.t - 6.0).abs() < 1e-5);
        // (0, −1, 0) is at 270° and (0, 1, 0) at 90°: both cut by φmax = 80°.
        let q = placed(hyperboloid(80.0), Affine3A::IDENTITY);
        assert!(q.intersect(&Ray::new(Vec3A::new(0.0, -5.0, 0.0), Vec3A::Y)).is_none());
    }

    #[test]
    fn degenerate_hyperboloids_are_refused() {
        // pbrt-v3 loops forever on its own defaults (a line through the axis) and on p1.z = p2.z.
        assert!(QuadricKind::hyperboloid([0.0; 3], [1.0, 1.0, 1.0], TAU).is_none());
        assert!(QuadricKind::hyperboloid([1.0, 0.0, 1.0], [0.0, 1.0, 1.0], TAU).is_none());
        assert!(QuadricKind::hyperboloid([1.0, 0.0, 1.0], [1.0, 0.0, 1.0], TAU).is_none());
        // hackmad's all-shapes hyperboloids are fine.
        assert!(QuadricKind::hyperboloid([3.0, 1.2, 1.0], [0.65, -0.5, -1.0], TAU).is_some());
        // p2.z = 0: pbrt-v3 swaps the ends.
        let Some(QuadricKind::Hyperboloid { p1, .. }) =
            QuadricKind::hyperboloid([1.0, -1.0, -1.0], [1.0, 0.0, 0.0], TAU)
        else {
            panic!()
        };
        assert_eq!(p1, DVec3::new(1.0, 0.0, 0.0));
    }

    /// Rays from all around at a placed shape: every hit lies in the object-space bounds, and a ray leaving
    /// the surface (offset as pbrt-v3's SpawnRay does) never hits it again right away.
    fn leaving_rays_do_not_rehit(kind: QuadricKind, check_rehit: bool) {
        let m = Affine3A::from_translation(glam::Vec3::new(3.0, -2.0, 7.0))
            * Affine3A::from_axis_angle(glam::Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7)
            * Affine3A::from_scale(glam::Vec3::new(1.5, 1.5, 0.8));
        let s = placed(kind, m);
        let (lo, hi) = kind.bounds();
        let centre = m.transform_point3a(Vec3A::new(0.0, 0.0, 0.5));
        let mut hits = 0;
        for i in 0..2000 {
            let a = i as f32 * 0.37;
            let dir = Vec3A::new(a.cos(), a.sin(), 0.8 * (a * 1.7).sin()).normalize();
            let target = centre + 0.6 * Vec3A::new((a * 2.3).sin(), (a * 3.1).cos(), (a * 0.9).sin());
            let Some(h) = s.intersect(&Ray::new(target - dir * 6.0, dir)) else { continue };
            hits += 1;
            let eps = 1e-9 * (1.0 + h.p.abs().max_element());
            assert!(h.p.cmpge(lo - eps).all() && h.p.cmple(hi + eps).all(), "{kind:?}: {:?} outside", h.p);
            if !check_rehit {
                continue;
            }
            let surf = s.surface(&h);
            let out = surf.n.dot(-dir).signum() * surf.n;
            let o = crate::scene::ray::offset_ray_origin(surf.p, surf.p_error, surf.n, out);
            for b in [Vec3A::new(0.1, -0.2, 0.05), Vec3A::new(-0.6, 0.3, 0.2), Vec3A::new(0.0, 0.9, -0.4)] {
                let bounce = (out + b).normalize();
                if let Some(again) = s.intersect(&Ray::new(o, bounce)) {
                    assert!(again.t > 1e-3, "{kind:?}: re-hit at t = {}", again.t);
                }
            }
        }
        assert!(hits > 500, "{kind:?}: only {hits} hits");
    }

    #[test]
    fn rays_leaving_cones_paraboloids_hyperboloids_do_not_hit_them_again() {
        leaving_rays_do_not_rehit(cone(270.0), true);
        leaving_rays_do_not_rehit(paraboloid(300.0), true);
        leaving_rays_do_not_rehit(hyperboloid(250.0), true);
        // pbrt-v3 fits this one through p2 and a further point of the line only: it comes out as a
        // two-sheeted surface the line does not lie on, and the normal pbrt-v3 gives it (∂p/∂u × the line's
        // direction) is not the surface's, so leaving rays may cross it again (pbrt-v3's do too). Bounds only.
        leaving_rays_do_not_rehit(QuadricKind::hyperboloid([3.0, 1.2, 1.0], [0.65, -0.5, -1.0], 4.7).unwrap(), false);
    }

    #[test]
    fn interval_and_f64_solutions_agree() {
        // The pbrt-v3-style f32 interval intersection (used for rendering) against the plain f64 one.
        let kinds = [cone(270.0), paraboloid(300.0), hyperboloid(250.0)];
        for kind in kinds {
            let q = placed(kind, Affine3A::IDENTITY);
            let (mut both, mut differ) = (0, 0);
            for i in 0..3000 {
                let a = i as f32 * 0.731;
                let dir = Vec3A::new(a.cos(), a.sin(), 0.9 * (a * 1.3).sin()).normalize();
                let target = Vec3A::new(0.5 * (a * 2.1).sin(), 0.5 * (a * 2.9).cos(), 0.5 + 0.4 * (a * 0.7).sin());
                let ray = Ray::new(target - dir * 5.0, dir);
                let f32_hit = q.intersect(&ray);
                let f64_hit = kind.intersect(ray.o.as_dvec3(), ray.d.as_dvec3(), f64::INFINITY);
                match (f32_hit, f64_hit) {
                    (Some(h), Some((t, _))) => {
                        both += 1;
                        assert!((h.t as f64 - t).abs() < 1e-4, "{kind:?}: t {} vs {t}", h.t);
                    }
                    (None, None) => {}
                    // Rays grazing a cut edge may differ by rounding; they are rare.
                    _ => differ += 1,
                }
            }
            assert!(both > 1000 && differ <= 3, "{kind:?}: {both} hits agree, {differ} differ");
        }
    }
}
