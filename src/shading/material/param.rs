//! STAGE 5 (shading): material parameters compiled once from a scene material's captured values — a
//! constant or a texture id — with the checks pbrt-v3 does not make: a negative or NaN colour, a negative
//! or NaN roughness, an index of refraction that is not positive become a warning at the parameter's
//! location and a safe value, so no NaN can come out of a BSDF.
//!
//! Depends on `scene` (material, props, surface interaction), `error` and the shading textures.

use crate::error::Warnings;
use crate::scene::geometry::SurfaceInteraction;
use crate::scene::material::MaterialSpec;
use crate::scene::props::Prop;
use crate::shading::Spectrum;
use crate::shading::texture::Textures;

/// A colour parameter: a constant or a spectrum texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpecParam {
    /// A constant (already checked).
    Const(Spectrum),
    /// A spectrum texture id.
    Tex(u32),
}

impl SpecParam {
    /// The value at `si`.
    #[inline]
    pub fn eval(&self, si: &SurfaceInteraction, textures: &Textures) -> Spectrum {
        match *self {
            SpecParam::Const(c) => c,
            SpecParam::Tex(id) => textures.spectrum(id, si),
        }
    }

    /// The value at `si` clamped to ≥ 0 (pbrt-v3's `Spectrum::Clamp()`; NaN components become 0).
    #[inline]
    pub fn eval_clamped(&self, si: &SurfaceInteraction, textures: &Textures) -> Spectrum {
        clamp_spectrum(self.eval(si, textures))
    }
}

/// A float parameter: a constant or a float texture id.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FloatParam {
    /// A constant (already checked).
    Const(f32),
    /// A float texture id.
    Tex(u32),
}

impl FloatParam {
    /// The value at `si`.
    #[inline]
    pub fn eval(&self, si: &SurfaceInteraction, textures: &Textures) -> f32 {
        match *self {
            FloatParam::Const(c) => c,
            FloatParam::Tex(id) => textures.float(id, si),
        }
    }
}

/// Components clamped to [0, ∞), NaN → 0.
#[inline]
pub fn clamp_spectrum(v: Spectrum) -> Spectrum {
    let f = |x: f32| if x > 0.0 { x } else { 0.0 };
    Spectrum::new(f(v.x), f(v.y), f(v.z))
}

/// Reads one scene material's values, warning about bad constants.
pub struct Reader<'a> {
    /// The material.
    pub m: &'a MaterialSpec,
    /// Where warnings go.
    pub warnings: &'a mut Warnings,
}

impl Reader<'_> {
    fn warn(&mut self, name: &str, msg: String) {
        let msg = format!("material \"{}\": parameter \"{name}\" {msg}", self.m.type_name);
        match self.m.loc_of(name) {
            Some(loc) => self.warnings.at(loc, msg),
            None => self.warnings.general(msg),
        }
    }

    /// A colour that pbrt-v3 clamps to ≥ 0 when it evaluates it (Kd, Ks, Kr, Kt, …): a constant with a
    /// negative or NaN component is clamped here, with a warning.
    pub fn color(&mut self, name: &str, default: f32) -> SpecParam {
        match self.m.props.get(name) {
            Some(Prop::Rgb(c)) => {
                let v = Spectrum::from(*c);
                let clamped = clamp_spectrum(v);
                if clamped != v {
                    self.warn(name, format!("= {c:?} has a negative or NaN component; clamped to {clamped:?}"));
                }
                SpecParam::Const(clamped)
            }
            Some(Prop::Float(x)) => {
                let v = clamp_spectrum(Spectrum::splat(*x));
                if v.x != *x {
                    self.warn(name, format!("= {x} is negative or NaN; clamped to 0"));
                }
                SpecParam::Const(v)
            }
            Some(Prop::SpectrumTexture(id)) => SpecParam::Tex(*id),
            _ => SpecParam::Const(Spectrum::splat(default)),
        }
    }

    /// A colour used without clamping (a metal's η and k): a constant with a negative or NaN component is
    /// replaced by `default`, with a warning.
    pub fn positive_color(&mut self, name: &str, default: Spectrum) -> SpecParam {
        match self.m.props.get(name) {
            Some(Prop::Rgb(c)) => {
                let v = Spectrum::from(*c);
                if !(v.cmpge(Spectrum::ZERO).all() && v.is_finite()) {
                    self.warn(name, format!("= {c:?} has a negative or non-finite component; using {default:?}"));
                    return SpecParam::Const(default);
                }
                SpecParam::Const(v)
            }
            Some(Prop::SpectrumTexture(id)) => SpecParam::Tex(*id),
            _ => SpecParam::Const(default),
        }
    }

    /// A float parameter, if given.
    pub fn optional_float(&mut self, name: &str) -> Option<FloatParam> {
        match self.m.props.get(name) {
            Some(Prop::Float(v)) => Some(FloatParam::Const(*v)),
            Some(Prop::FloatTexture(id)) => Some(FloatParam::Tex(*id)),
            _ => None,
        }
    }

    /// A roughness: a negative, NaN or infinite constant becomes 0, with a warning.
    pub fn roughness(&mut self, name: &str, default: f32) -> FloatParam {
        self.optional_roughness(name).unwrap_or(FloatParam::Const(default))
    }

    /// A roughness, if given (checked as [`Reader::roughness`]).
    pub fn optional_roughness(&mut self, name: &str) -> Option<FloatParam> {
        match self.optional_float(name)? {
            FloatParam::Const(v) if !(v >= 0.0 && v.is_finite()) => {
                self.warn(name, format!("= {v} is outside [0, ∞); using 0"));
                Some(FloatParam::Const(0.0))
            }
            p => Some(p),
        }
    }

    /// Oren–Nayar σ in degrees: clamped to [0, 90] as pbrt-v3 does, NaN → 0 with a warning.
    pub fn sigma(&mut self, name: &str) -> FloatParam {
        match self.optional_float(name) {
            Some(FloatParam::Const(v)) => {
                let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 90.0) };
                if c != v {
                    self.warn(name, format!("= {v} is outside [0, 90] degrees; using {c}"));
                }
                FloatParam::Const(c)
            }
            Some(p) => p,
            None => FloatParam::Const(0.0),
        }
    }

    /// An index of refraction from `eta`, else `index`, else `default`: a constant that is not positive and
    /// finite becomes `default`, with a warning.
    pub fn ior(&mut self, default: f32) -> FloatParam {
        let name = if self.m.props.get("eta").is_some() { "eta" } else { "index" };
        match self.optional_float(name) {
            Some(FloatParam::Const(v)) if !(v > 0.0 && v.is_finite()) => {
                self.warn(name, format!("= {v} is not a positive index of refraction; using {default}"));
                FloatParam::Const(default)
            }
            Some(p) => p,
            None => FloatParam::Const(default),
        }
    }

    /// A bool parameter.
    pub fn bool(&self, name: &str, default: bool) -> bool {
        match self.m.props.get(name) {
            Some(Prop::Bool(b)) => *b,
            _ => default,
        }
    }
}

/// A textured index of refraction at a hit: values that are not positive and finite give 1.5 (pbrt-v3
/// would produce NaN).
#[inline]
pub fn safe_ior(eta: f32) -> f32 {
    if eta > 0.0 && eta.is_finite() { eta } else { 1.5 }
}

/// A textured roughness at a hit: NaN → 0 (negative values are raised by the distribution itself).
#[inline]
pub fn safe_roughness(r: f32) -> f32 {
    if r.is_nan() { 0.0 } else { r }
}
