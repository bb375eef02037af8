//! STAGE 2 (scene): pbrt-v3's `curve` shape (`src/shapes/curve.cpp`), intersected exactly as pbrt-v3 does
//! it — no tessellation. A curve is a cubic Bézier piece with a width that varies linearly along it; pbrt-v3
//! splits each piece into 2^splitdepth [`CurveSegment`]s, each a primitive of its own in the acceleration
//! structure. A segment is tested in a coordinate frame looking down the ray: its control points are
//! subdivided recursively (to a depth set by how far they are from a straight line compared with the width)
//! while their width-expanded boxes still contain the ray, and each final piece is treated as a line
//! segment whose distance from the ray decides the hit.
//!
//! The three types differ only in width and normal: `flat` always faces the ray; `cylinder` faces the ray
//! too but its normal is turned about the tangent by −90°…90° across the width (v), so it shades like a
//! tube; `ribbon` has the normals given at the ends (slerped along u), and its apparent width shrinks with
//! the angle between that normal and the ray. As in pbrt-v3, a hit's error bound is twice the width in each
//! axis, so rays leaving a curve start well clear of it; occlusion queries do not skip the curve they leave.
//!
//! Computed in f32 like pbrt-v3. Depends only on the ray, glam and the quadric module's transform helpers;
//! never on the scene builder or the renderer.

use glam::{Affine3A, Vec3A};

use crate::scene::ray::Ray;
use crate::scene::transform::{transform_bounds, transform_normal, transform_point_with_error};

/// Deepest recursive subdivision of a segment (pbrt-v3 clamps its `maxDepth` to 10).
const MAX_DEPTH: i32 = 10;

/// How a curve's surface is oriented.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveType {
    /// A flat strip that always faces the ray.
    Flat,
    /// A flat strip shaded as a tube: the normal turns across the width.
    Cylinder,
    /// A strip oriented by normals given at its two ends.
    Ribbon,
}

/// One cubic Bézier piece of a `curve` shape (pbrt-v3's `CurveCommon`) placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Object-space control points.
    pub cp: [Vec3A; 4],
    /// Width at u = 0 and u = 1.
    pub width: [f32; 2],
    /// Type.
    pub kind: CurveType,
    /// Unit normals at u = 0 and u = 1 (ribbons only; zero otherwise).
    pub n: [Vec3A; 2],
    /// Angle between the two normals (pbrt-v3 clamps their dot product to [0, 1]).
    normal_angle: f32,
    /// 1 / sin(normal_angle).
    inv_sin_normal_angle: f32,
    /// Object → world (for curves inside an object definition: object → instance space).
    pub world_from_object: Affine3A,
    /// World → object.
    pub object_from_world: Affine3A,
    /// Whether the normal is flipped (ReverseOrientation xor a handedness-swapping transform).
    pub flip_normal: bool,
}

/// A part u ∈ [u0, u1] of a [`Curve`]: one primitive in the acceleration structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveSegment {
    /// Index of its curve.
    pub curve: u32,
    /// Parameter range on the curve.
    pub u: [f32; 2],
    /// Object-space control points of the part (blossomed from the curve's).
    pub cp: [Vec3A; 4],
}

/// Where a ray hit a curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveHit {
    /// Ray parameter.
    pub t: f32,
    /// Curve parameter along the curve.
    pub u: f32,
    /// Parameter across the width (0.5 on the centre line).
    pub v: f32,
}

/// Surface data of a curve hit, in world space (instance space for curves in an object definition).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveSurface {
    /// Position.
    pub p: Vec3A,
    /// Absolute error bound of `p`.
    pub p_error: Vec3A,
    /// Unit geometric normal, pbrt-v3's `cross(∂p/∂u, ∂p/∂v)` (flipped when the curve is).
    pub n: Vec3A,
    /// ∂p/∂u.
    pub dpdu: Vec3A,
    /// Surface parameters (u, v).
    pub uv: [f32; 2],
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

fn lerp3(t: f32, a: Vec3A, b: Vec3A) -> Vec3A {
    (1.0 - t) * a + t * b
}

/// The point of the cubic Bézier `p` with blossom arguments (u0, u1, u2).
fn blossom(p: &[Vec3A; 4], u0: f32, u1: f32, u2: f32) -> Vec3A {
    let a = [lerp3(u0, p[0], p[1]), lerp3(u0, p[1], p[2]), lerp3(u0, p[2], p[3])];
    let b = [lerp3(u1, a[0], a[1]), lerp3(u1, a[1], a[2])];
    lerp3(u2, b[0], b[1])
}

/// The control points of the two halves of `cp` (sharing the middle one).
fn subdivide(cp: &[Vec3A; 4]) -> [Vec3A; 7] {
    [
        cp[0],
        (cp[0] + cp[1]) / 2.0,
        (cp[0] + 2.0 * cp[1] + cp[2]) / 4.0,
        (cp[0] + 3.0 * cp[1] + 3.0 * cp[2] + cp[3]) / 8.0,
        (cp[1] + 2.0 * cp[2] + cp[3]) / 4.0,
        (cp[2] + cp[3]) / 2.0,
        cp[3],
    ]
}

/// The point at `u` and the derivative there (pbrt-v3 falls back to cp3 − cp0 where it vanishes).
fn eval_bezier(cp: &[Vec3A; 4], u: f32) -> (Vec3A, Vec3A) {
    let c1 = [lerp3(u, cp[0], cp[1]), lerp3(u, cp[1], cp[2]), lerp3(u, cp[2], cp[3])];
    let c2 = [lerp3(u, c1[0], c1[1]), lerp3(u, c1[1], c1[2])];
    let deriv = if (c2[1] - c2[0]).length_squared() > 0.0 { 3.0 * (c2[1] - c2[0]) } else { cp[3] - cp[0] };
    (lerp3(u, c2[0], c2[1]), deriv)
}

/// pbrt-v3's `CoordinateSystem`: a unit vector perpendicular to `v`.
fn perpendicular(v: Vec3A) -> Vec3A {
    if v.x.abs() > v.y.abs() {
        Vec3A::new(-v.z, 0.0, v.x) / (v.x * v.x + v.z * v.z).sqrt()
    } else {
        Vec3A::new(0.0, v.z, -v.y) / (v.y * v.y + v.z * v.z).sqrt()
    }
}

/// Whether the box of `cp` widened by `half_width` contains the ray (the z axis from 0 to `z_max`).
fn overlaps_ray(cp: &[Vec3A; 4], half_width: f32, z_max: f32) -> bool {
    let lo = cp[0].min(cp[1]).min(cp[2].min(cp[3])) - Vec3A::splat(half_width);
    let hi = cp[0].max(cp[1]).max(cp[2].max(cp[3])) + Vec3A::splat(half_width);
    !(hi.y < 0.0 || lo.y > 0.0 || hi.x < 0.0 || lo.x > 0.0 || hi.z < 0.0 || lo.z > z_max)
}

/// pbrt-v3's integer log2 of a float, rounded to nearest (0 below 1).
fn log2_round(v: f32) -> i32 {
    if v < 1.0 {
        return 0;
    }
    let bits = v.to_bits();
    (bits >> 23) as i32 - 127 + i32::from(bits & (1 << 22) != 0)
}

/// What one intersection query carries down the recursion.
struct Query {
    /// Object-space ray direction (not normalised).
    d: Vec3A,
    /// |d|.
    ray_len: f32,
    /// Farthest ray-frame z considered.
    z_max: f32,
    /// Any hit will do (occlusion).
    any: bool,
}

impl Curve {
    /// A curve piece placed by `world_from_object` (and its inverse `object_from_world`); `normals`
    /// (ribbons) are normalised here. `None` if a normal is zero or not finite.
    pub fn new(
        cp: [Vec3A; 4],
        width: [f32; 2],
        kind: CurveType,
        normals: Option<[Vec3A; 2]>,
        [world_from_object, object_from_world]: [Affine3A; 2],
        flip_normal: bool,
    ) -> Option<Curve> {
        let (n, normal_angle, inv_sin_normal_angle) = match normals {
            Some([a, b]) => {
                let (a, b) = (a.try_normalize()?, b.try_normalize()?);
                let angle = a.dot(b).clamp(0.0, 1.0).acos();
                ([a, b], angle, 1.0 / angle.sin())
            }
            None => ([Vec3A::ZERO; 2], 0.0, 0.0),
        };
        Some(Curve {
            cp,
            width,
            kind,
            n,
            normal_angle,
            inv_sin_normal_angle,
            world_from_object,
            object_from_world,
            flip_normal,
        })
    }

    /// Width at curve parameter `u`.
    fn width_at(&self, u: f32) -> f32 {
        lerp(u, self.width[0], self.width[1])
    }

    /// The ribbon normal at `u`: pbrt-v3's slerp between the end normals. Where the two normals are equal
    /// pbrt-v3 divides by sin 0 and gets NaN; we use the common normal.
    fn ribbon_normal(&self, u: f32) -> Vec3A {
        if !self.inv_sin_normal_angle.is_finite() || self.normal_angle == 0.0 {
            return self.n[0];
        }
        let s0 = ((1.0 - u) * self.normal_angle).sin() * self.inv_sin_normal_angle;
        let s1 = (u * self.normal_angle).sin() * self.inv_sin_normal_angle;
        s0 * self.n[0] + s1 * self.n[1]
    }

    /// The 2^`split_depth` segments of this curve (index `curve` in the scene's list), as pbrt-v3's
    /// `CreateCurve` makes them.
    pub fn segments(&self, curve: u32, split_depth: u32) -> impl Iterator<Item = CurveSegment> + '_ {
        let n = 1u32 << split_depth.min(MAX_DEPTH as u32);
        (0..n).map(move |i| {
            let (u0, u1) = (i as f32 / n as f32, (i + 1) as f32 / n as f32);
            let cp = [
                blossom(&self.cp, u0, u0, u0),
                blossom(&self.cp, u0, u0, u1),
                blossom(&self.cp, u0, u1, u1),
                blossom(&self.cp, u1, u1, u1),
            ];
            CurveSegment { curve, u: [u0, u1], cp }
        })
    }

    /// World-space box of a segment: its control points' box widened by half its largest width.
    pub fn world_bounds(&self, seg: &CurveSegment) -> (Vec3A, Vec3A) {
        let lo = seg.cp[0].min(seg.cp[1]).min(seg.cp[2].min(seg.cp[3]));
        let hi = seg.cp[0].max(seg.cp[1]).max(seg.cp[2].max(seg.cp[3]));
        let half = 0.5 * self.width_at(seg.u[0]).max(self.width_at(seg.u[1]));
        transform_bounds(&self.world_from_object, lo - Vec3A::splat(half), hi + Vec3A::splat(half))
    }

    /// The hit of world-space `ray` with segment `seg` of this curve, t in (0, ray.t_max]. With `any`, the
    /// first hit found (occlusion); otherwise, as in pbrt-v3, the last hit the subdivision finds (the
    /// sub-pieces are tested in order along u and a later hit replaces an earlier one).
    pub fn intersect(&self, seg: &CurveSegment, ray: &Ray, any: bool) -> Option<CurveHit> {
        let o = self.object_from_world.transform_point3a(ray.o);
        let d = self.object_from_world.transform_vector3a(ray.d);
        let ray_len = d.length();
        if ray_len == 0.0 || !ray_len.is_finite() {
            return None;
        }
        // A frame looking down the ray, its x axis along the segment's chord as seen from the ray (pbrt-v3's
        // LookAt(o, o + d, d × chord)): the curve lies roughly along x, so its boxes are thin in y.
        let dir = d / ray_len;
        let mut up = d.cross(seg.cp[3] - seg.cp[0]);
        if up.length_squared() == 0.0 {
            up = perpendicular(d);
        }
        let right = up.normalize().cross(dir).try_normalize()?;
        let new_up = dir.cross(right);
        let to_ray = |p: Vec3A| {
            let q = p - o;
            Vec3A::new(q.dot(right), q.dot(new_up), q.dot(dir))
        };
        let cp = seg.cp.map(to_ray);
        let z_max = ray_len * ray.t_max;
        let max_width = self.width_at(seg.u[0]).max(self.width_at(seg.u[1]));
        if !overlaps_ray(&cp, 0.5 * max_width, z_max) {
            return None;
        }
        // Subdivide until the pieces are within width/20 of straight (pbrt-v3's bound, log base 4).
        let mut l0 = 0.0f32;
        for i in 0..2 {
            let second = (cp[i] - 2.0 * cp[i + 1] + cp[i + 2]).abs();
            l0 = l0.max(second.max_element());
        }
        let eps = self.width[0].max(self.width[1]) * 0.05;
        let max_depth = (log2_round(std::f32::consts::SQRT_2 * 6.0 * l0 / (8.0 * eps)) / 2).clamp(0, MAX_DEPTH);
        let q = Query { d, ray_len, z_max, any };
        let mut hit = None;
        self.recursive_intersect(&q, &cp, seg.u[0], seg.u[1], max_depth, &mut hit);
        hit
    }

    /// pbrt-v3's `recursiveIntersect`; returns whether a hit was found, and stores it in `hit`.
    fn recursive_intersect(
        &self,
        q: &Query,
        cp: &[Vec3A; 4],
        u0: f32,
        u1: f32,
        depth: i32,
        hit: &mut Option<CurveHit>,
    ) -> bool {
        if depth > 0 {
            let split = subdivide(cp);
            let u = [u0, (u0 + u1) / 2.0, u1];
            let mut found = false;
            for half in 0..2 {
                let cps = [split[3 * half], split[3 * half + 1], split[3 * half + 2], split[3 * half + 3]];
                let max_width = self.width_at(u[half]).max(self.width_at(u[half + 1]));
                if !overlaps_ray(&cps, 0.5 * max_width, q.z_max) {
                    continue;
                }
                found |= self.recursive_intersect(q, &cps, u[half], u[half + 1], depth - 1, hit);
                if found && q.any {
                    return true;
                }
            }
            return found;
        }
        // The ray (the origin of the xy plane) must lie between the perpendiculars to the tangents at the
        // piece's ends.
        let edge = (cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x);
        if edge < 0.0 {
            return false;
        }
        let edge = (cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x);
        if edge < 0.0 {
            return false;
        }
        // The parameter w of the chord point nearest the ray.
        let chord = cp[3].truncate() - cp[0].truncate();
        let denom = chord.length_squared();
        if denom == 0.0 {
            return false;
        }
        let w = (-cp[0].truncate()).dot(chord) / denom;
        let u = lerp(w, u0, u1).clamp(u0, u1);
        let mut hit_width = self.width_at(u);
        if self.kind == CurveType::Ribbon {
            hit_width *= self.ribbon_normal(u).dot(q.d).abs() / q.ray_len;
        }
        let (pc, dpcdw) = eval_bezier(cp, w.clamp(0.0, 1.0));
        let dist2 = pc.x * pc.x + pc.y * pc.y;
        // Written so NaN counts as a miss.
        let within = dist2 <= hit_width * hit_width * 0.25;
        if !within || pc.z < 0.0 || pc.z > q.z_max {
            return false;
        }
        let dist = dist2.sqrt();
        let edge_func = dpcdw.x * -pc.y + pc.x * dpcdw.y;
        let v = if edge_func > 0.0 { 0.5 + dist / hit_width } else { 0.5 - dist / hit_width };
        *hit = Some(CurveHit { t: pc.z / q.ray_len, u, v });
        true
    }

    /// World-space surface data of `hit`, found along world-space `ray` (the normal of flat and cylinder
    /// curves depends on the ray).
    pub fn surface(&self, ray: &Ray, hit: &CurveHit) -> CurveSurface {
        let o = self.object_from_world.transform_point3a(ray.o);
        let d = self.object_from_world.transform_vector3a(ray.d);
        let ray_len = d.length();
        let dir = d / ray_len;
        let (u, v) = (hit.u, hit.v);
        let mut hit_width = self.width_at(u);
        let (_, dpdu) = eval_bezier(&self.cp, u);
        let dpdv = if self.kind == CurveType::Ribbon {
            let n = self.ribbon_normal(u);
            hit_width *= n.dot(d).abs() / ray_len;
            n.cross(dpdu).normalize_or_zero() * hit_width
        } else {
            // In the ray frame pbrt-v3 takes (−t.y, t.x, 0) for the tangent t: that is dir × t, whatever
            // the frame's roll.
            let across = dir.cross(dpdu).normalize_or_zero() * hit_width;
            if self.kind == CurveType::Cylinder {
                // Turned about the tangent by −θ, θ from −90° to 90° across the width (pbrt-v3's Rotate).
                let theta = lerp(v, -90.0, 90.0);
                rotate(across, dpdu.normalize_or_zero(), (-theta).to_radians())
            } else {
                across
            }
        };
        let mut n = dpdu.cross(dpdv).normalize_or_zero();
        if n == Vec3A::ZERO {
            // A degenerate tangent: face the ray.
            n = -dir;
        }
        if self.flip_normal {
            n = -n;
        }
        let p_obj = o + d * hit.t;
        let (p, p_error) = transform_point_with_error(&self.world_from_object, p_obj, Vec3A::splat(2.0 * hit_width));
        CurveSurface {
            p,
            p_error,
            n: transform_normal(&self.world_from_object, n),
            dpdu: self.world_from_object.transform_vector3a(dpdu),
            uv: [u, v],
        }
    }
}

/// `v` turned by `angle` radians about the unit `axis` (right-handed, as pbrt-v3's `Rotate`).
fn rotate(v: Vec3A, axis: Vec3A, angle: f32) -> Vec3A {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight curve along x from (−1, 0, 0) to (1, 0, 0).
    fn straight(kind: CurveType, width: [f32; 2], normals: Option<[Vec3A; 2]>) -> Curve {
        let cp = [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0].map(|x| Vec3A::new(x, 0.0, 0.0));
        Curve::new(cp, width, kind, normals, [Affine3A::IDENTITY; 2], false).unwrap()
    }

    fn first_hit(c: &Curve, ray: &Ray, split: u32) -> Option<(CurveHit, CurveSurface)> {
        c.segments(0, split)
            .filter_map(|s| c.intersect(&s, ray, false))
            .min_by(|a, b| a.t.total_cmp(&b.t))
            .map(|h| (h, c.surface(ray, &h)))
    }

    #[test]
    fn straight_flat_and_cylinder_curves_are_hit_at_their_distance() {
        for kind in [CurveType::Flat, CurveType::Cylinder] {
            let c = straight(kind, [0.5, 0.5], None);
            // Straight down onto the centre line at x = 0.3: t = 5, normal facing the ray, v = 0.5.
            let ray = Ray::new(Vec3A::new(0.3, 0.0, 5.0), -Vec3A::Z);
            let (h, s) = first_hit(&c, &ray, 3).expect("hit");
            assert!((h.t - 5.0).abs() < 1e-5, "{kind:?}: t {}", h.t);
            assert!((h.u - 0.65).abs() < 1e-3, "{kind:?}: u {}", h.u);
            assert!((h.v - 0.5).abs() < 1e-3);
            assert!(s.n.dot(Vec3A::Z).abs() > 0.999, "{kind:?}: n {:?}", s.n);
            assert!((s.p - Vec3A::new(0.3, 0.0, 0.0)).length() < 1e-5);
            assert!((s.p_error - Vec3A::splat(1.0)).abs().max_element() < 1e-5, "twice the width: {:?}", s.p_error);
            // Off the centre line but inside the half width 0.25: still t = 5 (the strip faces the ray).
            let (h, s) = first_hit(&c, &Ray::new(Vec3A::new(0.3, 0.2, 5.0), -Vec3A::Z), 3).expect("hit");
            assert!((h.t - 5.0).abs() < 1e-5);
            assert!((h.v - 0.5).abs() > 0.3, "v {} near an edge", h.v);
            if kind == CurveType::Cylinder {
                // Near the edge the normal leans over sideways (±72° at |v − 0.5| = 0.4).
                assert!(s.n.y.abs() > 0.9, "cylinder normal {:?}", s.n);
            } else {
                assert!(s.n.dot(Vec3A::Z).abs() > 0.999);
            }
            // Outside the width, and beyond the ends.
            assert!(first_hit(&c, &Ray::new(Vec3A::new(0.3, 0.26, 5.0), -Vec3A::Z), 3).is_none());
            assert!(first_hit(&c, &Ray::new(Vec3A::new(1.1, 0.0, 5.0), -Vec3A::Z), 3).is_none());
            // Seen from the side, the flat strip still faces the ray.
            let (h, _) = first_hit(&c, &Ray::new(Vec3A::new(0.0, -4.0, 0.1), Vec3A::Y), 3).expect("hit");
            assert!((h.t - 4.0).abs() < 1e-4);
            // t_max before the curve.
            assert!(first_hit(&c, &Ray { t_max: 4.9, ..ray }, 3).is_none());
        }
    }

    #[test]
    fn width_tapers_from_width0_to_width1() {
        let c = straight(CurveType::Flat, [0.8, 0.2], None);
        // At x = −0.5 (u = 0.25) the width is 0.65; at x = 0.5 (u = 0.75) it is 0.35.
        let down = |x: f32, y: f32| Ray::new(Vec3A::new(x, y, 3.0), -Vec3A::Z);
        assert!(first_hit(&c, &down(-0.5, 0.3), 2).is_some());
        assert!(first_hit(&c, &down(-0.5, 0.34), 2).is_none());
        assert!(first_hit(&c, &down(0.5, 0.17), 2).is_some());
        assert!(first_hit(&c, &down(0.5, 0.19), 2).is_none());
        let seg = c.segments(0, 1).next().unwrap();
        let (lo, hi) = c.world_bounds(&seg);
        assert!((lo.y + 0.4).abs() < 1e-6 && (hi.y - 0.4).abs() < 1e-6, "half the widest width of the half");
    }

    #[test]
    fn ribbons_narrow_with_the_viewing_angle() {
        // Normal +z along the whole ribbon: seen along −z full width; seen at 60° off the normal half width.
        let c = straight(CurveType::Ribbon, [0.4, 0.4], Some([Vec3A::Z, Vec3A::Z]));
        let (_, s) = first_hit(&c, &Ray::new(Vec3A::new(0.0, 0.19, 2.0), -Vec3A::Z), 3).expect("hit");
        assert!((s.n.dot(Vec3A::Z)).abs() > 0.999);
        let d = Vec3A::new(0.0, 60f32.to_radians().sin(), -0.5);
        let at = |y: f32| Ray::new(Vec3A::new(0.0, y, 0.0) - 4.0 * d, d);
        // The ray meets the ribbon's plane at y: inside the half width 0.2 or not.
        assert!(first_hit(&c, &at(0.19), 3).is_some());
        assert!(first_hit(&c, &at(0.21), 3).is_none());
        // Normals 90° apart: the ribbon twists, its normal at the middle is halfway.
        let c = straight(CurveType::Ribbon, [0.4, 0.4], Some([Vec3A::Z, Vec3A::Y]));
        assert!((c.ribbon_normal(0.5) - Vec3A::new(0.0, 1.0, 1.0).normalize()).length() < 1e-5);
    }

    #[test]
    fn curved_curves_are_hit_on_their_centre_line_and_shadow_queries_agree() {
        // A bent curve in the z = 0 plane, hit from above along its centre line.
        let cp = [
            Vec3A::new(-1.0, 0.0, 0.0),
            Vec3A::new(-0.3, 1.0, 0.0),
            Vec3A::new(0.3, 1.0, 0.0),
            Vec3A::new(1.0, 0.0, 0.0),
        ];
        let m = Affine3A::from_translation(glam::Vec3::new(0.5, 1.0, -2.0)) * Affine3A::from_rotation_z(0.4);
        let c = Curve::new(cp, [0.1, 0.1], CurveType::Cylinder, None, [m, m.inverse()], false).unwrap();
        for i in 1..20 {
            let u = i as f32 / 20.0;
            let p = m.transform_point3a(eval_bezier(&c.cp, u).0);
            let ray = Ray::new(p + Vec3A::new(0.0, 0.0, 3.0), -Vec3A::Z);
            let (h, s) = first_hit(&c, &ray, 3).unwrap_or_else(|| panic!("u {u}: no hit"));
            assert!((h.t - 3.0).abs() < 1e-3 && (h.u - u).abs() < 0.02, "u {u}: {h:?}");
            assert!((s.p - p).length() < 1e-3);
            let segs: Vec<_> = c.segments(0, 3).collect();
            assert!(segs.iter().any(|sg| c.intersect(sg, &ray, true).is_some()));
            for sg in &segs {
                let (lo, hi) = c.world_bounds(sg);
                if c.intersect(sg, &ray, false).is_some() {
                    assert!(s.p.cmpge(lo - 1e-4).all() && s.p.cmple(hi + 1e-4).all());
                }
            }
        }
    }

    #[test]
    fn degenerate_input_gives_no_nan_hits() {
        assert!(
            Curve::new(
                [Vec3A::ZERO; 4],
                [1.0, 1.0],
                CurveType::Ribbon,
                Some([Vec3A::ZERO, Vec3A::Z]),
                [Affine3A::IDENTITY; 2],
                false
            )
            .is_none()
        );
        let c =
            Curve::new([Vec3A::ZERO; 4], [1.0, 1.0], CurveType::Flat, None, [Affine3A::IDENTITY; 2], false).unwrap();
        let ray = Ray::new(Vec3A::new(0.0, 0.0, 1.0), -Vec3A::Z);
        for s in c.segments(0, 2) {
            if let Some(h) = c.intersect(&s, &ray, false) {
                let surf = c.surface(&ray, &h);
                assert!(surf.n.is_finite() && surf.p.is_finite());
            }
        }
        assert_eq!(log2_round(0.5), 0);
        assert_eq!(log2_round(f32::INFINITY) / 2, 64);
    }
}
