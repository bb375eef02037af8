//! STAGE 2 (scene, accelerator internals): ray traversal of obvhs's compressed wide BVH with our own node
//! test. obvhs's built-in test clamps the entry distance to a fixed 1e-4 (so boxes closer than that to the
//! origin are culled — shadow rays leaving a corner would miss the adjacent wall) and uses no rounding
//! margin; this one clips to [0, t_max·(1 + 2γ₃)] like pbrt-v3's `Bounds3::IntersectP`, so no hit the
//! primitive test would report is ever culled. The traversal order and stack are obvhs's (`traverse!`).

use std::mem::MaybeUninit;

use glam::{UVec2, Vec3A, uvec2};
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::faststack::FastStack;

use crate::scene::ray::gamma;

/// Depth of the traversal stack (obvhs's own; its build keeps trees shallower than this).
const STACK_SIZE: usize = 32;

/// The traversal stack of [`Traversal`]: obvhs's fixed-size stack without zero-filling its 32 entries for
/// every ray (only written entries are ever read).
pub(super) struct Stack {
    data: [MaybeUninit<UVec2>; STACK_SIZE],
    index: usize,
}

impl FastStack<UVec2> for Stack {
    /// Pushes; a full stack overwrites its top entry (obvhs's behaviour).
    #[inline(always)]
    fn push(&mut self, v: UVec2) {
        self.data[self.index] = MaybeUninit::new(v);
        self.index = (self.index + 1).min(STACK_SIZE - 1);
    }

    #[inline(always)]
    fn pop_fast(&mut self) -> UVec2 {
        if self.index == 0 {
            return UVec2::ZERO;
        }
        self.index -= 1;
        // SAFETY: every entry below the pre-pop index was written by `push`.
        unsafe { self.data[self.index].assume_init() }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<UVec2> {
        (self.index > 0).then(|| self.pop_fast())
    }

    #[inline(always)]
    fn len(&self) -> usize {
        self.index
    }

    #[inline(always)]
    fn is_empty(&self) -> bool {
        self.index == 0
    }

    #[inline(always)]
    fn clear(&mut self) {
        self.index = 0;
    }
}

/// The state `obvhs::traverse!` works on (the fields of obvhs's `Traversal` that the macro uses).
pub(super) struct Traversal {
    pub stack: Stack,
    pub current_group: UVec2,
    pub primitive_group: UVec2,
    pub oct_inv4: u32,
    pub primitive_id: u32,
    pub hitmask: u32,
}

impl Traversal {
    /// The start of a traversal of `bvh` in direction `d` (children are visited in the order obvhs picks
    /// for the direction's octant).
    #[inline(always)]
    pub fn new(bvh: &CwBvh, d: Vec3A) -> Self {
        let oct_inv4 = (if d.x.is_sign_negative() { 0 } else { 0x0404_0404 })
            | (if d.y.is_sign_negative() { 0 } else { 0x0202_0202 })
            | (if d.z.is_sign_negative() { 0 } else { 0x0101_0101 });
        Traversal {
            stack: Stack { data: [const { MaybeUninit::uninit() }; STACK_SIZE], index: 0 },
            current_group: if bvh.nodes.is_empty() { UVec2::ZERO } else { uvec2(0, 0x8000_0000) },
            primitive_group: UVec2::ZERO,
            oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// Capacity of [`NearStack`]. A node visit pushes at most 8 children and pops one, so a tree of depth d never
/// holds more than 7·d + 1 entries; levels deeper than [`NearStack::MAX_DEPTH`] use obvhs's traversal.
const NEAR_STACK: usize = 256;

/// The nodes the nearest-hit search has still to visit, each with the distance at which the ray enters its
/// box, the nearest on top.
pub(super) struct NearStack {
    data: [MaybeUninit<(u32, f32)>; NEAR_STACK],
    len: usize,
}

impl NearStack {
    /// The deepest tree (in node levels) whose search fits the stack.
    pub const MAX_DEPTH: usize = (NEAR_STACK - 1) / 7;

    /// An empty stack.
    #[inline(always)]
    pub fn new() -> Self {
        NearStack { data: [const { MaybeUninit::uninit() }; NEAR_STACK], len: 0 }
    }

    /// Pushes node `node` entered at distance `t`.
    #[inline(always)]
    pub fn push(&mut self, node: u32, t: f32) {
        // Indexing checks the bound: unreachable for trees within MAX_DEPTH.
        self.data[self.len] = MaybeUninit::new((node, t));
        self.len += 1;
    }

    /// The number of entries.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Orders the entries from `from` on by decreasing distance, so the nearest of them is popped first
    /// (insertion sort: at most 8 entries).
    #[inline(always)]
    pub fn sort_from(&mut self, from: usize) {
        for i in from + 1..self.len {
            // SAFETY: entries below `len` were written by `push`.
            let x = unsafe { self.data[i].assume_init() };
            let mut j = i;
            while j > from && unsafe { self.data[j - 1].assume_init().1 } < x.1 {
                self.data[j] = self.data[j - 1];
                j -= 1;
            }
            self.data[j] = MaybeUninit::new(x);
        }
    }

    /// Pops the top entry.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<(u32, f32)> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below the pre-pop `len` were written by `push`.
        Some(unsafe { self.data[self.len].assume_init() })
    }
}

/// The depth of `bvh` in node levels (1 for a root alone, 0 for an empty tree).
pub(super) fn depth(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut todo = vec![(0u32, 1usize)];
    while let Some((i, d)) = todo.pop() {
        deepest = deepest.max(d);
        let n = &bvh.nodes[i as usize];
        for k in 0..n.imask.count_ones() {
            todo.push((n.child_base_idx + k, d + 1));
        }
    }
    deepest
}

/// The far limit the node test uses for a search limited to `t_max` (the rounding margin of
/// pbrt-v3's `Bounds3::IntersectP`).
#[inline(always)]
pub(super) fn far_limit(t_max: f32) -> f32 {
    t_max * (1.0 + 2.0 * gamma(3))
}

/// Per-ray constants of the node test.
#[derive(Clone, Copy, Debug)]
pub(super) struct TravRay {
    o: Vec3A,
    inv_d: Vec3A,
    neg: [bool; 3],
    /// Current far limit of the search (shrinks as closer hits are found).
    pub t_max: f32,
}

/// Smallest |direction component| used for the reciprocal (an exact 0 would give ∞·0 = NaN in the slab test).
const TINY: f32 = 1e-30;

impl TravRay {
    /// Constants for the ray (o, d) searched up to `t_max`.
    #[inline]
    pub fn new(o: Vec3A, d: Vec3A, t_max: f32) -> Self {
        let safe = |v: f32| if v.abs() < TINY { TINY.copysign(v) } else { v };
        let inv_d = Vec3A::new(1.0 / safe(d.x), 1.0 / safe(d.y), 1.0 / safe(d.z));
        TravRay { o, inv_d, neg: [d.x.is_sign_negative(), d.y.is_sign_negative(), d.z.is_sign_negative()], t_max }
    }
}

/// The obvhs child hit mask of `node` for `r` (bit layout as `CwBvhNode::intersect_ray`). `WIDE` selects
/// the 8-wide AVX2 box test: callers instantiate it only inside a function compiled with AVX2 enabled
/// (see [`has_avx2`]), so it inlines there.
#[inline(always)]
pub(super) fn intersect_node<const WIDE: bool>(node: &CwBvhNode, r: &TravRay, oct_inv4: u32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if WIDE {
        // SAFETY: WIDE is true only on paths entered after `has_avx2()` returned true.
        return unsafe { hit_mask_avx2(node, r, oct_inv4) };
    }
    let mut mask = child_mask(node, r);
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut hit_mask = 0u32;
    while mask != 0 {
        let child = mask.trailing_zeros();
        mask &= mask - 1;
        let bits = ((child_bits8 >> (child * 8)) as u32) & 0xff;
        let index = ((bit_index8 >> (child * 8)) as u32) & 0xff;
        hit_mask |= bits << index;
    }
    hit_mask
}

/// The slab-test inputs of a node for a ray: per axis the quantised near/far planes (swapped for negative
/// directions), and the scale and offset that turn a quantised plane into a ray distance.
#[inline(always)]
fn setup<'a>(node: &'a CwBvhNode, r: &TravRay) -> ([&'a [u8; 8]; 6], Vec3A, Vec3A, f32) {
    let adj_inv = node.compute_extent() * r.inv_d;
    let adj_o = (Vec3A::from(node.p) - r.o) * r.inv_d;
    let pick = |lo: &'a [u8; 8], hi: &'a [u8; 8], neg: bool| if neg { [hi, lo] } else { [lo, hi] };
    let [x0, x1] = pick(&node.child_min_x, &node.child_max_x, r.neg[0]);
    let [y0, y1] = pick(&node.child_min_y, &node.child_max_y, r.neg[1]);
    let [z0, z1] = pick(&node.child_min_z, &node.child_max_z, r.neg[2]);
    ([x0, x1, y0, y1, z0, z1], adj_inv, adj_o, far_limit(r.t_max))
}

/// The entry and exit distances of children 4·half … 4·half + 3 (SSE2 lanes): the slab test's clipped
/// [t_min, t_max] per child, empty where t_min > t_max.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn half_slabs(
    q: &[&[u8; 8]; 6],
    inv: Vec3A,
    org: Vec3A,
    t_far: f32,
    half: usize,
) -> (std::arch::x86_64::__m128, std::arch::x86_64::__m128) {
    use std::arch::x86_64::*;
    #[inline(always)]
    fn load(v: &[u8; 8], half: usize) -> __m128 {
        let w = u32::from_le_bytes([v[4 * half], v[4 * half + 1], v[4 * half + 2], v[4 * half + 3]]);
        // SAFETY: SSE2 is part of the x86_64 baseline.
        unsafe {
            let z = _mm_setzero_si128();
            _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(w as i32), z), z))
        }
    }
    // SAFETY: SSE2 arithmetic only.
    unsafe {
        let (ix, iy, iz) = (_mm_set1_ps(inv.x), _mm_set1_ps(inv.y), _mm_set1_ps(inv.z));
        let (ox, oy, oz) = (_mm_set1_ps(org.x), _mm_set1_ps(org.y), _mm_set1_ps(org.z));
        let t0x = _mm_add_ps(_mm_mul_ps(load(q[0], half), ix), ox);
        let t1x = _mm_add_ps(_mm_mul_ps(load(q[1], half), ix), ox);
        let t0y = _mm_add_ps(_mm_mul_ps(load(q[2], half), iy), oy);
        let t1y = _mm_add_ps(_mm_mul_ps(load(q[3], half), iy), oy);
        let t0z = _mm_add_ps(_mm_mul_ps(load(q[4], half), iz), oz);
        let t1z = _mm_add_ps(_mm_mul_ps(load(q[5], half), iz), oz);
        let tmin = _mm_max_ps(_mm_max_ps(t0x, t0y), _mm_max_ps(t0z, _mm_setzero_ps()));
        let tmax = _mm_min_ps(_mm_min_ps(t1x, t1y), _mm_min_ps(t1z, _mm_set1_ps(t_far)));
        (tmin, tmax)
    }
}

/// Bit c set when child c's quantised box overlaps the ray segment [0, t_max·(1 + 2γ₃)] (4 at a time).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn child_mask(node: &CwBvhNode, r: &TravRay) -> u32 {
    child_entries_sse(node, r).1
}

/// [`child_entries`] four children at a time (SSE2).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn child_entries_sse(node: &CwBvhNode, r: &TravRay) -> ([f32; 8], u32) {
    use std::arch::x86_64::*;
    let (q, inv, org, t_far) = setup(node, r);
    let mut mask = 0u32;
    let mut entry = [0.0f32; 8];
    for half in 0..2 {
        let (tmin, tmax) = half_slabs(&q, inv, org, t_far, half);
        // SAFETY: SSE2 only; the store writes 4 of `entry`'s 8 floats.
        unsafe {
            mask |= (_mm_movemask_ps(_mm_cmple_ps(tmin, tmax)) as u32) << (4 * half);
            _mm_storeu_ps(entry.as_mut_ptr().add(4 * half), tmin);
        }
    }
    (entry, mask)
}

/// Each child's entry distance (its box's clipped t_min) and the mask of the children whose boxes overlap
/// [0, t_max·(1 + 2γ₃)] (bit c for child slot c). The distances order the nearest-hit search; an entry is
/// meaningful only where its bit is set. `WIDE` as for [`intersect_node`].
#[inline(always)]
pub(super) fn child_entries<const WIDE: bool>(node: &CwBvhNode, r: &TravRay) -> ([f32; 8], u32) {
    #[cfg(target_arch = "x86_64")]
    {
        if WIDE {
            // SAFETY: WIDE is true only on paths entered after `has_avx2()` returned true.
            return unsafe { child_entries_avx2(node, r) };
        }
        child_entries_sse(node, r)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        child_entries_portable(node, r)
    }
}

/// [`child_mask`] for all 8 children at once. The same operations in the same order (multiply, then add;
/// no fused multiply-add), so it visits exactly the nodes the SSE2 version visits and images do not depend
/// on the CPU. (Traversal uses [`hit_mask_avx2`]; this is what the tests compare lane by lane.)
#[cfg(all(test, target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
unsafe fn child_mask_avx2(node: &CwBvhNode, r: &TravRay) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is enabled in this function.
    _mm256_movemask_ps(unsafe { child_hits_avx2(node, r) }) as u32
}

/// The 8-wide slab test, the same operations in the same order as [`half_slabs`]'s (multiply, then add; no
/// fused multiply-add), so it visits exactly the nodes the SSE2 version visits and images do not depend on
/// the CPU: each child's clipped [t_min, t_max].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn slabs_avx2(node: &CwBvhNode, r: &TravRay) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    use std::arch::x86_64::*;
    #[inline(always)]
    fn load(v: &[u8; 8]) -> __m256 {
        // SAFETY: reads exactly the 8 bytes of `v`; only called where AVX2 is enabled.
        unsafe { _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(v.as_ptr() as *const __m128i))) }
    }
    let (q, inv, org, t_far) = setup(node, r);
    let (ix, iy, iz) = (_mm256_set1_ps(inv.x), _mm256_set1_ps(inv.y), _mm256_set1_ps(inv.z));
    let (ox, oy, oz) = (_mm256_set1_ps(org.x), _mm256_set1_ps(org.y), _mm256_set1_ps(org.z));
    let t0x = _mm256_add_ps(_mm256_mul_ps(load(q[0]), ix), ox);
    let t1x = _mm256_add_ps(_mm256_mul_ps(load(q[1]), ix), ox);
    let t0y = _mm256_add_ps(_mm256_mul_ps(load(q[2]), iy), oy);
    let t1y = _mm256_add_ps(_mm256_mul_ps(load(q[3]), iy), oy);
    let t0z = _mm256_add_ps(_mm256_mul_ps(load(q[4]), iz), oz);
    let t1z = _mm256_add_ps(_mm256_mul_ps(load(q[5]), iz), oz);
    let tmin = _mm256_max_ps(_mm256_max_ps(t0x, t0y), _mm256_max_ps(t0z, _mm256_setzero_ps()));
    let tmax = _mm256_min_ps(_mm256_min_ps(t1x, t1y), _mm256_min_ps(t1z, _mm256_set1_ps(t_far)));
    (tmin, tmax)
}

/// All ones in lane c when child c is hit ([`slabs_avx2`]'s t_min ≤ t_max).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn child_hits_avx2(node: &CwBvhNode, r: &TravRay) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is enabled in this function.
    let (tmin, tmax) = unsafe { slabs_avx2(node, r) };
    _mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax)
}

/// [`child_entries`] with the 8-wide slab test.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn child_entries_avx2(node: &CwBvhNode, r: &TravRay) -> ([f32; 8], u32) {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is enabled in this function; the store writes `entry`'s 8 floats.
    unsafe {
        let (tmin, tmax) = slabs_avx2(node, r);
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax)) as u32;
        let mut entry = [0.0f32; 8];
        _mm256_storeu_ps(entry.as_mut_ptr(), tmin);
        (entry, mask)
    }
}

/// [`intersect_node`]'s hit mask with the 8-wide box test and the per-child bits placed 8 lanes at once:
/// each hit child's bits (`child_bits8`, byte c) shifted by its index (`bit_index8`, byte c), OR-ed together.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn hit_mask_avx2(node: &CwBvhNode, r: &TravRay, oct_inv4: u32) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is enabled in this function.
    let hit = _mm256_castps_si256(unsafe { child_hits_avx2(node, r) });
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let bits = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(child_bits8 as i64));
    let index = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(bit_index8 as i64));
    let placed = _mm256_and_si256(_mm256_sllv_epi32(bits, index), hit);
    let x = _mm_or_si128(_mm256_castsi256_si128(placed), _mm256_extracti128_si256::<1>(placed));
    let x = _mm_or_si128(x, _mm_shuffle_epi32::<0b01_00_11_10>(x));
    let x = _mm_or_si128(x, _mm_shuffle_epi32::<0b10_11_00_01>(x));
    _mm_cvtsi128_si32(x) as u32
}

/// Whether the 8-wide node test can run (the standard library caches the CPU query).
#[inline]
pub(super) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Portable version of the slab test.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn child_mask(node: &CwBvhNode, r: &TravRay) -> u32 {
    child_entries_portable(node, r).1
}

/// Portable version of [`child_entries`].
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn child_entries_portable(node: &CwBvhNode, r: &TravRay) -> ([f32; 8], u32) {
    let (q, inv, org, t_far) = setup(node, r);
    let (inv, org) = (inv.to_array(), org.to_array());
    let mut mask = 0u32;
    let mut entry = [0.0f32; 8];
    for c in 0..8 {
        let t = |k: usize, axis: usize| q[k][c] as f32 * inv[axis] + org[axis];
        let tmin = t(0, 0).max(t(2, 1)).max(t(4, 2)).max(0.0);
        let tmax = t(1, 0).min(t(3, 1)).min(t(5, 2)).min(t_far);
        entry[c] = tmin;
        if tmin <= tmax {
            mask |= 1 << c;
        }
    }
    (entry, mask)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use obvhs::BvhBuildParams;
    use obvhs::cwbvh::builder::build_cwbvh_from_tris;
    use obvhs::triangle::Triangle;

    #[test]
    fn node_masks_match_obvhs_away_from_the_origin() {
        let mut rng = Rng::new(5);
        let mut v = || Vec3A::new(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0;
        let tris: Vec<Triangle> = (0..500)
            .map(|_| {
                let a = v();
                Triangle { v0: a, v1: a + v() * 0.1, v2: a + v() * 0.1 }
            })
            .collect();
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Default::default());
        let mut rng = Rng::new(9);
        let mut differ = 0;
        for i in 0..2000 {
            let o = Vec3A::new(-5.0, rng.uniform() * 10.0, rng.uniform() * 10.0);
            let d = (Vec3A::new(1.0, rng.uniform() - 0.5, rng.uniform() - 0.5)).normalize();
            let ray = obvhs::ray::Ray::new(o, d, 0.0, f32::INFINITY);
            let tr = TravRay::new(o, d, f32::INFINITY);
            let state = bvh.new_traversal(d);
            let node = &bvh.nodes[i % bvh.nodes.len()];
            let a = node.intersect_ray(&ray, state.oct_inv4);
            let b = if has_avx2() {
                intersect_node::<true>(node, &tr, state.oct_inv4)
            } else {
                intersect_node::<false>(node, &tr, state.oct_inv4)
            };
            if a != b {
                differ += 1;
            }
        }
        assert_eq!(differ, 0);
    }

    #[test]
    fn wide_and_narrow_node_tests_agree_everywhere() {
        let mut rng = Rng::new(11);
        let mut v = || Vec3A::new(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0;
        let tris: Vec<Triangle> = (0..300)
            .map(|_| {
                let a = v();
                Triangle { v0: a, v1: a + v() * 0.2, v2: a + v() * 0.2 }
            })
            .collect();
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Default::default());
        let mut rng = Rng::new(12);
        for i in 0..5000 {
            // Origins inside the scene, so many boxes contain them.
            let o = Vec3A::new(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0;
            let d = Vec3A::new(
                rng.uniform() - 0.5,
                rng.uniform() - 0.5,
                if i % 7 == 0 { 0.0 } else { rng.uniform() - 0.5 },
            );
            let t_max = if i % 3 == 0 { f32::INFINITY } else { rng.uniform() * 5.0 };
            let tr = TravRay::new(o, d, t_max);
            let node = &bvh.nodes[i % bvh.nodes.len()];
            let narrow = child_mask(node, &tr);
            if has_avx2() {
                // SAFETY: checked just above.
                assert_eq!(narrow, unsafe { child_mask_avx2(node, &tr) }, "ray {i}");
                let ((wide_entry, wide_mask), (entry, mask)) =
                    (child_entries::<true>(node, &tr), child_entries::<false>(node, &tr));
                assert_eq!((wide_mask, narrow), (mask, mask), "ray {i}");
                for c in (0..8).filter(|c| mask & (1 << c) != 0) {
                    assert_eq!(wide_entry[c].to_bits(), entry[c].to_bits(), "ray {i}, child {c}");
                }
                for oct_inv4 in [0, 0x0404_0404, 0x0303_0303, 0x0707_0707] {
                    let wide = intersect_node::<true>(node, &tr, oct_inv4);
                    assert_eq!(wide, intersect_node::<false>(node, &tr, oct_inv4), "ray {i}, octant {oct_inv4:x}");
                }
            }
        }
    }
}
