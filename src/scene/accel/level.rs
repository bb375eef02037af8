//! STAGE 2 (scene): one level of the two-level acceleration structure — a CWBVH built by obvhs over
//! triangles, analytic shapes, curve segments or instances, with the primitives stored in leaf order (a large
//! triangle split across several leaves appears in each) — and the build settings. The queries that walk
//! it are in the parent module.

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::ploc::PlocBuilder;
use obvhs::splits::split_aabbs_preset;
use obvhs::triangle::Triangle;

use super::{BuildPrim, Item, PrimRef, check_extent};
use crate::scene::shapes::curve::{Curve, CurveSegment};
use crate::scene::shapes::quadric::Quadric;

/// One BVH level: the tree plus its primitives in leaf order.
#[derive(Default)]
pub struct Level {
    pub(super) bvh: Option<CwBvh>,
    pub(super) items: Vec<Item>,
    /// World (or object) space bounds of everything in the level.
    pub bounds: Option<(Vec3A, Vec3A)>,
    /// Whether the tree is shallow and small enough for the distance-ordered nearest-hit search
    /// ([`NearStack::MAX_DEPTH`](super::traverse::NearStack::MAX_DEPTH)).
    pub(super) ordered: bool,
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
        let params = build_params(kept.len());
        let mut aabbs: Vec<Aabb> = kept.iter().map(|(_, (lo, hi))| Aabb::new(*lo, *hi)).collect();
        let mut indices: Vec<u32> = (0..kept.len() as u32).collect();
        if params.pre_split {
            split_triangles(prims, &kept, &mut aabbs, &mut indices);
        }
        let bounds = kept
            .iter()
            .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), (_, (a, b))| {
                (lo.min(*a), hi.max(*b))
            });
        let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
            params.ploc_search_distance,
            &aabbs,
            indices,
            params.sort_precision,
            params.search_depth_threshold,
        );
        bvh2.uses_spatial_splits = params.pre_split;
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        let bvh = bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
        let items: Vec<Item> = bvh
            .primitive_indices
            .iter()
            .map(|&k| {
                let p = &prims[kept[k as usize].0];
                Item { verts: p.verts, r: p.r }
            })
            .collect();
        let ordered =
            items.len() <= MAX_ORDERED_SLOTS && super::traverse::depth(&bvh) <= super::traverse::NearStack::MAX_DEPTH;
        Level { bvh: Some(bvh), items, bounds: Some(bounds), ordered }
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

/// The most leaf entries the distance-ordered search can address (it packs a leaf's first slot in 28 bits).
pub(super) const MAX_ORDERED_SLOTS: usize = 1 << 28;

/// Splits the boxes of large triangles among `kept` into several tighter ones (obvhs's preset, as its own
/// triangle builder does: a triangle spanning a room otherwise puts one box around empty space that every
/// ray through the room must enter). A split triangle's first box replaces its own and the others are
/// appended with its index; the first `kept.len()` entries of `indices` stay 0, 1, 2, … as obvhs's leaves
/// need (a leaf's primitive is looked up in the index list at the position its own index names). A
/// triangle then sits in several leaves; a query meeting it twice gets the same hit twice.
fn split_triangles(
    prims: &[BuildPrim],
    kept: &[(usize, (Vec3A, Vec3A))],
    aabbs: &mut Vec<Aabb>,
    indices: &mut Vec<u32>,
) {
    let tri_slots: Vec<u32> =
        (0..kept.len() as u32).filter(|&k| matches!(prims[kept[k as usize].0].r, PrimRef::Triangle { .. })).collect();
    if tri_slots.is_empty() {
        return;
    }
    // Indexed by slot in `kept` (only the triangles' entries are read).
    let tris: Vec<Triangle> = kept
        .iter()
        .map(|(i, _)| {
            let [v0, v1, v2] = prims[*i].verts.map(Vec3A::from);
            Triangle { v0, v1, v2 }
        })
        .collect();
    let mut boxes: Vec<Aabb> = tri_slots.iter().map(|&k| aabbs[k as usize]).collect();
    let mut idx = tri_slots.clone();
    let largest = boxes.iter().map(Aabb::half_area).fold(0.0f32, f32::max);
    let avg = boxes.iter().map(Aabb::half_area).sum::<f32>() / boxes.len() as f32;
    split_aabbs_preset(&mut boxes, &mut idx, &tris, avg, largest);
    if boxes.len() == tri_slots.len() {
        return;
    }
    // The pieces' corners are computed in floating point (the edge's crossing of the split plane), so a
    // piece may fall short of its part of the triangle by a rounding error: pad every piece of a split
    // triangle so no hit on the triangle lies outside all of its boxes.
    let mut pieces = vec![0u32; kept.len()];
    for &k in &idx {
        pieces[k as usize] += 1;
    }
    for (b, &k) in boxes.iter_mut().zip(&idx) {
        if pieces[k as usize] > 1 {
            *b = padded(*b);
        }
    }
    for (j, &k) in tri_slots.iter().enumerate() {
        aabbs[k as usize] = boxes[j];
    }
    aabbs.extend_from_slice(&boxes[tri_slots.len()..]);
    indices.extend_from_slice(&idx[tri_slots.len()..]);
}

/// `b` grown on every side by 2⁻²⁰ of its largest coordinate's magnitude (many ulps; the smallest normal
/// float where that is zero).
fn padded(b: Aabb) -> Aabb {
    let pad = (b.min.abs().max(b.max.abs()).max_element() * (1.0 / (1u32 << 20) as f32)).max(f32::MIN_POSITIVE);
    Aabb::new(b.min - Vec3A::splat(pad), b.max + Vec3A::splat(pad))
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
