//! STAGE 2 (scene): one level of the two-level acceleration structure — a CWBVH built by obvhs over
//! triangles, analytic shapes, curve segments or instances, with the primitives stored in leaf order — and
//! the build settings. The queries that walk it are in the parent module.

use std::time::Duration;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::{Boundable, BvhBuildParams};

use super::{BuildPrim, Item, PrimRef, check_extent};
use crate::scene::shapes::curve::{Curve, CurveSegment};
use crate::scene::shapes::quadric::Quadric;

struct Boxed(Aabb);

impl Boundable for Boxed {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// One BVH level: the tree plus its primitives in leaf order.
#[derive(Default)]
pub struct Level {
    pub(super) bvh: Option<CwBvh>,
    pub(super) items: Vec<Item>,
    /// World (or object) space bounds of everything in the level.
    pub bounds: Option<(Vec3A, Vec3A)>,
}

impl std::fmt::Debug for Level {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Level").field("primitives", &self.items.len()).field("bounds", &self.bounds).finish()
    }
}

impl Level {
    /// Builds the BVH over `prims` (zero-area triangles and primitives outside ±[`MAX_COORD`](super::MAX_COORD) left out);
    /// `instance_box` gives an instance's world box.
    pub(super) fn build(
        prims: &[BuildPrim],
        shapes: &Shapes<'_>,
        instance_box: &dyn Fn(u32) -> Option<(Vec3A, Vec3A)>,
    ) -> Level {
        let boxes: Vec<Option<(Vec3A, Vec3A)>> = prims
            .iter()
            .map(|p| match p.r {
                PrimRef::Triangle { .. } => {
                    let [a, b, c] = p.verts.map(Vec3A::from);
                    // A triangle of zero area can never be hit (the watertight test needs det ≠ 0);
                    // leaving it out of the tree changes no answer and saves every test of it.
                    if (b - a).cross(c - a) == Vec3A::ZERO {
                        return None;
                    }
                    shapes.bounds(p)
                }
                PrimRef::Instance(i) => instance_box(i),
                _ => shapes.bounds(p),
            })
            .collect();
        let kept: Vec<(usize, (Vec3A, Vec3A))> = boxes
            .iter()
            .enumerate()
            // The scene builder refuses shapes outside ±MAX_COORD with an error; this keeps the BVH build
            // safe for any other caller.
            .filter_map(|(i, b)| b.filter(|(lo, hi)| check_extent(*lo, *hi).is_ok()).map(|b| (i, b)))
            .collect();
        if kept.is_empty() {
            return Level::default();
        }
        let aabbs: Vec<Boxed> = kept.iter().map(|(_, (lo, hi))| Boxed(Aabb::new(*lo, *hi))).collect();
        let bounds = kept
            .iter()
            .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), (_, (a, b))| {
                (lo.min(*a), hi.max(*b))
            });
        let bvh = build_cwbvh(&aabbs, build_params(aabbs.len()), &mut Duration::default());
        let items = bvh
            .primitive_indices
            .iter()
            .map(|&k| {
                let p = &prims[kept[k as usize].0];
                Item { verts: p.verts, r: p.r }
            })
            .collect();
        Level { bvh: Some(bvh), items, bounds: Some(bounds) }
    }

    /// Number of primitives in this level.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether the level has no primitives.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

/// Levels with at most this many primitives get obvhs's most thorough build.
///
/// Its reinsertion pass moves every node once (ratio 1, against 0.05) and costs about 3 µs per primitive
/// (0.2 s for sibenik's 75 284 triangles, 1.8 s more than the default for the bathroom's 592 188). On a
/// small scene the tree it makes is faster to trace: on the Cornell box (36 triangles) irradiance caching's
/// gather took 6 % less time and `directlighting` 6 % less; on sibenik `path` took the same time with
/// either, so the larger levels keep obvhs's medium build.
const THOROUGH_BUILD_MAX: usize = 100_000;

/// The BVH build settings for a level of `n` primitives (see [`THOROUGH_BUILD_MAX`]).
fn build_params(n: usize) -> BvhBuildParams {
    if n <= THOROUGH_BUILD_MAX { BvhBuildParams::very_slow_build() } else { BvhBuildParams::medium_build() }
}

/// The analytic shapes and curves that [`BuildPrim`]s refer to.
#[derive(Clone, Copy, Debug)]
pub struct Shapes<'a> {
    /// Analytic shapes, indexed by [`PrimRef::Quadric`].
    pub quadrics: &'a [Quadric],
    /// Curve pieces, indexed by [`CurveSegment::curve`].
    pub curves: &'a [Curve],
    /// Curve segments, indexed by [`PrimRef::Curve`].
    pub curve_segments: &'a [CurveSegment],
}

impl Shapes<'_> {
    /// The box of a triangle, analytic shape or curve segment in the space it was given in (`None` for an
    /// instance, whose box depends on its object's BVH, or for an index out of range).
    pub fn bounds(&self, p: &BuildPrim) -> Option<(Vec3A, Vec3A)> {
        match p.r {
            PrimRef::Triangle { .. } => {
                let [a, b, c] = p.verts.map(Vec3A::from);
                Some((a.min(b).min(c), a.max(b).max(c)))
            }
            PrimRef::Quadric(q) => self.quadrics.get(q as usize).map(Quadric::world_bounds),
            PrimRef::Curve(c) => {
                let seg = self.curve_segments.get(c as usize)?;
                self.curves.get(seg.curve as usize).map(|curve| curve.world_bounds(seg))
            }
            PrimRef::Instance(_) => None,
        }
    }
}
