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
