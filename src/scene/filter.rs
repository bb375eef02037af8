//! STAGE 2 (scene): pbrt-v3's pixel reconstruction filters (`PixelFilter`), evaluated exactly (pbrt-v3
//! tabulates them 16×16; the difference is far below Monte Carlo noise).

use std::f32::consts::PI;

use crate::error::{Error, Result, Warnings};
use crate::parse::Named;

/// A separable reconstruction filter with its radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSpec {
    /// Half-width in pixels along x and y (pbrt's `xwidth`/`ywidth`).
    pub radius: [f32; 2],
    /// Which filter.
    pub kind: FilterKind,
}

/// The filter shapes of pbrt-v3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterKind {
    /// Constant 1 within the radius.
    Box,
    /// Tent: (r − |x|)·(r − |y|).
    Triangle,
    /// Truncated Gaussian, shifted to reach 0 at the radius.
    Gaussian {
        /// Falloff rate.
        alpha: f32,
        /// exp(−α·rx²).
        exp_x: f32,
        /// exp(−α·ry²).
        exp_y: f32,
    },
    /// Mitchell–Netravali cubic.
    Mitchell {
        /// The B parameter.
        b: f32,
        /// The C parameter.
        c: f32,
    },
    /// Lanczos-windowed sinc.
    Sinc {
        /// Number of sinc cycles in the window.
        tau: f32,
    },
}

impl Default for FilterSpec {
    fn default() -> Self {
        FilterSpec { radius: [0.5, 0.5], kind: FilterKind::Box }
    }
}

impl FilterSpec {
    /// Builds the filter named by a `PixelFilter` directive (pbrt-v3 defaults per type).
    pub fn from_directive(d: &Named, _warnings: &mut Warnings) -> Result<FilterSpec> {
        let p = &d.params;
        let default_r = match d.name.as_str() {
            "box" => 0.5,
            "gaussian" | "triangle" | "mitchell" => 2.0,
            "sinc" => 4.0,
            other => {
                return Err(Error::at(
                    &d.name_loc,
                    format!("unknown pixel filter \"{other}\"; expected box, triangle, gaussian, mitchell or sinc"),
                ));
            }
        };
        let rx = p.float_or("xwidth", default_r)? as f32;
        let ry = p.float_or("ywidth", default_r)? as f32;
        for (name, r) in [("xwidth", rx), ("ywidth", ry)] {
            if !(r > 0.0 && r.is_finite() && r <= 64.0) {
                let loc = p.loc_of(name).unwrap_or(&d.name_loc);
                return Err(Error::at(loc, format!("filter {name} must be in (0, 64], got {r}")));
            }
        }
        let kind = match d.name.as_str() {
            "box" => FilterKind::Box,
            "triangle" => FilterKind::Triangle,
            "gaussian" => {
                let alpha = p.float_or("alpha", 2.0)? as f32;
                FilterKind::Gaussian { alpha, exp_x: (-alpha * rx * rx).exp(), exp_y: (-alpha * ry * ry).exp() }
            }
            "mitchell" => {
                FilterKind::Mitchell { b: p.float_or("B", 1.0 / 3.0)? as f32, c: p.float_or("C", 1.0 / 3.0)? as f32 }
            }
            _ => FilterKind::Sinc { tau: p.float_or("tau", 3.0)? as f32 },
        };
        Ok(FilterSpec { radius: [rx, ry], kind })
    }

    /// The filter weight at offset (x, y) from the pixel centre (0 outside the radius).
    pub fn eval(&self, x: f32, y: f32) -> f32 {
        let [rx, ry] = self.radius;
        if x.abs() > rx || y.abs() > ry {
            return 0.0;
        }
        match self.kind {
            FilterKind::Box => 1.0,
            FilterKind::Triangle => (rx - x.abs()).max(0.0) * (ry - y.abs()).max(0.0),
            FilterKind::Gaussian { alpha, exp_x, exp_y } => {
                ((-alpha * x * x).exp() - exp_x).max(0.0) * ((-alpha * y * y).exp() - exp_y).max(0.0)
            }
            FilterKind::Mitchell { b, c } => mitchell_1d(x / rx, b, c) * mitchell_1d(y / ry, b, c),
            FilterKind::Sinc { tau } => windowed_sinc(x, rx, tau) * windowed_sinc(y, ry, tau),
        }
    }
}

fn mitchell_1d(x: f32, b: f32, c: f32) -> f32 {
    let x = (2.0 * x).abs();
    let v = if x > 1.0 {
        (-b - 6.0 * c) * x * x * x + (6.0 * b + 30.0 * c) * x * x + (-12.0 * b - 48.0 * c) * x + (8.0 * b + 24.0 * c)
    } else {
        (12.0 - 9.0 * b - 6.0 * c) * x * x * x + (-18.0 + 12.0 * b + 6.0 * c) * x * x + (6.0 - 2.0 * b)
    };
    v * (1.0 / 6.0)
}

fn sinc(x: f32) -> f32 {
    let x = x.abs();
    if x < 1e-5 { 1.0 } else { (PI * x).sin() / (PI * x) }
}

fn windowed_sinc(x: f32, radius: f32, tau: f32) -> f32 {
    if x.abs() > radius { 0.0 } else { sinc(x) * sinc(x / tau) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_match_pbrt_v3() {
        let b = FilterSpec::default();
        assert_eq!(b.eval(0.49, -0.49), 1.0);
        assert_eq!(b.eval(0.51, 0.0), 0.0);
        let t = FilterSpec { radius: [2.0, 2.0], kind: FilterKind::Triangle };
        assert_eq!(t.eval(1.0, 0.0), 2.0);
        let m = FilterSpec { radius: [2.0, 2.0], kind: FilterKind::Mitchell { b: 1.0 / 3.0, c: 1.0 / 3.0 } };
        assert!((m.eval(0.0, 0.0) - (16.0 / 18.0f32).powi(2)).abs() < 1e-6);
        assert!(m.eval(2.0, 0.0).abs() < 1e-6);
        let s = FilterSpec { radius: [4.0, 4.0], kind: FilterKind::Sinc { tau: 3.0 } };
        assert!((s.eval(0.0, 0.0) - 1.0).abs() < 1e-6 && s.eval(1.0, 0.0).abs() < 1e-6);
    }
}
