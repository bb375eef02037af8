//! STAGE 2 (scene): pbrt-v3 light sources (`LightSource`, `AreaLightSource`), stored with their parameters
//! and transforms for the lighting stage. Schemas follow src/lights/*.cpp.

use glam::Affine3A;

use crate::error::SourceLoc;
use crate::scene::props::{Kind, Props};

use Kind::*;

/// The parameters light type `name` reads, or `None` for a type pbrt-v3 does not have.
pub fn schema(name: &str) -> Option<&'static [(&'static str, Kind)]> {
    Some(match name {
        "point" => &[("I", Spectrum), ("scale", Spectrum), ("from", Point3)],
        "spot" => &[
            ("I", Spectrum),
            ("scale", Spectrum),
            ("coneangle", Float),
            ("conedeltaangle", Float),
            ("from", Point3),
            ("to", Point3),
        ],
        "goniometric" => &[("I", Spectrum), ("scale", Spectrum), ("mapname", File)],
        "projection" => &[("I", Spectrum), ("scale", Spectrum), ("fov", Float), ("mapname", File)],
        "distant" => &[("L", Spectrum), ("scale", Spectrum), ("from", Point3), ("to", Point3)],
        "infinite" | "exinfinite" => {
            &[("L", Spectrum), ("scale", Spectrum), ("nsamples", Int), ("samples", Int), ("mapname", File)]
        }
        _ => return None,
    })
}

/// The parameters of an area light (`"diffuse"`, also accepted as `"area"`).
pub const AREA_SCHEMA: &[(&str, Kind)] =
    &[("L", Spectrum), ("scale", Spectrum), ("twosided", Bool), ("nsamples", Int), ("samples", Int)];

/// A light source that is not attached to a shape.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSpec {
    /// pbrt-v3 type name.
    pub type_name: String,
    /// The values given.
    pub props: Props,
    /// World ← light space (the CTM at the directive).
    pub world_from_light: Affine3A,
    /// Where the `LightSource` directive is (for messages about its values).
    pub loc: SourceLoc,
}

/// An emitting shape: a mesh or quadric with a diffuse area light.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLightSpec {
    /// The values given.
    pub props: Props,
    /// The emitting shape.
    pub shape: crate::scene::geometry::ShapeId,
    /// Where the `AreaLightSource` directive is (for messages about its values).
    pub loc: SourceLoc,
}
