//! Orthonormal frames around a normal.

use glam::Vec3A;

/// An orthonormal basis (s, t, n); local directions have z along n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3A,
    /// Second tangent, n × s.
    pub t: Vec3A,
    /// The normal.
    pub n: Vec3A,
}

impl Frame {
    /// A frame around unit normal `n` (Duff et al. 2017, branchless and continuous except at n.z = −1).
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// The frame of ALGORITHMS.md §3.3 for gathering caches: tangent = the fixed generic axis
    /// a = (1,2,3)/√14 made orthogonal to n (fallback a' = (3,−1,2)/√14 when that is nearly zero), so that
    /// nearby caches with similar normals get similar frames and their gathering samples correspond index by
    /// index.
    pub fn generic(n: Vec3A) -> Self {
        let inv = 1.0 / 14f32.sqrt();
        let a = Vec3A::new(1.0, 2.0, 3.0) * inv;
        let mut t = a - n * a.dot(n);
        if t.length() < 1e-3 {
            let a2 = Vec3A::new(3.0, -1.0, 2.0) * inv;
            t = a2 - n * a2.dot(n);
        }
        let s = t.normalize();
        Frame { s, t: n.cross(s), n }
    }

    /// Local → world.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    /// World → local.
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generic_frames_are_orthonormal_and_vary_smoothly() {
        let n1 = Vec3A::new(0.1, 0.2, 0.97).normalize();
        let n2 = (n1 + Vec3A::new(0.017, 0.0, 0.0)).normalize(); // about 1° apart
        let (f1, f2) = (Frame::generic(n1), Frame::generic(n2));
        assert!(
            f1.s.dot(f1.t).abs() < 1e-5 && f1.s.dot(f1.n).abs() < 1e-5 && (f1.s.cross(f1.t) - f1.n).length() < 1e-5
        );
        assert!(f1.s.dot(f2.s) > (3f32.to_radians()).cos(), "tangents of normals 1° apart differ by more than 3°");
        let a = Vec3A::new(1.0, 2.0, 3.0).normalize();
        let f = Frame::generic(a);
        assert!((f.s.length() - 1.0).abs() < 1e-5, "fallback axis used at n = a");
    }

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        for n in [
            Vec3A::Z,
            -Vec3A::Z,
            Vec3A::X,
            Vec3A::new(0.3, -0.5, 0.8).normalize(),
            Vec3A::new(-0.01, 0.02, -0.9997).normalize(),
        ] {
            let f = Frame::from_normal(n);
            for (a, b) in [(f.s, f.t), (f.t, f.n), (f.s, f.n)] {
                assert!(a.dot(b).abs() < 1e-5);
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-5);
            }
            assert!((f.s.cross(f.t) - f.n).length() < 1e-5);
            let v = Vec3A::new(0.2, 0.3, 0.9);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-5);
        }
    }
}
