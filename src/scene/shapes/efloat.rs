//! STAGE 2 (scene): pbrt-v3's `EFloat`, an f32 carried with a conservative interval around the exact result,
//! and its interval quadratic: what the cone, paraboloid and hyperboloid of [`super::quadric`] solve with, so
//! that they reject the roots pbrt-v3 rejects.
//!
//! Depends on nothing of the crate.

/// pbrt-v3's `EFloat`: an f32 value with a conservative interval [low, high] around the exact result.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EFloat {
    /// The value.
    pub(crate) v: f32,
    /// The interval's lower end.
    pub(crate) low: f32,
    /// The interval's upper end.
    pub(crate) high: f32,
}

impl EFloat {
    /// `v` with the absolute error `err` (exact when 0).
    pub(crate) fn new(v: f32, err: f32) -> Self {
        if err == 0.0 {
            EFloat { v, low: v, high: v }
        } else {
            EFloat { v, low: (v - err).next_down(), high: (v + err).next_up() }
        }
    }

    /// An exact value.
    pub(crate) fn exact(v: f32) -> Self {
        EFloat::new(v, 0.0)
    }

    /// The largest distance from the value to either end of the interval, rounded up.
    pub(crate) fn abs_error(self) -> f32 {
        (self.high - self.v).abs().max((self.v - self.low).abs()).next_up()
    }
}

impl std::ops::Add for EFloat {
    type Output = EFloat;
    fn add(self, e: EFloat) -> EFloat {
        EFloat { v: self.v + e.v, low: (self.low + e.low).next_down(), high: (self.high + e.high).next_up() }
    }
}

impl std::ops::Sub for EFloat {
    type Output = EFloat;
    fn sub(self, e: EFloat) -> EFloat {
        EFloat { v: self.v - e.v, low: (self.low - e.high).next_down(), high: (self.high - e.low).next_up() }
    }
}

impl std::ops::Mul for EFloat {
    type Output = EFloat;
    fn mul(self, e: EFloat) -> EFloat {
        let p = [self.low * e.low, self.high * e.low, self.low * e.high, self.high * e.high];
        EFloat {
            v: self.v * e.v,
            low: p[0].min(p[1]).min(p[2].min(p[3])).next_down(),
            high: p[0].max(p[1]).max(p[2].max(p[3])).next_up(),
        }
    }
}

impl std::ops::Div for EFloat {
    type Output = EFloat;
    fn div(self, e: EFloat) -> EFloat {
        if e.low < 0.0 && e.high > 0.0 {
            return EFloat { v: self.v / e.v, low: f32::NEG_INFINITY, high: f32::INFINITY };
        }
        let q = [self.low / e.low, self.high / e.low, self.low / e.high, self.high / e.high];
        EFloat {
            v: self.v / e.v,
            low: q[0].min(q[1]).min(q[2].min(q[3])).next_down(),
            high: q[0].max(q[1]).max(q[2].max(q[3])).next_up(),
        }
    }
}

impl std::ops::Neg for EFloat {
    type Output = EFloat;
    fn neg(self) -> EFloat {
        EFloat { v: -self.v, low: -self.high, high: -self.low }
    }
}

/// pbrt-v3's `Quadratic` on intervals (the discriminant in f64). A zero `a` (a ray along a paraboloid's
/// axis) gives the linear root and an infinite one.
pub(crate) fn efloat_quadratic(a: EFloat, b: EFloat, c: EFloat) -> Option<(EFloat, EFloat)> {
    if a.v == 0.0 {
        return (b.v != 0.0).then(|| (-c / b, EFloat::exact(f32::INFINITY)));
    }
    let discrim = b.v as f64 * b.v as f64 - 4.0 * a.v as f64 * c.v as f64;
    if discrim < 0.0 {
        return None;
    }
    let root = discrim.sqrt();
    let root = EFloat::new(root as f32, (f32::EPSILON as f64 * 0.5 * root) as f32);
    let half = EFloat::exact(-0.5);
    let q = if b.v < 0.0 { half * (b - root) } else { half * (b + root) };
    let (t0, t1) = (q / a, c / q);
    Some(if t0.v > t1.v { (t1, t0) } else { (t0, t1) })
}
