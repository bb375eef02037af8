//! STAGE 5 (application, importance caching): a tree of bounding spheres over the positional VPLs, for
//! the queries of the split ([`super::split`]) and of the lobe technique ([`super::lobe`]): which VPLs lie
//! in a ball or a cone around a shading point.
//!
//! The VPL list's Morton order is cut in halves down to runs of at most [`LEAF`] VPLs; each node keeps a
//! sphere around its run, and the nodes are stored in preorder with the index past each subtree, so a
//! query is one loop without a stack.
//!
//! Depends on the VPL positions only.

use glam::Vec3A;

use super::vpl::Vpls;

/// VPLs per leaf.
pub const LEAF: usize = 8;

/// A node: a bounding sphere of VPLs `lo..hi`; `skip` is the index past this node's subtree.
#[derive(Clone, Copy, Debug)]
struct Node {
    center: Vec3A,
    radius: f32,
    lo: u32,
    hi: u32,
    skip: u32,
}

/// The sphere tree over VPLs `0..positional` of a VPL list.
#[derive(Clone, Debug, Default)]
pub struct SphereTree {
    nodes: Vec<Node>,
}

impl SphereTree {
    /// The tree over the first `positional` VPLs of `vpls`.
    pub fn new(vpls: &Vpls, positional: usize) -> SphereTree {
        let mut tree = SphereTree::default();
        tree.build(vpls, 0, positional.min(vpls.list.len()));
        tree
    }

    fn build(&mut self, vpls: &Vpls, lo: usize, hi: usize) {
        if lo >= hi {
            return;
        }
        let (mut min, mut max) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for v in &vpls.list[lo..hi] {
            (min, max) = (min.min(v.p), max.max(v.p));
        }
        let center = 0.5 * (min + max);
        let radius = vpls.list[lo..hi].iter().map(|v| (v.p - center).length()).fold(0.0f32, f32::max);
        // Rounding of the query's distances: the sphere is grown so that culling never drops a member.
        let radius = radius * (1.0 + 1e-4) + 1e-6 * center.abs().max_element().max(1.0);
        let at = self.nodes.len();
        self.nodes.push(Node { center, radius, lo: lo as u32, hi: hi as u32, skip: 0 });
        if hi - lo > LEAF {
            let mid = lo + (hi - lo) / 2;
            self.build(vpls, lo, mid);
            self.build(vpls, mid, hi);
        }
        self.nodes[at].skip = self.nodes.len() as u32;
    }

    /// Walks the tree in preorder: a node whose sphere (centre, radius) `keep` rejects is skipped with its
    /// subtree; for every leaf kept, `leaf` gets its run `lo..hi` of VPLs (runs come in ascending order).
    #[inline]
    pub fn walk(&self, mut keep: impl FnMut(Vec3A, f32) -> bool, mut leaf: impl FnMut(usize, usize)) {
        let mut i = 0;
        while i < self.nodes.len() {
            let n = &self.nodes[i];
            if !keep(n.center, n.radius) {
                i = n.skip as usize;
                continue;
            }
            if n.hi - n.lo <= LEAF as u32 {
                leaf(n.lo as usize, n.hi as usize);
            }
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::application::importance::vpl::{Emitter, Vpl};
    use crate::shading::Spectrum;

    #[test]
    fn a_walk_finds_exactly_the_members_of_a_ball_in_ascending_order() {
        let mut vpls = Vpls::none(0.01);
        let mut rng = crate::sampling::Rng::new(9);
        for _ in 0..500 {
            let p = Vec3A::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0;
            vpls.list.push(Vpl {
                p,
                p_error: Vec3A::ZERO,
                ng: Vec3A::Z,
                ns: Vec3A::Z,
                power: Spectrum::splat(1.0),
                emitter: Emitter::Isotropic,
            });
        }
        let tree = SphereTree::new(&vpls, vpls.list.len());
        let (apex, r) = (Vec3A::splat(2.0), 0.7);
        let mut found = Vec::new();
        tree.walk(
            |c, radius| (c - apex).length() <= radius + r,
            |lo, hi| found.extend((lo..hi).filter(|&j| (vpls.list[j].p - apex).length() <= r)),
        );
        let expected: Vec<usize> = (0..500).filter(|&j| (vpls.list[j].p - apex).length() <= r).collect();
        assert!(!expected.is_empty());
        assert_eq!(found, expected);
    }
}
