//! STAGE 5 (shading): textures evaluated at a surface interaction, as pbrt-v3's `src/textures` define them.
//!
//! [`Textures::build`] turns every `Texture` of the scene into a `node::Node` (reading image files once
//! per distinct file and settings); [`Textures::spectrum`] and [`Textures::float`] evaluate one at a hit.
//! Supported: `constant`, `scale`, `mix`, `bilerp`, `checkerboard` (2-D, point-sampled, and 3-D), `dots`,
//! `uv` and `imagemap` (PNG, TGA, EXR, PFM), with the `uv`, `spherical`, `cylindrical` and `planar`
//! mappings. What differs from pbrt-v3, because cachert traces no ray differentials:
//! - image lookups are at the finest level of pbrt-v3's MIP map, with its EWA filter in the limit of a
//!   small footprint (or bilinear with `"bool trilinear" true`) — pbrt-v3 does the same wherever a ray's
//!   footprint is under a texel (see [`mipmap`]); minified textures are not prefiltered;
//! - the checkerboard's `closedform` antialiasing is a point sample (see `checkerboard`).
//!
//! `fbm`, `wrinkled`, `windy`, `marble` and `ptex` become the constant 1 with one warning each (the
//! shared scenes use none of them). pbrt-v3's quirks kept on purpose: an unreadable image is a grey 0.5
//! texel (sRGB-decoded for 8-bit files, times `scale`), and `dots` shows its `outside` texture inside the
//! dots and `inside` around them (v3's constructor takes them in the other order).
//!
//! Depends on `scene` (the stored textures and the surface interaction) and `image` (EXR/PFM readers);
//! never on `render`, `placement` or `application`. Evaluation does not allocate.

mod checkerboard;
mod imagemap;
mod mapping;
pub mod mipmap;
mod node;
mod noise;

use std::collections::HashMap;

use crate::error::{Result, Warnings};
use crate::scene::Scene;
use crate::scene::geometry::SurfaceInteraction;
use crate::scene::props::{Prop, Props};
use crate::scene::texture::{TextureSpec, TextureValue};

use super::Spectrum;
use imagemap::ImageKey;
use mapping::{MAPPING_NAMES, Mapping2D};
use mipmap::{MipMap, Wrap};
use node::{Filter, Input, Node};

pub use imagemap::inverse_gamma;

/// Textures nested deeper than this (through scale, mix, …) become the constant 1 with a warning, so
/// evaluation's recursion stays shallow.
const MAX_DEPTH: u32 = 64;

/// The scene's textures, ready to evaluate (images loaded).
#[derive(Debug, Default)]
pub struct Textures {
    nodes: Vec<Node>,
    images: Vec<MipMap>,
}

impl Textures {
    /// Prepares every texture of `scene`; problems that pbrt-v3 survives are warnings.
    pub fn build(scene: &Scene, warnings: &mut Warnings) -> Result<Textures> {
        let mut out = Textures::default();
        let mut cache: HashMap<ImageKey, u32> = HashMap::new();
        let mut depth: Vec<u32> = Vec::with_capacity(scene.textures.len());
        for (id, tex) in scene.textures.iter().enumerate() {
            let mut node = out.node(tex, id, &mut cache, warnings);
            let d = 1 + node.inputs().iter().flatten().map(|&i| depth[i as usize]).max().unwrap_or(0);
            if d > MAX_DEPTH {
                warnings.at(
                    &tex.loc,
                    format!("texture \"{}\" nests more than {MAX_DEPTH} textures; using the constant 1", tex.name),
                );
                node = Node::Constant(Spectrum::ONE);
            }
            depth.push(d.min(1 + MAX_DEPTH));
            out.nodes.push(node);
        }
        Ok(out)
    }

    /// Spectrum texture `id` (an index into `Scene::textures`) at `si`.
    pub fn spectrum(&self, id: u32, si: &SurfaceInteraction) -> Spectrum {
        self.eval(id, si)
    }

    /// Float texture `id` at `si`.
    pub fn float(&self, id: u32, si: &SurfaceInteraction) -> f32 {
        self.eval(id, si).x
    }

    /// How many distinct images were loaded (textures with the same file and settings share one).
    pub fn image_count(&self) -> usize {
        self.images.len()
    }

    /// The node for texture `id`, loading its image if it has one.
    fn node(&mut self, tex: &TextureSpec, id: usize, cache: &mut HashMap<ImageKey, u32>, w: &mut Warnings) -> Node {
        let p = &tex.props;
        let float = tex.value == TextureValue::Float;
        let warn = |w: &mut Warnings, msg: String| w.at(&tex.loc, format!("texture \"{}\": {msg}", tex.name));
        let mapping = |w: &mut Warnings| {
            Mapping2D::from_props(p, tex.texture_from_world).unwrap_or_else(|name| {
                let known = MAPPING_NAMES.join(", ");
                warn(w, format!("unknown mapping \"{name}\" (pbrt-v3 knows {known}); using \"uv\""));
                Mapping2D::IDENTITY
            })
        };
        let input = |name: &str, default: f32| tex_input(p, name, default, id);
        match tex.class.as_str() {
            "constant" => Node::Constant(value(p, "value", 1.0)),
            "scale" => Node::Scale(input("tex1", 1.0), input("tex2", 1.0)),
            "mix" => Node::Mix { tex1: input("tex1", 0.0), tex2: input("tex2", 1.0), amount: input("amount", 0.5) },
            "bilerp" => Node::Bilerp {
                mapping: mapping(w),
                v: [value(p, "v00", 0.0), value(p, "v01", 1.0), value(p, "v10", 0.0), value(p, "v11", 1.0)],
            },
            "checkerboard" => {
                let (tex1, tex2) = (input("tex1", 1.0), input("tex2", 0.0));
                match int(p, "dimension", 2) {
                    2 => {
                        let aa = p.str("aamode").unwrap_or("closedform");
                        if aa != "none" && aa != "closedform" {
                            warn(w, format!("unknown aamode \"{aa}\"; the checks are point-sampled"));
                        }
                        Node::Checker2D { mapping: mapping(w), tex1, tex2 }
                    }
                    // pbrt-v3 hands the CTM itself (world ← texture) to its 3-D mapping, which applies it
                    // as texture ← world; so do we.
                    3 => Node::Checker3D { texture_from_world: tex.texture_from_world.inverse(), tex1, tex2 },
                    d => {
                        warn(
                            w,
                            format!("a {d}-dimensional checkerboard does not exist (2 or 3); using the constant 1"),
                        );
                        Node::Constant(Spectrum::ONE)
                    }
                }
            }
            // pbrt-v3 passes "inside" where its constructor expects the outside texture and vice versa.
            "dots" => Node::Dots { mapping: mapping(w), in_dot: input("outside", 0.0), out_dot: input("inside", 1.0) },
            "uv" if float => {
                warn(w, "pbrt-v3 has no float \"uv\" texture; using the constant 1".into());
                Node::Constant(Spectrum::ONE)
            }
            "uv" => Node::Uv { mapping: mapping(w) },
            "imagemap" => {
                let mapping = mapping(w);
                let image = self.image(tex, float, cache, w);
                let filter =
                    if matches!(p.get("trilinear"), Some(Prop::Bool(true))) { Filter::Bilinear } else { Filter::Ewa };
                Node::Image { mapping, image, filter }
            }
            class @ ("fbm" | "wrinkled" | "windy" | "marble" | "ptex") => {
                warn(w, format!("texture class \"{class}\" is not supported by cachert; using the constant 1"));
                Node::Constant(Spectrum::ONE)
            }
            other => {
                warn(w, format!("unknown texture class \"{other}\"; using the constant 1"));
                Node::Constant(Spectrum::ONE)
            }
        }
    }

    /// The index of the loaded image an imagemap texture reads (loaded now unless an earlier texture
    /// read the same file with the same settings).
    fn image(&mut self, tex: &TextureSpec, float: bool, cache: &mut HashMap<ImageKey, u32>, w: &mut Warnings) -> u32 {
        let p = &tex.props;
        let path = p.str("filename").unwrap_or("");
        let wrap_name = p.str("wrap").unwrap_or("repeat");
        let wrap = Wrap::from_name(wrap_name).unwrap_or_else(|| {
            let msg = format!("texture \"{}\": unknown wrap mode \"{wrap_name}\"; using \"repeat\"", tex.name);
            w.at(&tex.loc, msg);
            Wrap::Repeat
        });
        let gamma = match p.get("gamma") {
            Some(Prop::Bool(g)) => *g,
            _ => imagemap::default_gamma(path),
        };
        let key = ImageKey::new(path, wrap, p.float("scale", 1.0), gamma, float);
        if let Some(&i) = cache.get(&key) {
            return i;
        }
        let (mipmap, err) = imagemap::load(&key);
        // A file that does not exist was reported when the scene was loaded.
        if let Some(e) = err.filter(|_| std::path::Path::new(path).is_file()) {
            w.at(
                &tex.loc,
                format!(
                    "texture \"{}\": cannot use image \"{path}\" ({e}); using pbrt-v3's grey 0.5 texel in its place",
                    tex.name
                ),
            );
        }
        let i = self.images.len() as u32;
        self.images.push(mipmap);
        cache.insert(key, i);
        i
    }
}

/// A colour or float parameter as a colour (floats become grey), or grey `default`.
fn value(p: &Props, name: &str, default: f32) -> Spectrum {
    match p.get(name) {
        Some(Prop::Rgb(c)) => Spectrum::from(*c),
        Some(Prop::Float(v)) => Spectrum::splat(*v),
        _ => Spectrum::splat(default),
    }
}

/// A texture-or-value parameter of texture `id` (references can only be to earlier textures).
fn tex_input(p: &Props, name: &str, default: f32, id: usize) -> Input {
    match p.get(name) {
        Some(Prop::SpectrumTexture(t) | Prop::FloatTexture(t)) if (*t as usize) < id => Input::Texture(*t),
        _ => Input::Value(value(p, name, default)),
    }
}

/// An integer parameter, or `default`.
fn int(p: &Props, name: &str, default: i64) -> i64 {
    match p.get(name) {
        Some(Prop::Int(v)) => *v,
        _ => default,
    }
}
