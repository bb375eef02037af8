//! STAGE 4 helper (refine): draws `n` pixels from a density map *stratified* by the map's mass. The image is
//! cut recursively, along the longer side of each rectangle, where the mass splits in proportion to the
//! caches each side gets, until a rectangle holds one cache, which is then drawn in it with probability
//! proportional to the map. Every cache thus stands for an equal share of the map's mass, and no two land
//! in the same share: independent draws (DGS's [`super::discrete2d`]) leave clumps and holes at the same
//! density, and where the map is flat a hole is an interpolation error that a stratified set does not
//! make (refine's rounds before this lost to the clustered placements on the Cornell box and the staircase
//! with the largest seed spread of any placement: experiments/notes/refine.md).
//!
//! Depends on `sampling` only; the map and the pixel ids are plain slices. Deterministic: the cuts depend
//! on the map alone and each leaf's draw on (seed, tag, the leaf's first pixel).

use crate::sampling::Rng;

/// Summed-area tables of the map's mass and of its positive pixels, for O(1) rectangle queries.
struct Tables {
    w: usize,
    /// (w + 1) × (h + 1), exclusive prefix sums.
    mass: Vec<f64>,
    count: Vec<u32>,
}

/// A half-open pixel rectangle [x0, x1) × [y0, y1).
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

impl Tables {
    fn new(w: usize, h: usize, map: &[f32]) -> Self {
        let stride = w + 1;
        let mut mass = vec![0f64; stride * (h + 1)];
        let mut count = vec![0u32; stride * (h + 1)];
        for y in 0..h {
            let (mut row_m, mut row_c) = (0f64, 0u32);
            for x in 0..w {
                let v = positive(map[y * w + x]);
                row_m += v as f64;
                row_c += u32::from(v > 0.0);
                mass[(y + 1) * stride + x + 1] = mass[y * stride + x + 1] + row_m;
                count[(y + 1) * stride + x + 1] = count[y * stride + x + 1] + row_c;
            }
        }
        Tables { w, mass, count }
    }

    fn mass(&self, r: Rect) -> f64 {
        let s = self.w + 1;
        (self.mass[r.y1 * s + r.x1] - self.mass[r.y0 * s + r.x1] - self.mass[r.y1 * s + r.x0]
            + self.mass[r.y0 * s + r.x0])
            .max(0.0)
    }

    fn count(&self, r: Rect) -> usize {
        let s = self.w + 1;
        (self.count[r.y1 * s + r.x1] + self.count[r.y0 * s + r.x0]
            - self.count[r.y0 * s + r.x1]
            - self.count[r.y1 * s + r.x0]) as usize
    }
}

/// The map's value as a weight: negative and non-finite values count as 0.
fn positive(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

/// Draws up to `n` distinct pixels (ids `y·w + x`) with positive map values, stratified by the map's mass
/// (module doc). Fewer than `n` only when fewer pixels have a positive value; the order is the leaves'
/// (a depth-first walk of the cuts).
pub(crate) fn draw(w: usize, h: usize, map: &[f32], n: usize, seed: u64, tag: u64) -> Vec<u32> {
    let t = Tables::new(w, h, map);
    let mut out = Vec::with_capacity(n);
    let mut stack = vec![(Rect { x0: 0, x1: w, y0: 0, y1: h }, n)];
    while let Some((r, n)) = stack.pop() {
        let free = t.count(r);
        let n = n.min(free);
        if n == 0 {
            continue;
        }
        if n == free {
            for y in r.y0..r.y1 {
                out.extend((r.x0..r.x1).filter(|&x| positive(map[y * w + x]) > 0.0).map(|x| (y * w + x) as u32));
            }
            continue;
        }
        if n == 1 {
            out.push(draw_one(w, map, r, t.mass(r), seed, tag));
            continue;
        }
        let (a, b) = cut(&t, r, n);
        let (ma, mb) = (t.mass(a), t.mass(b));
        // a's share of the caches by its mass, within what each side can hold.
        let share = if ma + mb > 0.0 { (n as f64 * ma / (ma + mb)).round() as usize } else { n / 2 };
        let na = share.clamp(n.saturating_sub(t.count(b)), t.count(a).min(n));
        stack.push((b, n - na));
        stack.push((a, na));
    }
    out
}

/// Cuts `r` across its longer side where the mass before the cut is closest to half of it when `n` is
/// even, to ⌊n/2⌋/n of it when odd; both parts keep at least one row or column.
fn cut(t: &Tables, r: Rect, n: usize) -> (Rect, Rect) {
    let total = t.mass(r);
    let goal = total * (n / 2) as f64 / n as f64;
    let horizontal = r.x1 - r.x0 >= r.y1 - r.y0;
    let (lo, hi) = if horizontal { (r.x0, r.x1) } else { (r.y0, r.y1) };
    let part = |s: usize| -> (Rect, Rect) {
        if horizontal { (Rect { x1: s, ..r }, Rect { x0: s, ..r }) } else { (Rect { y1: s, ..r }, Rect { y0: s, ..r }) }
    };
    // The first cut whose first part reaches the goal (the masses before the cut are non-decreasing in s),
    // or the one before it if that is closer.
    let (mut a, mut b) = (lo + 1, hi - 1);
    while a < b {
        let mid = (a + b) / 2;
        if t.mass(part(mid).0) < goal {
            a = mid + 1;
        } else {
            b = mid;
        }
    }
    let s = if a > lo + 1 && goal - t.mass(part(a - 1).0) < t.mass(part(a).0) - goal { a - 1 } else { a };
    part(s)
}

/// One pixel of `r` with probability map / mass; the first positive pixel if rounding runs past the end.
fn draw_one(w: usize, map: &[f32], r: Rect, mass: f64, seed: u64, tag: u64) -> u32 {
    let mut rng = Rng::keyed(seed, tag, (r.y0 * w + r.x0) as u64);
    let u = rng.uniform() as f64 * mass;
    let mut acc = 0f64;
    let mut first = None;
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            let v = positive(map[y * w + x]);
            if v > 0.0 {
                first.get_or_insert((y * w + x) as u32);
                acc += v as f64;
                if u < acc {
                    return (y * w + x) as u32;
                }
            }
        }
    }
    // Only reachable by rounding (u close to the mass): the last positive pixel would be as right; the
    // first is as good a choice and is known.
    first.unwrap_or((r.y0 * w + r.x0) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_exactly_n_distinct_positive_pixels() {
        let (w, h) = (37, 23);
        let map: Vec<f32> = (0..w * h).map(|i| if i % 7 == 3 { 0.0 } else { 1.0 + (i % 5) as f32 }).collect();
        for n in [0, 1, 2, 5, 64, 300, 700] {
            let got = draw(w, h, &map, n, 9, 1);
            let positive = map.iter().filter(|v| **v > 0.0).count();
            assert_eq!(got.len(), n.min(positive));
            let mut sorted = got.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), got.len(), "a pixel drawn twice for n = {n}");
            assert!(got.iter().all(|&id| map[id as usize] > 0.0));
        }
        // More than the positive pixels: every one of them, once.
        let all = draw(w, h, &map, 10_000, 9, 1);
        assert_eq!(all.len(), map.iter().filter(|v| **v > 0.0).count());
    }

    #[test]
    fn each_quarter_of_a_flat_map_gets_its_share_exactly() {
        // A uniform 64×64 map and 64 caches: every 16×16 block gets 4 (independent draws would give
        // Poisson-like counts, 4 ± 2).
        let (w, h) = (64, 64);
        let map = vec![1f32; w * h];
        let got = draw(w, h, &map, 64, 3, 2);
        let mut blocks = [0usize; 16];
        for id in got {
            let (x, y) = (id as usize % w, id as usize / w);
            blocks[(y / 16) * 4 + x / 16] += 1;
        }
        assert!(blocks.iter().all(|&c| c == 4), "{blocks:?}");
    }

    #[test]
    fn the_counts_follow_the_mass() {
        // The right half weighs three times the left: it gets three quarters of the caches.
        let (w, h) = (40, 40);
        let map: Vec<f32> = (0..w * h).map(|i| if i % w >= 20 { 3.0 } else { 1.0 }).collect();
        let got = draw(w, h, &map, 100, 5, 3);
        let right = got.iter().filter(|&&id| id as usize % w >= 20).count();
        assert!((73..=77).contains(&right), "{right} of 100 on the heavy half");
    }

    #[test]
    fn the_same_seed_gives_the_same_pixels_and_another_seed_others() {
        let (w, h) = (50, 30);
        let map: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 13) as f32).collect();
        let a = draw(w, h, &map, 120, 1, 4);
        assert_eq!(a, draw(w, h, &map, 120, 1, 4));
        assert_ne!(a, draw(w, h, &map, 120, 2, 4));
    }
}
