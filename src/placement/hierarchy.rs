//! STAGE 4 (shared by SD and VGC): a binary hierarchy over shading points built once, top-down, by
//! partitioning the point array in place (every node is a contiguous range), and *cut* at a threshold.
//!
//! Both clusterings split a node the same way whatever the threshold (SD: longest 6-D axis; VGC spatial
//! pass: longest world axis) and stop where a per-node key ≤ threshold. So the tree is built once and each
//! step of the budget search only walks it down to the cut and counts — no rebuild, nothing materialised
//! (ALGORITHMS.md §4.2, §4.4 "only the cluster count is needed during the search"). Subtrees are built and
//! counted with rayon; the layout (pre-order) and every count are the same for any thread count.
//!
//! Depends only on `points`; knows nothing of budgets, seeds or strategies.

use super::points::Pt;

/// One node: the range `start..start + len` of the point array, the offset from this node to its right
/// child (the left child is the next node; 0 = no children) and the key the cut compares with a threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node {
    /// First point.
    pub start: u32,
    /// Number of points.
    pub len: u32,
    /// Offset to the right child; 0 for a node without children.
    pub right: u32,
    /// Stop key: the node is a cut leaf at threshold t when key ≤ t.
    pub key: f32,
    /// A second per-node value the rule may record (VGC: a bound of the normal spread).
    pub aux: f32,
}

/// How a hierarchy measures and splits a node.
pub(crate) trait NodeRule: Sync {
    /// Computes the node's key and auxiliary value and, when it can have children, partitions it and
    /// returns the size of the left part (in 1..len).
    fn process(&self, pts: &mut [Pt]) -> (f32, f32, Option<usize>);
}

/// Nodes bigger than this are built / walked in parallel.
const PAR_MIN: usize = 16 * 1024;
/// Parallel recursion stops at this depth (very unbalanced splits continue sequentially on the heap).
const PAR_DEPTH: u32 = 40;

/// A pre-order hierarchy over a point array.
#[derive(Clone, Debug, Default)]
pub(crate) struct Hierarchy {
    /// Nodes in pre-order; node 0 is the root.
    pub nodes: Vec<Node>,
}

impl Hierarchy {
    /// Builds the full hierarchy over `pts` (which it reorders).
    pub fn build(pts: &mut [Pt], rule: &impl NodeRule) -> Self {
        if pts.is_empty() {
            return Hierarchy::default();
        }
        Hierarchy { nodes: build_par(pts, 0, rule, 0) }
    }

    /// Number of cut leaves at threshold `t`, each weighted by `weight(node index)`.
    pub fn cut_count(&self, t: f32, weight: &(impl Fn(usize) -> usize + Sync)) -> usize {
        if self.nodes.is_empty() { 0 } else { self.count_par(0, t, weight, 0) }
    }

    /// The cut leaves at threshold `t`, left to right.
    pub fn cut(&self, t: f32) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = if self.nodes.is_empty() { vec![] } else { vec![0usize] };
        while let Some(i) = stack.pop() {
            let nd = self.nodes[i];
            if nd.right == 0 || nd.key <= t {
                out.push(i);
            } else {
                stack.push(i + nd.right as usize);
                stack.push(i + 1);
            }
        }
        out
    }

    fn count_par(&self, i: usize, t: f32, weight: &(impl Fn(usize) -> usize + Sync), depth: u32) -> usize {
        let nd = self.nodes[i];
        if nd.right == 0 || nd.key <= t {
            return weight(i);
        }
        if (nd.len as usize) < PAR_MIN || depth >= PAR_DEPTH {
            return self.count_seq(i, t, weight);
        }
        let (a, b) = rayon::join(
            || self.count_par(i + 1, t, weight, depth + 1),
            || self.count_par(i + nd.right as usize, t, weight, depth + 1),
        );
        a + b
    }

    fn count_seq(&self, root: usize, t: f32, weight: &impl Fn(usize) -> usize) -> usize {
        let mut stack = vec![root];
        let mut count = 0;
        while let Some(i) = stack.pop() {
            let nd = self.nodes[i];
            if nd.right == 0 || nd.key <= t {
                count += weight(i);
            } else {
                stack.push(i + nd.right as usize);
                stack.push(i + 1);
            }
        }
        count
    }
}

/// Builds the subtree over `pts` (whose first point is at `start` in the whole array) in pre-order with
/// relative right-child offsets, so subtrees built in parallel concatenate without fix-ups.
fn build_par(pts: &mut [Pt], start: u32, rule: &impl NodeRule, depth: u32) -> Vec<Node> {
    if pts.len() < PAR_MIN || depth >= PAR_DEPTH {
        let mut out = Vec::new();
        build_seq(pts, start, rule, &mut out);
        return out;
    }
    let len = pts.len();
    let (key, aux, split) = rule.process(pts);
    let mut out = vec![Node { start, len: len as u32, right: 0, key, aux }];
    if let Some(m) = split {
        let (a, b) = pts.split_at_mut(m);
        let (l, r) =
            rayon::join(|| build_par(a, start, rule, depth + 1), || build_par(b, start + m as u32, rule, depth + 1));
        out[0].right = 1 + l.len() as u32;
        out.extend(l);
        out.extend(r);
    }
    out
}

/// Sequential pre-order build with an explicit stack (no recursion: degenerate inputs can be deep).
fn build_seq(pts: &mut [Pt], start: u32, rule: &impl NodeRule, out: &mut Vec<Node>) {
    let base = out.len();
    // (offset of the range in `pts`, length, index of the parent whose right child this is)
    let mut stack: Vec<(usize, usize, Option<usize>)> = vec![(0, pts.len(), None)];
    while let Some((off, len, parent)) = stack.pop() {
        let me = out.len();
        if let Some(p) = parent {
            out[p].right = (me - p) as u32;
        }
        let (key, aux, split) = rule.process(&mut pts[off..off + len]);
        out.push(Node { start: start + off as u32, len: len as u32, right: 0, key, aux });
        if let Some(m) = split {
            // Right first so the left subtree is emitted next (pre-order); a node's `right` stays 0 until its
            // right child is popped, which is after its whole left subtree.
            stack.push((off + m, len - m, Some(me)));
            stack.push((off, m, None));
        }
    }
    debug_assert!(out.len() > base);
}

#[cfg(test)]
mod tests {
    use super::super::split::{spatial_stats, split_spatial};
    use super::*;
    use crate::sampling::Rng;

    /// Key = longest side; split at its midpoint.
    struct Longest;
    impl NodeRule for Longest {
        fn process(&self, pts: &mut [Pt]) -> (f32, f32, Option<usize>) {
            let (lo, hi, _) = spatial_stats(pts);
            let key = (hi - lo).max_element();
            (key, 0.0, if key > 0.0 { split_spatial(pts, lo, hi) } else { None })
        }
    }

    fn random_points(n: usize) -> Vec<Pt> {
        let mut r = Rng::keyed(0x41e7, 0, 0);
        (0..n as u32)
            .map(|id| Pt { p: [r.uniform(), r.uniform(), 0.01 * r.uniform()], n: [0.0, 0.0, 1.0], depth: 1.0, id })
            .collect()
    }

    #[test]
    fn tree_is_a_partition_and_counts_match_cuts() {
        let mut pts = random_points(70_000);
        let h = Hierarchy::build(&mut pts, &Longest);
        // Every cut is a partition of the array, in order.
        for t in [0.5, 0.1, 0.01, 0.001] {
            let cut = h.cut(t);
            let mut next = 0;
            for &i in &cut {
                assert_eq!(h.nodes[i].start, next);
                next += h.nodes[i].len;
            }
            assert_eq!(next as usize, pts.len());
            assert_eq!(h.cut_count(t, &|_| 1), cut.len());
        }
        // Non-increasing in t.
        let counts: Vec<usize> = [1e-4, 1e-3, 1e-2, 1e-1, 1.0].iter().map(|&t| h.cut_count(t, &|_| 1)).collect();
        assert!(counts.windows(2).all(|w| w[0] >= w[1]), "{counts:?}");
    }

    #[test]
    fn layout_does_not_depend_on_the_thread_count() {
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut pts = random_points(100_000);
                let h = Hierarchy::build(&mut pts, &Longest);
                (h.nodes, pts.iter().map(|q| q.id).collect::<Vec<_>>())
            })
        };
        assert_eq!(run(1), run(2));
    }
}
