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
use crate::sampling::sequence::{permute, sobol02};

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
    /// The keys of the first dimensions of `keys_pixel`'s samples (`keys_known` of them): every sample of a
    /// pixel uses the same ones, so they are hashed once per pixel, not once per sample.
    keys: [u64; KEPT_KEYS],
    keys_known: usize,
    keys_pixel: u64,
}

/// How many dimension keys [`PixelSamples`] remembers per pixel (later dimensions are hashed each time).
const KEPT_KEYS: usize = 64;

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
            keys: [0; KEPT_KEYS],
            keys_known: 0,
            keys_pixel: 0,
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

    /// The key of the next dimension: hash3(seed, pixel, dimension), remembered for the pixel's next samples.
    fn dim_key(&mut self) -> u64 {
        self.dim += 1;
        let d = (self.dim - 1) as usize;
        if d < self.keys_known {
            return self.keys[d];
        }
        let k = hash3(self.seed, self.pixel_key, self.dim);
        // Dimensions are drawn in order, so an unknown one is the next to remember.
        if d == self.keys_known && d < KEPT_KEYS {
            self.keys[d] = k;
            self.keys_known += 1;
        }
        k
    }

    /// The next two dimensions: stratified across the pixel's samples (or uniform for `random`).
    pub fn get2d(&mut self) -> [f32; 2] {
        match self.kind {
            SamplerKind::Random => self.rng.uniform2(),
            SamplerKind::Stratified => {
                let k = self.dim_key();
                let i = permute(self.index, self.spp, k as u32);
                sobol02(i, [(k >> 32) as u32, mix64(k) as u32])
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
                let k = self.dim_key();
                let s = [(k >> 32) as u32, mix64(k) as u32];
                let n = out.len() as u64;
                let block = permute(self.index, self.spp, mix64(k ^ ARRAY_BLOCKS) as u32) as u64;
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
