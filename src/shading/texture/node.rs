//! STAGE 5 (shading): one prepared texture and its evaluation — pbrt-v3's texture classes as a closed set.
//!
//! Textures that read other textures (scale, mix, checkerboard, dots) hold their inputs as [`Input`]s: a
//! value or the id of an earlier texture, resolved through the [`Textures`] table at evaluation time, so
//! evaluating never allocates. Float textures evaluate to a grey colour (all three channels equal).
//!
//! Depends on the mappings, the mip map and the patterns beside it.

use glam::Affine3A;

use super::checkerboard::{checker_2d_first, checker_3d_first, in_dot};
use super::mapping::{Mapping2D, map_3d};
use super::{Spectrum, Textures};
use crate::scene::geometry::SurfaceInteraction;

/// A texture's input: a value, or another (earlier) texture by id.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// A constant (grey for a float input).
    Value(Spectrum),
    /// Texture id (an index into `Scene::textures`).
    Texture(u32),
}

/// How an image texture is filtered (see [`super::mipmap`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Bilinear (`"bool trilinear" true`).
    Bilinear,
    /// pbrt-v3's EWA at a vanishing footprint (the default).
    Ewa,
}

/// A texture ready to evaluate.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// `constant` (and every fallback).
    Constant(Spectrum),
    /// `scale`: tex1 · tex2.
    Scale(Input, Input),
    /// `mix`: (1 − amount)·tex1 + amount·tex2, amount a float.
    Mix {
        /// `tex1`
        tex1: Input,
        /// `tex2`
        tex2: Input,
        /// `amount`
        amount: Input,
    },
    /// `bilerp`: bilinear in (s, t) between four corner values `[v00, v01, v10, v11]`.
    Bilerp {
        /// The mapping.
        mapping: Mapping2D,
        /// `v00`, `v01`, `v10`, `v11`.
        v: [Spectrum; 4],
    },
    /// 2-D `checkerboard`, point-sampled.
    Checker2D {
        /// The mapping.
        mapping: Mapping2D,
        /// Where ⌊s⌋ + ⌊t⌋ is even.
        tex1: Input,
        /// Elsewhere.
        tex2: Input,
    },
    /// 3-D `checkerboard` (`"integer dimension" 3`) in texture space.
    Checker3D {
        /// The transform applied to world points: the CTM at the `Texture` directive, as pbrt-v3 applies it.
        texture_from_world: Affine3A,
        /// Where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ is even.
        tex1: Input,
        /// Elsewhere.
        tex2: Input,
    },
    /// `dots`.
    Dots {
        /// The mapping.
        mapping: Mapping2D,
        /// What shows inside a dot.
        in_dot: Input,
        /// What shows elsewhere.
        out_dot: Input,
    },
    /// `uv`: the fractional parts of (s, t) as red and green.
    Uv {
        /// The mapping.
        mapping: Mapping2D,
    },
    /// `imagemap`.
    Image {
        /// The mapping.
        mapping: Mapping2D,
        /// Index into the loaded images.
        image: u32,
        /// The lookup filter.
        filter: Filter,
    },
}

impl Node {
    /// The texture ids this node reads.
    pub fn inputs(&self) -> [Option<u32>; 3] {
        let id = |i: &Input| match i {
            Input::Texture(t) => Some(*t),
            Input::Value(_) => None,
        };
        match self {
            Node::Scale(a, b) => [id(a), id(b), None],
            Node::Mix { tex1, tex2, amount } => [id(tex1), id(tex2), id(amount)],
            Node::Checker2D { tex1, tex2, .. } | Node::Checker3D { tex1, tex2, .. } => [id(tex1), id(tex2), None],
            Node::Dots { in_dot, out_dot, .. } => [id(in_dot), id(out_dot), None],
            _ => [None; 3],
        }
    }
}

impl Textures {
    /// Texture `id` at `si` (1 for an id that does not exist).
    pub(super) fn eval(&self, id: u32, si: &SurfaceInteraction) -> Spectrum {
        let Some(node) = self.nodes.get(id as usize) else { return Spectrum::ONE };
        match node {
            Node::Constant(v) => *v,
            Node::Scale(a, b) => self.input(a, si) * self.input(b, si),
            Node::Mix { tex1, tex2, amount } => {
                let (t1, t2) = (self.input(tex1, si), self.input(tex2, si));
                let amt = self.input(amount, si).x;
                (1.0 - amt) * t1 + amt * t2
            }
            Node::Bilerp { mapping, v } => {
                let [s, t] = mapping.map(si);
                (1.0 - s) * (1.0 - t) * v[0] + (1.0 - s) * t * v[1] + s * (1.0 - t) * v[2] + s * t * v[3]
            }
            Node::Checker2D { mapping, tex1, tex2 } => {
                self.input(if checker_2d_first(mapping.map(si)) { tex1 } else { tex2 }, si)
            }
            Node::Checker3D { texture_from_world, tex1, tex2 } => {
                let p = map_3d(texture_from_world, si);
                self.input(if checker_3d_first(p.into()) { tex1 } else { tex2 }, si)
            }
            Node::Dots { mapping, in_dot: inside, out_dot } => {
                self.input(if in_dot(mapping.map(si)) { inside } else { out_dot }, si)
            }
            Node::Uv { mapping } => {
                let [s, t] = mapping.map(si);
                Spectrum::new(s - s.floor(), t - t.floor(), 0.0)
            }
            Node::Image { mapping, image, filter } => {
                let st = mapping.map(si);
                let m = &self.images[*image as usize];
                Spectrum::from(match filter {
                    Filter::Bilinear => m.bilinear(st),
                    Filter::Ewa => m.ewa(st),
                })
            }
        }
    }

    #[inline]
    fn input(&self, i: &Input, si: &SurfaceInteraction) -> Spectrum {
        match i {
            Input::Value(v) => *v,
            Input::Texture(id) => self.eval(*id, si),
        }
    }
}
