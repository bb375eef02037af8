//! STAGE 1 (parse): the directives of a pbrt-v3 scene file, as plain data.
//!
//! A [`Directive`] is one statement of the file with its source location; it knows nothing about what the
//! statement means for rendering (that is `scene::builder`'s job). `Include` never appears here: the parser
//! replaces it by the directives of the included file, each keeping its own file:line:col.

use crate::error::SourceLoc;
use crate::parse::params::ParamList;

/// One statement of a scene file and where it starts.
#[derive(Debug)]
pub struct Directive {
    /// What the statement says.
    pub kind: DirectiveKind,
    /// Where its keyword starts.
    pub loc: SourceLoc,
}

/// A typed name plus parameter list, the shape of most pbrt directives (`Shape "sphere" "float radius" 1`).
#[derive(Debug)]
pub struct Named {
    /// The quoted type or object name (`"sphere"`, `"perspective"`, a material name …).
    pub name: String,
    /// Where the quoted name starts (for "unknown shape type" messages).
    pub name_loc: SourceLoc,
    /// The parameters that follow it.
    pub params: ParamList,
}

/// Which transform(s) of a two-level (motion) transform later transform directives set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActiveTransform {
    /// `ActiveTransform StartTime`
    Start,
    /// `ActiveTransform EndTime`
    End,
    /// `ActiveTransform All`
    All,
}

/// Every pbrt-v3 directive except `Include` (inlined by the parser).
///
/// Numbers are kept as `f64` exactly as written; checks of meaning (finite transforms, known shape types,
/// matching AttributeBegin/End) belong to the scene builder, which reports them at [`Directive::loc`].
#[derive(Debug)]
pub enum DirectiveKind {
    /// `Identity`
    Identity,
    /// `Translate x y z`
    Translate([f64; 3]),
    /// `Scale x y z`
    Scale([f64; 3]),
    /// `Rotate angle_degrees x y z`
    Rotate([f64; 4]),
    /// `LookAt ex ey ez  lx ly lz  ux uy uz`
    LookAt([f64; 9]),
    /// `CoordinateSystem "name"`
    CoordinateSystem(String),
    /// `CoordSysTransform "name"`
    CoordSysTransform(String),
    /// `Transform [16 numbers]`, column-major as written in the file (not yet transposed).
    Transform([f64; 16]),
    /// `ConcatTransform [16 numbers]`, column-major as written in the file (not yet transposed).
    ConcatTransform([f64; 16]),
    /// `TransformTimes start end`
    TransformTimes(f64, f64),
    /// `ActiveTransform StartTime|EndTime|All`
    ActiveTransform(ActiveTransform),
    /// `ReverseOrientation`
    ReverseOrientation,
    /// `Camera "type" params`
    Camera(Named),
    /// `Sampler "type" params`
    Sampler(Named),
    /// `Film "type" params`
    Film(Named),
    /// `PixelFilter "type" params`
    PixelFilter(Named),
    /// `Integrator "type" params`
    Integrator(Named),
    /// `Accelerator "type" params`
    Accelerator(Named),
    /// `MakeNamedMedium "name" params`
    MakeNamedMedium(Named),
    /// `MediumInterface "inside" ["outside"]` (one name means both sides).
    MediumInterface(String, String),
    /// `WorldBegin`
    WorldBegin,
    /// `WorldEnd`
    WorldEnd,
    /// `AttributeBegin`
    AttributeBegin,
    /// `AttributeEnd`
    AttributeEnd,
    /// `TransformBegin`
    TransformBegin,
    /// `TransformEnd`
    TransformEnd,
    /// `ObjectBegin "name"`
    ObjectBegin(String),
    /// `ObjectEnd`
    ObjectEnd,
    /// `ObjectInstance "name"`
    ObjectInstance(String),
    /// `LightSource "type" params`
    LightSource(Named),
    /// `AreaLightSource "type" params`
    AreaLightSource(Named),
    /// `Material "type" params` (type may be "" or "none")
    Material(Named),
    /// `MakeNamedMaterial "name" params` (the type is the parameter `"string type"`)
    MakeNamedMaterial(Named),
    /// `NamedMaterial "name"`
    NamedMaterial(String),
    /// `Texture "name" "spectrum"|"float" "class" params`
    Texture {
        /// The texture's name.
        name: String,
        /// `"spectrum"` (also `"color"`, `"rgb"`) or `"float"`, as written.
        value_type: String,
        /// The texture class (`"imagemap"`, `"checkerboard"`, …), its location, and the parameters.
        class: Named,
    },
    /// `Shape "type" params`
    Shape(Named),
}

impl DirectiveKind {
    /// The keyword as written in scene files (`"Shape"`, `"AttributeBegin"` …), for messages.
    pub fn keyword(&self) -> &'static str {
        use DirectiveKind::*;
        match self {
            Identity => "Identity",
            Translate(_) => "Translate",
            Scale(_) => "Scale",
            Rotate(_) => "Rotate",
            LookAt(_) => "LookAt",
            CoordinateSystem(_) => "CoordinateSystem",
            CoordSysTransform(_) => "CoordSysTransform",
            Transform(_) => "Transform",
            ConcatTransform(_) => "ConcatTransform",
            TransformTimes(..) => "TransformTimes",
            ActiveTransform(_) => "ActiveTransform",
            ReverseOrientation => "ReverseOrientation",
            Camera(_) => "Camera",
            Sampler(_) => "Sampler",
            Film(_) => "Film",
            PixelFilter(_) => "PixelFilter",
            Integrator(_) => "Integrator",
            Accelerator(_) => "Accelerator",
            MakeNamedMedium(_) => "MakeNamedMedium",
            MediumInterface(..) => "MediumInterface",
            WorldBegin => "WorldBegin",
            WorldEnd => "WorldEnd",
            AttributeBegin => "AttributeBegin",
            AttributeEnd => "AttributeEnd",
            TransformBegin => "TransformBegin",
            TransformEnd => "TransformEnd",
            ObjectBegin(_) => "ObjectBegin",
            ObjectEnd => "ObjectEnd",
            ObjectInstance(_) => "ObjectInstance",
            LightSource(_) => "LightSource",
            AreaLightSource(_) => "AreaLightSource",
            Material(_) => "Material",
            MakeNamedMaterial(_) => "MakeNamedMaterial",
            NamedMaterial(_) => "NamedMaterial",
            Texture { .. } => "Texture",
            Shape(_) => "Shape",
        }
    }
}
