//! STAGE 5 (shading): each scene material compiled once into the parameters pbrt-v3's `Create*Material`
//! reads (src/materials/*.cpp), with pbrt-v3's defaults. Types cachert does not model (fourier, hair,
//! subsurface, kdsubsurface, disney) become matte with their Kd (else 0.5) and one warning; a bump map is
//! ignored with one warning.
//!
//! Depends on `scene::material` and [`super::param`].

use crate::error::Warnings;
use crate::scene::material::{MaterialKind, MaterialSpec};
use crate::shading::Spectrum;

use super::param::{FloatParam, Reader, SpecParam};

/// A material ready to build BSDFs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Compiled {
    /// No BSDF (`none`, `interface`, `""`).
    None,
    /// Lambert (σ = 0) or Oren–Nayar.
    Matte {
        /// Diffuse reflectance (0.5).
        kd: SpecParam,
        /// σ in degrees (0).
        sigma: FloatParam,
    },
    /// Lambert plus a Trowbridge–Reitz coat with a dielectric (1.5) Fresnel.
    Plastic {
        /// Diffuse (0.25).
        kd: SpecParam,
        /// Specular (0.25).
        ks: SpecParam,
        /// Roughness (0.1).
        roughness: FloatParam,
        /// Remap roughness to α (true).
        remap: bool,
    },
    /// FresnelBlend.
    Substrate {
        /// Diffuse (0.5).
        kd: SpecParam,
        /// Specular (0.5).
        ks: SpecParam,
        /// Roughness along u (0.1).
        urough: FloatParam,
        /// Roughness along v (0.1).
        vrough: FloatParam,
        /// Remap (true).
        remap: bool,
    },
    /// Conductor microfacet reflection.
    Metal {
        /// η (copper).
        eta: SpecParam,
        /// k (copper).
        k: SpecParam,
        /// Roughness along u (uroughness, else roughness 0.01).
        urough: FloatParam,
        /// Roughness along v (vroughness, else roughness 0.01).
        vrough: FloatParam,
        /// Remap (true).
        remap: bool,
    },
    /// Perfect mirror.
    Mirror {
        /// Reflectance (0.9).
        kr: SpecParam,
    },
    /// Dielectric.
    Glass {
        /// Reflection tint (1).
        kr: SpecParam,
        /// Transmission tint (1).
        kt: SpecParam,
        /// Index (eta, else index, 1.5).
        eta: FloatParam,
        /// Roughness along u (0: specular).
        urough: FloatParam,
        /// Roughness along v (0).
        vrough: FloatParam,
        /// Remap (true).
        remap: bool,
    },
    /// pbrt-v3's uber material.
    Uber {
        /// Diffuse (0.25).
        kd: SpecParam,
        /// Glossy (0.25).
        ks: SpecParam,
        /// Specular reflection (0).
        kr: SpecParam,
        /// Specular transmission (0).
        kt: SpecParam,
        /// Roughness along u (uroughness, else roughness 0.1).
        urough: FloatParam,
        /// Roughness along v (vroughness, else the u roughness).
        vrough: Option<FloatParam>,
        /// Index (eta, else index, 1.5).
        eta: FloatParam,
        /// Opacity (1).
        opacity: SpecParam,
        /// Remap (true).
        remap: bool,
    },
    /// Blend of two materials.
    Mix {
        /// Weight of the first material (0.5); the second gets 1 − amount.
        amount: SpecParam,
        /// The two materials.
        materials: [u32; 2],
    },
    /// Diffuse and glossy reflection and transmission.
    Translucent {
        /// Diffuse (0.25).
        kd: SpecParam,
        /// Glossy (0.25).
        ks: SpecParam,
        /// Reflected fraction (0.5).
        reflect: SpecParam,
        /// Transmitted fraction (0.5).
        transmit: SpecParam,
        /// Roughness (0.1).
        roughness: FloatParam,
        /// Remap (true).
        remap: bool,
    },
}

impl Compiled {
    /// Whether this material can add a glossy reflection lobe (for a mix, whether either part can, given
    /// theirs): plastic, substrate, metal, uber, translucent, and glass with a roughness that is not the
    /// constant 0. Conservative: a glossy coefficient that happens to be black still counts.
    pub fn may_be_glossy(&self, glossy_of: impl Fn(u32) -> bool) -> bool {
        use super::param::FloatParam;
        match self {
            Compiled::Plastic { .. }
            | Compiled::Substrate { .. }
            | Compiled::Metal { .. }
            | Compiled::Uber { .. }
            | Compiled::Translucent { .. } => true,
            Compiled::Glass { urough, vrough, .. } => {
                !matches!((urough, vrough), (FloatParam::Const(u), FloatParam::Const(v)) if *u == 0.0 && *v == 0.0)
            }
            Compiled::Mix { materials, .. } => glossy_of(materials[0]) || glossy_of(materials[1]),
            _ => false,
        }
    }

    /// Whether this material can add a perfectly specular lobe (for a mix, whether either part can, given
    /// theirs): smooth glass, mirrors and uber's Kr and Kt. Conservative: smooth glass made rough by a
    /// texture still counts.
    pub fn may_be_specular(&self, specular_of: impl Fn(u32) -> bool) -> bool {
        match self {
            Compiled::Mirror { .. } | Compiled::Glass { .. } | Compiled::Uber { .. } => true,
            Compiled::Mix { materials, .. } => specular_of(materials[0]) || specular_of(materials[1]),
            _ => false,
        }
    }

    /// The most lobes this material adds to a BSDF (for a mix, the sum of its parts, given theirs).
    pub fn max_lobes(&self, lobes_of: impl Fn(u32) -> usize) -> usize {
        match self {
            Compiled::None => 0,
            Compiled::Matte { .. } | Compiled::Substrate { .. } | Compiled::Metal { .. } | Compiled::Mirror { .. } => 1,
            Compiled::Plastic { .. } | Compiled::Glass { .. } => 2,
            Compiled::Translucent { .. } => 4,
            Compiled::Uber { .. } => 5,
            Compiled::Mix { materials, .. } => lobes_of(materials[0]) + lobes_of(materials[1]),
        }
    }
}

/// Compiles material `m`; `copper` is the default (η, k) of metal.
pub fn compile(m: &MaterialSpec, copper: (Spectrum, Spectrum), warnings: &mut Warnings) -> Compiled {
    use MaterialKind as K;
    let mut r = Reader { m, warnings };
    if m.props.get("bumpmap").is_some() {
        let msg = format!("material \"{}\": bump mapping is not supported; the bump map is ignored", m.type_name);
        match m.loc_of("bumpmap") {
            Some(loc) => r.warnings.at(loc, msg),
            None => r.warnings.general(msg),
        }
    }
    let remap = r.bool("remaproughness", true);
    match m.kind {
        K::None => Compiled::None,
        K::Matte => Compiled::Matte { kd: r.color("Kd", 0.5), sigma: r.sigma("sigma") },
        K::Plastic => Compiled::Plastic {
            kd: r.color("Kd", 0.25),
            ks: r.color("Ks", 0.25),
            roughness: r.roughness("roughness", 0.1),
            remap,
        },
        K::Substrate => Compiled::Substrate {
            kd: r.color("Kd", 0.5),
            ks: r.color("Ks", 0.5),
            urough: r.roughness("uroughness", 0.1),
            vrough: r.roughness("vroughness", 0.1),
            remap,
        },
        K::Metal => {
            let rough = r.roughness("roughness", 0.01);
            Compiled::Metal {
                eta: r.positive_color("eta", copper.0),
                k: r.positive_color("k", copper.1),
                urough: r.optional_roughness("uroughness").unwrap_or(rough),
                vrough: r.optional_roughness("vroughness").unwrap_or(rough),
                remap,
            }
        }
        K::Mirror => Compiled::Mirror { kr: r.color("Kr", 0.9) },
        K::Glass => Compiled::Glass {
            kr: r.color("Kr", 1.0),
            kt: r.color("Kt", 1.0),
            eta: r.ior(1.5),
            urough: r.roughness("uroughness", 0.0),
            vrough: r.roughness("vroughness", 0.0),
            remap,
        },
        K::Uber => {
            let rough = r.roughness("roughness", 0.1);
            Compiled::Uber {
                kd: r.color("Kd", 0.25),
                ks: r.color("Ks", 0.25),
                kr: r.color("Kr", 0.0),
                kt: r.color("Kt", 0.0),
                urough: r.optional_roughness("uroughness").unwrap_or(rough),
                vrough: r.optional_roughness("vroughness"),
                eta: r.ior(1.5),
                opacity: r.color("opacity", 1.0),
                remap,
            }
        }
        K::Mix => Compiled::Mix { amount: r.color("amount", 0.5), materials: m.mix.unwrap_or([0, 0]) },
        K::Translucent => Compiled::Translucent {
            kd: r.color("Kd", 0.25),
            ks: r.color("Ks", 0.25),
            reflect: r.color("reflect", 0.5),
            transmit: r.color("transmit", 0.5),
            roughness: r.roughness("roughness", 0.1),
            remap,
        },
        K::Fourier | K::Hair | K::Subsurface | K::KdSubsurface | K::Disney => {
            let msg = format!("material type \"{}\" is not supported; rendered as matte", m.type_name);
            match &m.loc {
                Some(loc) => r.warnings.at(loc, msg),
                None => r.warnings.general(msg),
            }
            Compiled::Matte { kd: r.color("Kd", 0.5), sigma: FloatParam::Const(0.0) }
        }
    }
}
