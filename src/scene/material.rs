//! STAGE 2 (scene): pbrt-v3 materials (`Material`, `MakeNamedMaterial`, `NamedMaterial`), stored with their
//! parameters for the shading stage. The schemas list what each pbrt-v3 material reads (src/materials/*.cpp).
//! `""`, `"none"` and `"interface"` give no BSDF: pbrt-v3's integrators pass straight through them.

use crate::error::SourceLoc;
use crate::scene::props::{Kind, Props};

/// The material types of pbrt-v3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    /// No surface (`""`, `"none"`, `"interface"`): invisible to shading, still blocks shadow rays.
    None,
    /// Lambertian / Oren–Nayar.
    Matte,
    /// Diffuse plus glossy coating.
    Plastic,
    /// Diffuse and glossy transmission.
    Translucent,
    /// Dielectric.
    Glass,
    /// Perfect mirror.
    Mirror,
    /// Hair fibre.
    Hair,
    /// Disney principled BSDF.
    Disney,
    /// Blend of two named materials.
    Mix,
    /// Conductor.
    Metal,
    /// Ashikhmin–Shirley coated diffuse.
    Substrate,
    /// pbrt's "uber" material.
    Uber,
    /// Subsurface scattering.
    Subsurface,
    /// Subsurface scattering from diffuse reflectance.
    KdSubsurface,
    /// Tabulated measured BSDF.
    Fourier,
}

use Kind::*;

const BUMP: (&str, Kind) = ("bumpmap", FloatTex);

impl MaterialKind {
    /// Looks a pbrt-v3 material name up; `None` for an unknown name.
    pub fn from_name(name: &str) -> Option<MaterialKind> {
        use MaterialKind as M;
        Some(match name {
            "" | "none" | "interface" => M::None,
            "matte" => M::Matte,
            "plastic" => M::Plastic,
            "translucent" => M::Translucent,
            "glass" => M::Glass,
            "mirror" => M::Mirror,
            "hair" => M::Hair,
            "disney" => M::Disney,
            "mix" => M::Mix,
            "metal" => M::Metal,
            "substrate" => M::Substrate,
            "uber" => M::Uber,
            "subsurface" => M::Subsurface,
            "kdsubsurface" => M::KdSubsurface,
            "fourier" => M::Fourier,
            _ => return None,
        })
    }

    /// The parameters this material reads (pbrt-v3's names and kinds).
    pub fn schema(self) -> &'static [(&'static str, Kind)] {
        use MaterialKind as M;
        match self {
            M::None => &[],
            M::Matte => &[("Kd", SpectrumTex), ("sigma", FloatTex), BUMP],
            M::Plastic => {
                &[("Kd", SpectrumTex), ("Ks", SpectrumTex), ("roughness", FloatTex), ("remaproughness", Bool), BUMP]
            }
            M::Translucent => &[
                ("Kd", SpectrumTex),
                ("Ks", SpectrumTex),
                ("reflect", SpectrumTex),
                ("transmit", SpectrumTex),
                ("roughness", FloatTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::Glass => &[
                ("Kr", SpectrumTex),
                ("Kt", SpectrumTex),
                ("eta", FloatTex),
                ("index", FloatTex),
                ("uroughness", FloatTex),
                ("vroughness", FloatTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::Mirror => &[("Kr", SpectrumTex), BUMP],
            M::Hair => &[
                ("sigma_a", SpectrumTex),
                ("color", SpectrumTex),
                ("eumelanin", FloatTex),
                ("pheomelanin", FloatTex),
                ("eta", FloatTex),
                ("beta_m", FloatTex),
                ("beta_n", FloatTex),
                ("alpha", FloatTex),
            ],
            M::Disney => &[
                ("color", SpectrumTex),
                ("metallic", FloatTex),
                ("eta", FloatTex),
                ("roughness", FloatTex),
                ("speculartint", FloatTex),
                ("anisotropic", FloatTex),
                ("sheen", FloatTex),
                ("sheentint", FloatTex),
                ("clearcoat", FloatTex),
                ("clearcoatgloss", FloatTex),
                ("spectrans", FloatTex),
                ("scatterdistance", SpectrumTex),
                ("thin", Bool),
                ("flatness", FloatTex),
                ("difftrans", FloatTex),
                BUMP,
            ],
            M::Mix => &[("amount", SpectrumTex), ("namedmaterial1", Str), ("namedmaterial2", Str)],
            M::Metal => &[
                ("eta", SpectrumTex),
                ("k", SpectrumTex),
                ("roughness", FloatTex),
                ("uroughness", FloatTex),
                ("vroughness", FloatTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::Substrate => &[
                ("Kd", SpectrumTex),
                ("Ks", SpectrumTex),
                ("uroughness", FloatTex),
                ("vroughness", FloatTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::Uber => &[
                ("Kd", SpectrumTex),
                ("Ks", SpectrumTex),
                ("Kr", SpectrumTex),
                ("Kt", SpectrumTex),
                ("roughness", FloatTex),
                ("uroughness", FloatTex),
                ("vroughness", FloatTex),
                ("eta", FloatTex),
                ("index", FloatTex),
                ("opacity", SpectrumTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::Subsurface => &[
                ("name", Str),
                ("sigma_a", SpectrumTex),
                ("sigma_s", SpectrumTex),
                ("scale", Float),
                ("eta", Float),
                ("g", Float),
                ("Kr", SpectrumTex),
                ("Kt", SpectrumTex),
                ("uroughness", FloatTex),
                ("vroughness", FloatTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::KdSubsurface => &[
                ("Kd", SpectrumTex),
                ("mfp", SpectrumTex),
                ("Kr", SpectrumTex),
                ("Kt", SpectrumTex),
                ("scale", Float),
                ("eta", Float),
                ("g", Float),
                ("uroughness", FloatTex),
                ("vroughness", FloatTex),
                ("remaproughness", Bool),
                BUMP,
            ],
            M::Fourier => &[("bsdffile", File), BUMP],
        }
    }
}

/// A material with the parameter values the scene gave it (absent values take pbrt-v3's defaults when the
/// material is evaluated).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    /// The pbrt-v3 type name as written (`"matte"`, `"uber"`, …).
    pub type_name: String,
    /// The type.
    pub kind: MaterialKind,
    /// The values given.
    pub props: Props,
    /// For `mix`: the two blended materials, resolved.
    pub mix: Option<[u32; 2]>,
    /// Where the type is named in the scene file (`None` for the built-in default), for warnings.
    pub loc: Option<SourceLoc>,
    /// Where each given parameter is written, for warnings about its value.
    pub param_locs: Vec<(&'static str, SourceLoc)>,
}

impl MaterialSpec {
    /// pbrt-v3's default material: matte with Kd 0.5.
    pub fn default_matte() -> Self {
        MaterialSpec {
            type_name: "matte".into(),
            kind: MaterialKind::Matte,
            props: Props::default(),
            mix: None,
            loc: None,
            param_locs: Vec::new(),
        }
    }

    /// Where parameter `name` is written, else where the material is, if known.
    pub fn loc_of(&self, name: &str) -> Option<&SourceLoc> {
        self.param_locs.iter().find(|(n, _)| *n == name).map(|(_, l)| l).or(self.loc.as_ref())
    }

    /// Whether the surface has no BSDF (rays pass through it for shading, pbrt-v3 `bsdf == nullptr`).
    pub fn is_null(&self) -> bool {
        self.kind == MaterialKind::None
    }
}
