//! STAGE 2 (scene): the transforms of the scene description — pbrt-v3's Translate, Scale, Rotate, LookAt
//! and Transform matrices, composed in f64 and checked (finite, invertible) before anything uses them; and
//! applying an f32 transform to a point with its error bound, a normal, or a box, as pbrt-v3 does.

use glam::{Affine3A, DMat4, DVec3, DVec4, Mat3A, Vec3A};

use crate::scene::ray::gamma;

/// A 4×4 transform with its inverse, in f64 (the builder composes many; f32 is used only for rendering).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// The matrix (column vectors; points are multiplied on the right).
    pub m: DMat4,
    /// Its inverse.
    pub inv: DMat4,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform { m: DMat4::IDENTITY, inv: DMat4::IDENTITY };

    /// Wraps `m`; `Err` with a reason when it has a non-finite entry or is singular.
    pub fn new(m: DMat4) -> Result<Self, String> {
        if !m.is_finite() {
            return Err("the matrix has a non-finite (NaN or infinite) entry".into());
        }
        let det = m.determinant();
        if !det.is_finite() {
            return Err("the matrix's values are too large (its determinant overflows)".into());
        }
        if det == 0.0 {
            return Err("the matrix is singular (not invertible)".into());
        }
        let inv = m.inverse();
        if !inv.is_finite() {
            return Err("the matrix cannot be inverted in floating point".into());
        }
        Ok(Transform { m, inv })
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Transform {
        Transform { m: self.inv, inv: self.m }
    }

    /// `self * other` (apply `other` first), as pbrt's `curTransform * T`.
    pub fn then_local(&self, other: &Transform) -> Transform {
        Transform { m: self.m * other.m, inv: other.inv * self.inv }
    }

    /// `Translate dx dy dz`.
    pub fn translate(d: [f64; 3]) -> Result<Self, String> {
        Transform::new(DMat4::from_translation(DVec3::from(d)))
    }

    /// `Scale sx sy sz`.
    pub fn scale(s: [f64; 3]) -> Result<Self, String> {
        Transform::new(DMat4::from_scale(DVec3::from(s)))
    }

    /// `Rotate angle x y z` (degrees, about the normalised axis).
    pub fn rotate(angle_deg: f64, axis: [f64; 3]) -> Result<Self, String> {
        let a = DVec3::from(axis);
        if a.length_squared() == 0.0 || !a.is_finite() {
            return Err("the rotation axis is zero or not finite".into());
        }
        Transform::new(DMat4::from_axis_angle(a.normalize(), angle_deg.to_radians()))
    }

    /// `LookAt eye target up`: the world-to-camera transform of pbrt-v3 (left-handed: right = up × dir).
    pub fn look_at(eye: [f64; 3], target: [f64; 3], up: [f64; 3]) -> Result<Self, String> {
        let (eye, target, up) = (DVec3::from(eye), DVec3::from(target), DVec3::from(up));
        let d = target - eye;
        if d.length_squared() == 0.0 {
            return Err("the eye and the target are the same point".into());
        }
        if up.length_squared() == 0.0 {
            return Err("the up vector is zero".into());
        }
        let dir = d.normalize();
        let right = up.normalize().cross(dir);
        if right.length_squared() == 0.0 {
            return Err("the up vector and the viewing direction are parallel".into());
        }
        let right = right.normalize();
        let new_up = dir.cross(right);
        let camera_to_world = DMat4::from_cols(
            right.extend(0.0),
            new_up.extend(0.0),
            dir.extend(0.0),
            DVec4::new(eye.x, eye.y, eye.z, 1.0),
        );
        Transform::new(camera_to_world).map(|t| t.inverse())
    }

    /// A matrix given as pbrt-v3 writes it in `Transform [...]`: 16 numbers, column-major.
    pub fn from_pbrt(cols: &[f64; 16]) -> Result<Self, String> {
        Transform::new(DMat4::from_cols_array(cols))
    }

    /// Whether the transform flips handedness (negative determinant of the linear part).
    pub fn swaps_handedness(&self) -> bool {
        glam::DMat3::from_mat4(self.m).determinant() < 0.0
    }

    /// Applies the transform to a point.
    pub fn point(&self, p: [f64; 3]) -> DVec3 {
        self.m.transform_point3(DVec3::from(p))
    }

    /// The f32 affine form for rendering, or `Err` when the matrix is projective or leaves f32 range.
    pub fn to_affine(&self) -> Result<Affine3A, String> {
        let r = self.m.row(3);
        if r != DVec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err("a projective transform cannot be applied to geometry".into());
        }
        let a = Affine3A {
            matrix3: Mat3A::from_cols(
                self.m.x_axis.truncate().as_vec3().into(),
                self.m.y_axis.truncate().as_vec3().into(),
                self.m.z_axis.truncate().as_vec3().into(),
            ),
            translation: Vec3A::from(self.m.w_axis.truncate().as_vec3()),
        };
        if !a.is_finite() {
            return Err("the transform does not fit in single precision".into());
        }
        Ok(a)
    }

    /// Whether the linear part is the identity and there is no translation.
    pub fn is_identity(&self) -> bool {
        self.m == DMat4::IDENTITY
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

    #[test]
    fn pbrt_matrices_are_column_major() {
        let t = Transform::from_pbrt(&[1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 5., 6., 7., 1.]).unwrap();
        assert_eq!(t.point([0.0; 3]), DVec3::new(5.0, 6.0, 7.0));
    }

    #[test]
    fn look_at_maps_the_eye_to_the_origin_and_the_target_to_plus_z() {
        let t = Transform::look_at([1., 2., 3.], [1., 2., 10.], [0., 1., 0.]).unwrap();
        assert!(t.point([1., 2., 3.]).length() < 1e-12);
        let p = t.point([1., 2., 10.]);
        assert!((p - DVec3::new(0., 0., 7.)).length() < 1e-12);
        // pbrt is left-handed: with +y up and +z forward, +x is to the right.
        let r = t.point([2., 2., 3.]);
        assert!((r - DVec3::new(1., 0., 0.)).length() < 1e-12);
        assert!(Transform::look_at([0.; 3], [0.; 3], [0., 1., 0.]).is_err());
        assert!(Transform::look_at([0.; 3], [0., 1., 0.], [0., 1., 0.]).is_err());
    }

    #[test]
    fn bad_matrices_are_refused() {
        assert!(Transform::scale([1.0, 0.0, 1.0]).is_err());
        assert!(Transform::translate([f64::NAN, 0.0, 0.0]).is_err());
        assert!(Transform::rotate(30.0, [0.0; 3]).is_err());
        let t = Transform::scale([1e300, 1.0, 1.0]).unwrap();
        assert!(t.to_affine().is_err());
    }

    #[test]
    fn rotation_follows_the_right_hand_rule() {
        let t = Transform::rotate(90.0, [0., 0., 1.]).unwrap();
        assert!((t.point([1., 0., 0.]) - DVec3::new(0., 1., 0.)).length() < 1e-12);
    }
}
