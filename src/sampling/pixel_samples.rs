//! Sampling (below `scene`): the sample values of one camera sample — film position, lens position and 2-D arrays
//! for integrators — keyed by (seed, pixel, sample index), never by thread, so images are identical for any
//! thread count.
//!
//! `random` gives independent uniform numbers, as pbrt-v3's random sampler. Every other pbrt-v3 sampler
//! maps to stratified points: each dimension pair of a pixel's samples is a scrambled (0,2)-sequence visited
//! in a pixel- and dimension-specific order, and the arrays of a pixel's samples are consecutive blocks of
//! one scrambled (0,2)-sequence, each sample's block a (0,2)-net of its own (the same guarantees pbrt-v3's
//! `02sequence` sampler gives: its arrays are stratified across the pixel, not only within a sample).

use crate::sampling::rng::{Rng, hash3, mix64};
use crate::sampling::sequence::{permute, permute_range, sobol02};

/// How sample values are generated (what a scene's `Sampler` directive chooses).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerKind {
    /// Independent uniform random numbers (pbrt-v3 `random`).
    Random,
    /// Stratified / low-discrepancy points: `stratified`, `halton`, `sobol`, `02sequence`, `maxmindist`
    /// all map here (scrambled (0,2)-sequence points per pixel).
    Stratified,
}

/// A stream of sample values for one (pixel, sample index).
#[derive(Clone, Debug)]
pub struct PixelSamples {
    kind: SamplerKind,
    seed: u64,
    spp: u32,
    pixel_key: u64,
    index: u32,
    dim: u64,
    rng: Rng,
    order_scratch: OrderScratch,
    /// What the first dimensions of `keys_pixel`'s samples derive from their keys (`keys_known` of them):
    /// every sample of a pixel uses the same ones, so they are hashed once per pixel, not once per sample.
    dims: [Dim; KEPT_KEYS],
    keys_known: usize,
    keys_pixel: u64,
    /// Per remembered dimension, a row of `spp` permuted sample indices (see [`Dim::row`]); allocated on the
    /// first use, for at most [`TABLE_SPP`] samples per pixel.
    rows: Vec<u32>,
}

/// What a remembered dimension of the current pixel derives from its key.
#[derive(Clone, Copy, Debug, Default)]
struct Dim {
    /// hash3(seed, pixel, dimension).
    key: u64,
    /// The XOR scrambles of its points: the key's high half and the low half of `mix64(key)`.
    scramble: [u32; 2],
    /// Which permutation its row in [`PixelSamples::rows`] holds, from which sample on.
    row: Row,
}

/// The permutation a dimension's row holds: the one [`PixelSamples::get2d`] visits the pixel's samples in,
/// or the order of [`PixelSamples::array2d`]'s blocks (another key), each tabulated from the sample that
/// first asked for it to the pixel's last. A pixel's samples are drawn in order, so one batch of
/// independent [`permute`] evaluations replaces a chain of dependent multiplies on every draw (the draw's
/// largest cost); a sample index before the row's start, or the other kind, is computed as before.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Row {
    /// Not tabulated.
    #[default]
    None,
    /// `permute(i, spp, key as u32)` for i ≥ the start.
    Points(u32),
    /// `permute(i, spp, mix64(key ^ ARRAY_BLOCKS) as u32)` for i ≥ the start.
    Blocks(u32),
}

/// How many dimension keys [`PixelSamples`] remembers per pixel (later dimensions are hashed each time).
const KEPT_KEYS: usize = 64;
/// The most samples per pixel whose permutations [`PixelSamples`] tabulates (64 rows of 256 indices: 64 KiB).
const TABLE_SPP: u32 = 256;

/// Stage tag of camera-sample streams in random keys.
const STAGE_CAMERA: u64 = 0x63616d;
/// Key tag of the block order of arrays.
const ARRAY_BLOCKS: u64 = 0x626c_6f63_6b73;

impl PixelSamples {
    /// A stream of `kind` for `spp` samples per pixel with `seed` (call [`PixelSamples::start`] before use).
    pub fn new(kind: SamplerKind, spp: u32, seed: u64) -> Self {
        PixelSamples {
            kind,
            seed,
            spp: spp.max(1),
            pixel_key: 0,
            index: 0,
            dim: 0,
            rng: Rng::new(0),
            order_scratch: OrderScratch::default(),
            dims: [Dim::default(); KEPT_KEYS],
            keys_known: 0,
            keys_pixel: 0,
            rows: Vec::new(),
        }
    }

    /// Positions the stream at sample `index` of pixel (x, y).
    pub fn start(&mut self, pixel: [i32; 2], index: u32) {
        self.pixel_key = ((pixel[0] as u32 as u64) << 32) | pixel[1] as u32 as u64;
        if self.pixel_key != self.keys_pixel {
            (self.keys_pixel, self.keys_known) = (self.pixel_key, 0);
        }
        self.index = index;
        self.dim = 0;
        // Only `random` draws from the generator; the stratified points are functions of their keys.
        if self.kind == SamplerKind::Random {
            self.rng = Rng::new(hash3(self.seed ^ STAGE_CAMERA, self.pixel_key, index as u64));
        }
    }

    /// The next dimension: its key, scrambles and (when remembered) its slot in [`PixelSamples::dims`].
    #[inline]
    fn next_dim(&mut self) -> (u64, [u32; 2], Option<usize>) {
        self.dim += 1;
        let d = (self.dim - 1) as usize;
        if d < self.keys_known {
            let dim = &self.dims[d];
            return (dim.key, dim.scramble, Some(d));
        }
        self.next_dim_cold(d)
    }

    /// [`PixelSamples::next_dim`] for a dimension this pixel has not remembered: hashes its key.
    #[cold]
    #[inline(never)]
    fn next_dim_cold(&mut self, d: usize) -> (u64, [u32; 2], Option<usize>) {
        let key = hash3(self.seed, self.pixel_key, self.dim);
        let scramble = [(key >> 32) as u32, mix64(key) as u32];
        // Dimensions are drawn in order, so an unknown one is the next to remember.
        if d == self.keys_known && d < KEPT_KEYS {
            self.dims[d] = Dim { key, scramble, row: Row::None };
            self.keys_known += 1;
            return (key, scramble, Some(d));
        }
        (key, scramble, None)
    }

    /// `permute(self.index, spp, perm_key)`, from remembered dimension `slot`'s row when it holds that
    /// permutation (`blocks`: array blocks' order, else points'), tabulating the row on its first use. The
    /// permutation's key is [`perm_key`] of the dimension's `key`, computed only when the row cannot answer.
    #[inline]
    fn permuted(&mut self, slot: Option<usize>, blocks: bool, key: u64) -> u32 {
        // The hot path, one load and a compare: the row is tabulated for this kind from this sample on.
        if let Some(d) = slot {
            let i = self.index;
            if let (Row::Points(from), false) | (Row::Blocks(from), true) = (self.dims[d].row, blocks)
                && i >= from
                && i < self.spp
            {
                let at = d * self.spp as usize + i as usize;
                if let Some(&v) = self.rows.get(at) {
                    return v;
                }
            }
        }
        self.permuted_cold(slot, blocks, perm_key(key, blocks))
    }

    /// [`PixelSamples::permuted`] when the row does not hold the value: tabulates it, or computes one value.
    #[cold]
    #[inline(never)]
    fn permuted_cold(&mut self, slot: Option<usize>, blocks: bool, perm_key: u32) -> u32 {
        let (spp, i) = (self.spp, self.index);
        let Some(d) = slot.filter(|_| spp <= TABLE_SPP && i < spp) else {
            return permute(i, spp, perm_key);
        };
        let n = spp as usize;
        let row = &mut self.dims[d].row;
        let tabulated = match (*row, blocks) {
            (Row::Points(from), false) | (Row::Blocks(from), true) => i >= from,
            _ => false,
        };
        if !tabulated {
            if *row != Row::None {
                return permute(i, spp, perm_key);
            }
            *row = if blocks { Row::Blocks(i) } else { Row::Points(i) };
            if self.rows.is_empty() {
                self.rows = vec![0; KEPT_KEYS * n];
            }
            permute_range(i, &mut self.rows[d * n + i as usize..(d + 1) * n], spp, perm_key);
        }
        self.rows[d * n + i as usize]
    }

    /// The next two dimensions: stratified across the pixel's samples (or uniform for `random`).
    pub fn get2d(&mut self) -> [f32; 2] {
        match self.kind {
            SamplerKind::Random => self.rng.uniform2(),
            SamplerKind::Stratified => {
                let (k, s, slot) = self.next_dim();
                let i = self.permuted(slot, false, k);
                sobol02(i, s)
            }
        }
    }

    /// Moves past the next two dimensions without computing their values: the stream afterwards is exactly
    /// as after [`PixelSamples::get2d`] (for a caller that draws them only to keep the dimensions aligned,
    /// like pbrt-v3's `SpecularReflect` at a surface without a specular lobe).
    pub fn skip2d(&mut self) {
        match self.kind {
            SamplerKind::Random => {
                self.rng.uniform2();
            }
            SamplerKind::Stratified => {
                // Only the dimension count and the remembered keys advance; a tabulated row is a function of
                // its key alone, so tabulating it later gives the same values.
                self.next_dim();
            }
        }
    }

    /// Reorders an array from [`PixelSamples::array2d`] coherently (see [`coherent_order`]).
    pub fn coherent(&mut self, points: &mut [[f32; 2]]) {
        coherent_order(points, &mut self.order_scratch);
    }

    /// Fills `out` with the next 2-D array of this sample (e.g. ambient-occlusion directions).
    pub fn array2d(&mut self, out: &mut [[f32; 2]]) {
        match self.kind {
            SamplerKind::Random => out.iter_mut().for_each(|u| *u = self.rng.uniform2()),
            SamplerKind::Stratified => {
                // The arrays of a pixel's samples together are one scrambled (0,2)-sequence: sample i takes
                // the block of n consecutive points at a permuted block index, so the pixel's n·spp points are
                // stratified as a whole (as pbrt-v3's samplers stratify arrays across the pixel), and each
                // block of a power-of-two size is itself a (0,2)-net.
                let (k, s, slot) = self.next_dim();
                let n = out.len() as u64;
                let block = self.permuted(slot, true, k) as u64;
                if n * self.spp as u64 <= u32::MAX as u64 {
                    let first = block * n;
                    out.iter_mut().enumerate().for_each(|(j, u)| *u = sobol02((first + j as u64) as u32, s));
                } else {
                    // Beyond 2^32 points per pixel: a (0,2)-net per sample.
                    let k = mix64(k ^ ((self.index as u64) << 17));
                    let s = [(k >> 32) as u32, k as u32];
                    out.iter_mut().enumerate().for_each(|(j, u)| *u = sobol02(j as u32, s));
                }
            }
        }
    }
}

/// The key of the permutation a dimension with key `key` visits its points (`blocks`: its array blocks) in.
#[inline]
fn perm_key(key: u64, blocks: bool) -> u32 {
    if blocks { mix64(key ^ ARRAY_BLOCKS) as u32 } else { key as u32 }
}

/// Reorders 2-D sample points so consecutive points are neighbours in the unit square (a counting sort into
/// a k×k grid of cells visited in serpentine order, k = ⌈√n⌉). The set of points is unchanged, so every
/// estimate over them is too; occlusion queries from one point then meet the same blockers in a row (see
/// `scene::accel::OccluderHint`). `scratch` is reused storage.
pub fn coherent_order(points: &mut [[f32; 2]], scratch: &mut OrderScratch) {
    let n = points.len();
    if n < 4 {
        return;
    }
    let k = (n as f64).sqrt().ceil() as usize;
    let (kf, last) = (k as f32, (k - 1) as f32);
    // The cell column (or row) of a coordinate: ⌊v·k⌋ clamped to [0, k-1], NaN → 0. Clamped in float first,
    // so the conversion cannot overflow and needs none of the saturating cast's checks.
    let axis = |v: f32| {
        let c = (v * kf).max(0.0).min(last);
        // SAFETY: `c` is finite and in [0, k - 1] (max/min drop a NaN operand), so it fits a u32.
        unsafe { c.to_int_unchecked::<u32>() }
    };
    let k32 = k as u32;
    let OrderScratch { copy, start } = scratch;
    copy.clear();
    copy.extend(points.iter().map(|&p| {
        let (x, y) = (axis(p[0]), axis(p[1]));
        // Serpentine: odd rows are visited right to left.
        let col = if y & 1 == 0 { x } else { k32 - 1 - x };
        (p, y * k32 + col)
    }));
    start.clear();
    start.resize(k * k + 1, 0);
    for &(_, c) in copy.iter() {
        start[c as usize + 1] += 1;
    }
    let mut sum = 0;
    for s in start.iter_mut() {
        sum += *s;
        *s = sum;
    }
    // `start[c + 1]` now ends cell c; fill each cell from its end backwards, walking the points backwards, so
    // points sharing a cell keep their order (stable: the result is a pure function of the input).
    for &(p, c) in copy.iter().rev() {
        let slot = &mut start[c as usize + 1];
        *slot -= 1;
        points[*slot as usize] = p;
    }
}

/// Reusable storage of [`coherent_order`].
#[derive(Clone, Debug, Default)]
pub struct OrderScratch {
    copy: Vec<([f32; 2], u32)>,
    start: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coherent_order_keeps_the_points_and_makes_neighbours_adjacent() {
        let mut rng = crate::sampling::Rng::new(4);
        let mut pts: Vec<[f32; 2]> = (0..256).map(|_| rng.uniform2()).collect();
        let before = {
            let mut v = pts.clone();
            v.sort_by(|a, b| a.partial_cmp(b).unwrap());
            v
        };
        let step = |v: &[[f32; 2]]| {
            v.windows(2).map(|w| ((w[0][0] - w[1][0]).powi(2) + (w[0][1] - w[1][1]).powi(2)).sqrt()).sum::<f32>()
        };
        let random_path = step(&pts);
        coherent_order(&mut pts, &mut OrderScratch::default());
        let mut after = pts.clone();
        after.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(before, after);
        assert!(step(&pts) < random_path / 4.0);
    }

    #[test]
    fn coherent_order_is_a_stable_sort_by_serpentine_cell() {
        // Checked against the plain definition: a stable sort by the cell index ⌊v·k⌋ (clamped), odd rows
        // reversed. Includes values on and beyond the cell edges, and NaN (cell 0).
        let mut rng = crate::sampling::Rng::new(7);
        for n in [4usize, 5, 16, 17, 63, 64, 100, 256, 1000] {
            let mut pts: Vec<[f32; 2]> = (0..n).map(|_| rng.uniform2()).collect();
            pts[0] = [0.0, 0.999_999_9];
            pts[1] = [1.0, 0.5];
            pts[2] = [f32::NAN, -0.25];
            pts[3] = [0.25, 0.25];
            let k = (n as f64).sqrt().ceil() as usize;
            let cell = |p: &[f32; 2]| {
                let c = |v: f32| ((v * k as f32) as usize).min(k - 1);
                let (x, y) = (c(p[0]), c(p[1]));
                y * k + if y % 2 == 0 { x } else { k - 1 - x }
            };
            let mut expect = pts.clone();
            expect.sort_by_key(cell);
            coherent_order(&mut pts, &mut OrderScratch::default());
            let bits = |v: &[[f32; 2]]| v.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&pts), bits(&expect), "n = {n}");
        }
    }

    /// The values the stream must give, computed from their definition: dimension d (from 1) of sample
    /// `index` has key hash3(seed, pixel, d), a point is that dimension's scrambled (0,2)-sequence at the
    /// permuted sample index, an array the block of points at the permuted block index.
    fn plain(seed: u64, pixel: [i32; 2], spp: u32, index: u32, d: u64, array: Option<usize>) -> Vec<[f32; 2]> {
        let pixel_key = ((pixel[0] as u32 as u64) << 32) | pixel[1] as u32 as u64;
        let k = hash3(seed, pixel_key, d);
        let s = [(k >> 32) as u32, mix64(k) as u32];
        match array {
            None => vec![sobol02(permute(index, spp, k as u32), s)],
            Some(n) => {
                let block = permute(index, spp, mix64(k ^ ARRAY_BLOCKS) as u32);
                (0..n as u32).map(|j| sobol02(block * n as u32 + j, s)).collect()
            }
        }
    }

    #[test]
    fn skipping_two_dimensions_leaves_the_stream_where_drawing_them_does() {
        for kind in [SamplerKind::Stratified, SamplerKind::Random] {
            for skip in 0..6 {
                let (mut drawn, mut skipped) = (PixelSamples::new(kind, 16, 5), PixelSamples::new(kind, 16, 5));
                let mut out = [[0.0; 2]; 3];
                for i in 0..16 {
                    let (mut a, mut b) = (Vec::new(), Vec::new());
                    drawn.start([3, 4], i);
                    skipped.start([3, 4], i);
                    for d in 0..8 {
                        if d == skip {
                            drawn.get2d();
                            skipped.skip2d();
                        } else if d % 3 == 2 {
                            drawn.array2d(&mut out);
                            a.extend(out);
                            skipped.array2d(&mut out);
                            b.extend(out);
                        } else {
                            a.push(drawn.get2d());
                            b.push(skipped.get2d());
                        }
                    }
                    assert_eq!(a, b, "{kind:?}, dimension pair {skip} skipped, sample {i}");
                }
            }
        }
    }

    #[test]
    fn tabulated_permutations_give_the_defined_values_in_any_call_pattern() {
        // Samples in order and out of order, a pixel left and revisited, a dimension drawn as a point by some
        // samples and as an array by others, more dimensions than are remembered, and sample counts with and
        // without tables.
        for spp in [1u32, 3, 16, 64, TABLE_SPP + 1] {
            let mut st = PixelSamples::new(SamplerKind::Stratified, spp, 9);
            let mut order: Vec<([i32; 2], u32)> = (0..spp).map(|i| ([2, 7], i)).collect();
            order.extend((0..spp).rev().map(|i| ([3, 7], i)));
            order.extend((0..spp.min(5)).map(|i| ([2, 7], (i * 7) % spp)));
            for (pixel, i) in order {
                st.start(pixel, i);
                let dims = if i % 3 == 0 { KEPT_KEYS as u64 + 6 } else { 5 + (i as u64 % 4) };
                for d in 1..=dims {
                    let array = (d + i as u64).is_multiple_of(3).then_some(1 + (d as usize % 4));
                    let got = match array {
                        None => vec![st.get2d()],
                        Some(n) => {
                            let mut v = vec![[0.0; 2]; n];
                            st.array2d(&mut v);
                            v
                        }
                    };
                    assert_eq!(
                        got,
                        plain(9, pixel, spp, i, d, array),
                        "spp {spp}, pixel {pixel:?}, sample {i}, dim {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn same_key_same_values_and_film_samples_are_stratified() {
        let s = (SamplerKind::Stratified, 16);
        let mut a = PixelSamples::new(s.0, s.1, 3);
        let mut b = PixelSamples::new(s.0, s.1, 3);
        let mut cells = [false; 16];
        for i in 0..16 {
            a.start([5, -2], i);
            b.start([5, -2], i);
            let (pa, pb) = (a.get2d(), b.get2d());
            assert_eq!(pa, pb);
            let c = (pa[0] * 4.0) as usize + 4 * (pa[1] * 4.0) as usize;
            assert!(!cells[c], "two samples in one stratum");
            cells[c] = true;
        }
        let mut r = PixelSamples::new(SamplerKind::Random, 4, 3);
        r.start([0, 0], 0);
        let x = r.get2d();
        r.start([0, 0], 0);
        assert_eq!(x, r.get2d());
    }
}
