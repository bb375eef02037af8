//! STAGE 2 (scene): parameters of materials, textures and lights captured against a per-type schema.
//!
//! Each pbrt-v3 material, texture and light type lists the parameters it reads (name and kind, as in
//! pbrt-v3's `Create*` functions). Reading a directive through its schema checks every value's type, marks
//! what was used (so a typo such as `"rgb kd"` is reported as unused) and stores the values for the stage
//! that evaluates them. Texture references are resolved to texture ids here.

use std::collections::HashMap;

use crate::error::{Result, SourceLoc, Warnings};
use crate::parse::{ParamList, ParamType, ParamValue, TexOr};

/// What kind of value a schema entry reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A colour or the name of a spectrum texture.
    SpectrumTex,
    /// A float or the name of a float texture.
    FloatTex,
    /// A colour (rgb, xyz, blackbody or spectrum).
    Spectrum,
    /// One float.
    Float,
    /// A list of floats.
    Floats,
    /// One integer.
    Int,
    /// One bool.
    Bool,
    /// One string.
    Str,
    /// A file name (a string, resolved relative to the scene file that names it).
    File,
    /// One point.
    Point3,
    /// One vector.
    Vector3,
}

/// A captured value.
#[derive(Clone, Debug, PartialEq)]
pub enum Prop {
    /// A linear RGB colour.
    Rgb([f32; 3]),
    /// A spectrum texture id.
    SpectrumTexture(u32),
    /// A float.
    Float(f32),
    /// A float texture id.
    FloatTexture(u32),
    /// A list of floats.
    Floats(Vec<f32>),
    /// An integer.
    Int(i64),
    /// A bool.
    Bool(bool),
    /// A string (file names are stored resolved).
    Str(String),
    /// A point or vector.
    Vec3([f32; 3]),
}

/// The named values captured for one material, texture or light.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Props {
    entries: Vec<(&'static str, Prop)>,
}

impl Props {
    /// The value of `name`, if the scene gave one.
    pub fn get(&self, name: &str) -> Option<&Prop> {
        self.entries.iter().find(|(n, _)| *n == name).map(|(_, p)| p)
    }

    /// All captured values in schema order.
    pub fn iter(&self) -> impl Iterator<Item = &(&'static str, Prop)> {
        self.entries.iter()
    }

    /// Sets (or replaces) a value.
    pub fn set(&mut self, name: &'static str, p: Prop) {
        match self.entries.iter_mut().find(|(n, _)| *n == name) {
            Some(e) => e.1 = p,
            None => self.entries.push((name, p)),
        }
    }

    /// A float value, or `default`.
    pub fn float(&self, name: &str, default: f32) -> f32 {
        match self.get(name) {
            Some(Prop::Float(v)) => *v,
            _ => default,
        }
    }

    /// A colour value, or `default`.
    pub fn rgb(&self, name: &str, default: [f32; 3]) -> [f32; 3] {
        match self.get(name) {
            Some(Prop::Rgb(v)) => *v,
            _ => default,
        }
    }

    /// A string value.
    pub fn str(&self, name: &str) -> Option<&str> {
        match self.get(name) {
            Some(Prop::Str(s)) => Some(s),
            _ => None,
        }
    }
}

/// Texture names visible at a point of the scene file (pbrt-v3 keeps float and spectrum textures apart).
#[derive(Clone, Debug, Default)]
pub struct TextureScope {
    /// Float textures by name.
    pub float: HashMap<String, u32>,
    /// Spectrum textures by name.
    pub spectrum: HashMap<String, u32>,
}

/// Context for reading a directive through a schema.
pub struct Capture<'a> {
    /// Textures that may be referenced.
    pub textures: &'a TextureScope,
    /// Where the directive is (for messages about references).
    pub loc: &'a SourceLoc,
    /// Where warnings go.
    pub warnings: &'a mut Warnings,
}

impl Capture<'_> {
    /// Reads every schema entry present in `params` (marking them used) into `out`. A reference to an
    /// undefined texture is a warning and leaves the value unset (the type's default applies, as in pbrt-v3).
    pub fn read(&mut self, params: &ParamList, schema: &[(&'static str, Kind)], out: &mut Props) -> Result<()> {
        for &(name, kind) in schema {
            let v = match kind {
                Kind::SpectrumTex => match self.spectrum_file_fallback(params, name, |p| p.rgb_or_texture(name))? {
                    Some(TexOr::Value(c)) => Some(Prop::Rgb(c.map(|x| x as f32))),
                    Some(TexOr::Texture(t)) => self.texture(&t, name, false, params).map(Prop::SpectrumTexture),
                    None => None,
                },
                Kind::FloatTex => match params.float_or_texture(name)? {
                    Some(TexOr::Value(v)) => Some(Prop::Float(v as f32)),
                    Some(TexOr::Texture(t)) => self.texture(&t, name, true, params).map(Prop::FloatTexture),
                    None => None,
                },
                Kind::Spectrum => {
                    self.spectrum_file_fallback(params, name, |p| p.rgb(name))?.map(|c| Prop::Rgb(c.map(|x| x as f32)))
                }
                Kind::Float => params.float(name)?.map(|v| Prop::Float(v as f32)),
                Kind::Floats => params.floats(name)?.map(|v| Prop::Floats(v.iter().map(|&x| x as f32).collect())),
                Kind::Int => params.int(name)?.map(Prop::Int),
                Kind::Bool => params.bool(name)?.map(Prop::Bool),
                Kind::Str => params.string(name)?.map(|s| Prop::Str(s.to_string())),
                Kind::File => match params.string(name)? {
                    Some(s) => {
                        let loc = params.loc_of(name).unwrap_or(self.loc);
                        Some(Prop::Str(super::resolve_path(loc, s).display().to_string()))
                    }
                    None => None,
                },
                Kind::Point3 => params.point3(name)?.map(|v| Prop::Vec3(v.map(|x| x as f32))),
                Kind::Vector3 => params.vector3(name)?.map(|v| Prop::Vec3(v.map(|x| x as f32))),
            };
            if let Some(v) = v {
                out.set(name, v);
            }
        }
        Ok(())
    }

    /// Runs a colour lookup; a `spectrum` parameter naming a file that cannot be read (or a pbrt-v4 named
    /// spectrum) becomes a warning and leaves the value unset, so the type's default applies.
    fn spectrum_file_fallback<T>(
        &mut self,
        params: &ParamList,
        name: &str,
        f: impl Fn(&ParamList) -> Result<Option<T>>,
    ) -> Result<Option<T>> {
        match f(params) {
            Err(e)
                if params.iter().any(|p| {
                    p.name == name && p.ty == ParamType::Spectrum && matches!(p.value, ParamValue::Strings(_))
                }) =>
            {
                let loc = params.loc_of(name).unwrap_or(self.loc);
                let why = match e {
                    crate::error::Error::Scene { msg, .. } => msg,
                    other => other.to_string(),
                };
                self.warnings.at(loc, format!("{why}; using the default value"));
                Ok(None)
            }
            other => other,
        }
    }

    fn texture(&mut self, tex: &str, param: &str, float: bool, params: &ParamList) -> Option<u32> {
        let map = if float { &self.textures.float } else { &self.textures.spectrum };
        if let Some(&id) = map.get(tex) {
            return Some(id);
        }
        let loc = params.loc_of(param).unwrap_or(self.loc);
        let kind = if float { "float" } else { "spectrum" };
        self.warnings
            .at(loc, format!("parameter \"{param}\": no {kind} texture named \"{tex}\"; using the default value"));
        None
    }
}

/// The names a schema reads (for deciding whether a shape's parameters override its material's).
pub fn schema_has(schema: &[(&'static str, Kind)], name: &str) -> bool {
    schema.iter().any(|(n, _)| *n == name)
}
