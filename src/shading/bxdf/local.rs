//! STAGE 5 (shading): trigonometry of directions in the local shading frame (z = shading normal), as
//! pbrt-v3's reflection.h defines it, plus mirror reflection and Snell refraction.
//!
//! Pure functions of `Vec3A`; depends on nothing else in the crate.

use glam::Vec3A;

/// cos θ of a local direction.
#[inline]
pub fn cos_theta(w: Vec3A) -> f32 {
    w.z
}

/// cos² θ.
#[inline]
pub fn cos2_theta(w: Vec3A) -> f32 {
    w.z * w.z
}

/// |cos θ|.
#[inline]
pub fn abs_cos_theta(w: Vec3A) -> f32 {
    w.z.abs()
}

/// sin² θ (never negative).
#[inline]
pub fn sin2_theta(w: Vec3A) -> f32 {
    (1.0 - cos2_theta(w)).max(0.0)
}

/// sin θ.
#[inline]
pub fn sin_theta(w: Vec3A) -> f32 {
    sin2_theta(w).sqrt()
}

/// tan θ (infinite at grazing angles).
#[inline]
pub fn tan_theta(w: Vec3A) -> f32 {
    sin_theta(w) / cos_theta(w)
}

/// tan² θ (infinite at grazing angles).
#[inline]
pub fn tan2_theta(w: Vec3A) -> f32 {
    sin2_theta(w) / cos2_theta(w)
}

/// cos φ (1 along the normal).
#[inline]
pub fn cos_phi(w: Vec3A) -> f32 {
    let s = sin_theta(w);
    if s == 0.0 { 1.0 } else { (w.x / s).clamp(-1.0, 1.0) }
}

/// sin φ (0 along the normal).
#[inline]
pub fn sin_phi(w: Vec3A) -> f32 {
    let s = sin_theta(w);
    if s == 0.0 { 0.0 } else { (w.y / s).clamp(-1.0, 1.0) }
}

/// cos² φ.
#[inline]
pub fn cos2_phi(w: Vec3A) -> f32 {
    cos_phi(w) * cos_phi(w)
}

/// sin² φ.
#[inline]
pub fn sin2_phi(w: Vec3A) -> f32 {
    sin_phi(w) * sin_phi(w)
}

/// Whether two local directions lie on the same side of the surface.
#[inline]
pub fn same_hemisphere(a: Vec3A, b: Vec3A) -> bool {
    a.z * b.z > 0.0
}

/// `wo` mirrored about `n`.
#[inline]
pub fn reflect(wo: Vec3A, n: Vec3A) -> Vec3A {
    -wo + 2.0 * wo.dot(n) * n
}

/// `wi` refracted through a surface with normal `n` (on `wi`'s side) and relative index `eta` = η_i/η_t;
/// `None` at total internal reflection.
#[inline]
pub fn refract(wi: Vec3A, n: Vec3A, eta: f32) -> Option<Vec3A> {
    let cos_i = n.dot(wi);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = eta * eta * sin2_i;
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * -wi + (eta * cos_i - cos_t) * n)
}

/// `v` flipped, if needed, to lie on the same side as `w`.
#[inline]
pub fn face_forward(v: Vec3A, w: Vec3A) -> Vec3A {
    if v.dot(w) < 0.0 { -v } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refraction_obeys_snell_and_reflection_keeps_the_angle() {
        let wi = Vec3A::new(0.6, 0.0, 0.8);
        let wt = refract(wi, Vec3A::Z, 1.0 / 1.5).unwrap();
        assert!((sin_theta(wt) - 0.6 / 1.5).abs() < 1e-6 && wt.z < 0.0);
        assert!((wt.length() - 1.0).abs() < 1e-6);
        assert!(refract(Vec3A::new(0.8, 0.0, 0.6), Vec3A::Z, 1.5).is_none(), "total internal reflection");
        let r = reflect(wi, Vec3A::Z);
        assert!((r - Vec3A::new(-0.6, 0.0, 0.8)).length() < 1e-6);
    }
}
