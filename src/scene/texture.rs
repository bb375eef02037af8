//! STAGE 2 (scene): pbrt-v3 textures (`Texture "name" "float"|"spectrum" "class" …`), stored with their
//! parameters. Image files are checked when the texture is declared; a missing file is a warning and the
//! texture becomes the constant 1, as pbrt-v3 does when it cannot read an image.

use glam::Affine3A;

use crate::error::SourceLoc;
use crate::scene::props::{Kind, Props};

/// Whether a texture yields floats or colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureValue {
    /// `"float"`
    Float,
    /// `"spectrum"` / `"color"` / `"rgb"`
    Spectrum,
}

use Kind::*;

const MAPPING: [(&str, Kind); 7] = [
    ("mapping", Str),
    ("uscale", Float),
    ("vscale", Float),
    ("udelta", Float),
    ("vdelta", Float),
    ("v1", Vector3),
    ("v2", Vector3),
];

/// The parameters texture class `class` reads, or `None` for a class pbrt-v3 does not have.
/// (`value` decides the kind of the `tex1`/`tex2`-style inputs.)
pub fn schema(class: &str, value: TextureValue) -> Option<Vec<(&'static str, Kind)>> {
    let input = if value == TextureValue::Float { FloatTex } else { SpectrumTex };
    let constant = if value == TextureValue::Float { Float } else { Spectrum };
    let mut s: Vec<(&'static str, Kind)> = match class {
        "constant" => vec![("value", constant)],
        "scale" => vec![("tex1", input), ("tex2", input)],
        "mix" => vec![("tex1", input), ("tex2", input), ("amount", FloatTex)],
        "bilerp" => vec![("v00", constant), ("v01", constant), ("v10", constant), ("v11", constant)],
        "imagemap" => vec![
            ("filename", File),
            ("maxanisotropy", Float),
            ("trilinear", Bool),
            ("wrap", Str),
            ("scale", Float),
            ("gamma", Bool),
        ],
        "uv" => vec![],
        "checkerboard" => vec![("tex1", input), ("tex2", input), ("dimension", Int), ("aamode", Str)],
        "dots" => vec![("inside", input), ("outside", input)],
        "fbm" | "wrinkled" => vec![("octaves", Int), ("roughness", Float)],
        "windy" => vec![],
        "marble" => vec![("octaves", Int), ("roughness", Float), ("scale", Float), ("variation", Float)],
        "ptex" => vec![("filename", File), ("gamma", Float)],
        _ => return None,
    };
    if matches!(class, "bilerp" | "imagemap" | "uv" | "checkerboard" | "dots") {
        s.extend(MAPPING);
    }
    Some(s)
}

/// A declared texture.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSpec {
    /// Its name in the scene.
    pub name: String,
    /// Float or colour.
    pub value: TextureValue,
    /// The class (`"imagemap"`, `"checkerboard"`, …); `"constant"` for a fallback.
    pub class: String,
    /// The values given.
    pub props: Props,
    /// Texture space ← world: the inverse of the CTM at declaration (pbrt-v3's spherical and cylindrical
    /// mappings use it; its 3-D mappings apply the CTM itself, i.e. this transform's inverse).
    pub texture_from_world: Affine3A,
    /// Where the `Texture` directive is (for warnings about it when its image is read).
    pub loc: SourceLoc,
}
