//! STAGE 5 (shading): an image texture's texels and their lookup — the finest level of pbrt-v3's `MIPMap`.
//!
//! As pbrt-v3 does, an image whose sides are not powers of two is first resampled up to the next powers
//! of two with its 4-tap Lanczos filter (τ = 2), wrapping as the texture wraps, negative results clamped
//! to 0; texel (s, t) = (0, 0) is the lower-left corner. Only that level is kept: cachert traces no ray
//! differentials, so every lookup is at pbrt-v3's finest level — which is where pbrt-v3 itself looks
//! whenever a ray's footprint is under one texel (its camera rays' differentials are ⅛ pixel apart at 64
//! or more samples per pixel).
//!
//! Two filters, as pbrt-v3 chooses them with the imagemap's `trilinear` flag:
//! - `trilinear` true: bilinear interpolation of the four nearest texels (v3's `triangle` at level 0);
//! - `trilinear` false (the default): v3's EWA filter in the limit of a footprint much smaller than a
//!   texel, which is not bilinear: v3 adds one texel to the ellipse's radii, so the filter is a Gaussian
//!   (its 128-entry table of e^{−2r²} − e^{−2}) over the texels within one texel's distance.
//!
//! Lookups never allocate. Depends on nothing outside this module.

/// What a lookup outside the image gives (pbrt-v3's `ImageWrap`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles the plane.
    Repeat,
    /// Black outside.
    Black,
    /// The edge texels extend outward.
    Clamp,
}

impl Wrap {
    /// pbrt-v3's `wrap` parameter: `"black"`, `"clamp"`, anything else repeats (`None` when the name is
    /// not one of pbrt-v3's three, so the caller can warn).
    pub fn from_name(name: &str) -> Option<Wrap> {
        match name {
            "repeat" => Some(Wrap::Repeat),
            "black" => Some(Wrap::Black),
            "clamp" => Some(Wrap::Clamp),
            _ => None,
        }
    }
}

/// Size of pbrt-v3's EWA weight table.
const LUT_SIZE: usize = 128;

/// An image ready for lookups: power-of-two sides, linear RGB, row 0 at the bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct MipMap {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    wrap: Wrap,
    lut: [f32; LUT_SIZE],
}

impl MipMap {
    /// Builds the lookup level from `texels` (`width`×`height`, row 0 at the bottom), resampling to powers
    /// of two as pbrt-v3 does. `None` when the size is 0 or does not match the texel count.
    pub fn new(width: usize, height: usize, texels: Vec<[f32; 3]>, wrap: Wrap) -> Option<MipMap> {
        if width == 0 || height == 0 || width.checked_mul(height) != Some(texels.len()) {
            return None;
        }
        let (w2, h2) = (width.checked_next_power_of_two()?, height.checked_next_power_of_two()?);
        let texels = if (w2, h2) == (width, height) { texels } else { resample(width, height, &texels, w2, h2, wrap) };
        let lut = std::array::from_fn(|i| {
            let r2 = i as f32 / (LUT_SIZE - 1) as f32;
            (-2.0 * r2).exp() - (-2.0f32).exp()
        });
        Some(MipMap { width: w2, height: h2, texels, wrap, lut })
    }

    /// Width and height of the lookup level (powers of two).
    pub fn size(&self) -> [usize; 2] {
        [self.width, self.height]
    }

    /// The texels of the lookup level, row-major.
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// Texel (s, t) with the wrap mode applied (t = 0 is the bottom row).
    #[inline]
    pub fn texel(&self, s: i64, t: i64) -> [f32; 3] {
        let (w, h) = (self.width as i64, self.height as i64);
        let (s, t) = match self.wrap {
            Wrap::Repeat => (repeat(s, w), repeat(t, h)),
            Wrap::Clamp => (s.clamp(0, w - 1), t.clamp(0, h - 1)),
            Wrap::Black => {
                if s < 0 || s >= w || t < 0 || t >= h {
                    return [0.0; 3];
                }
                (s, t)
            }
        };
        self.texels[(t * w + s) as usize]
    }

    /// Bilinear interpolation at texture coordinates `st` (v3's `MIPMap::triangle` at level 0).
    #[inline]
    pub fn bilinear(&self, st: [f32; 2]) -> [f32; 3] {
        let [s, t] = self.texel_coords(st);
        let (s0, t0) = (s.floor(), t.floor());
        let (ds, dt) = (s - s0, t - t0);
        let (s0, t0) = (s0 as i64, t0 as i64);
        let mut out = [0.0; 3];
        for (w, ts, tt) in [
            ((1.0 - ds) * (1.0 - dt), s0, t0),
            ((1.0 - ds) * dt, s0, t0 + 1),
            (ds * (1.0 - dt), s0 + 1, t0),
            (ds * dt, s0 + 1, t0 + 1),
        ] {
            let v = self.texel(ts, tt);
            for c in 0..3 {
                out[c] += w * v[c];
            }
        }
        out
    }

    /// pbrt-v3's EWA filter at level 0 for a vanishing footprint: Gaussian weights from its table over the
    /// texels closer than one texel to `st` (in texel units, texel centres at half-integers).
    #[inline]
    pub fn ewa(&self, st: [f32; 2]) -> [f32; 3] {
        let [s, t] = self.texel_coords(st);
        let (s0, s1) = ((s - 1.0).ceil() as i64, (s + 1.0).floor() as i64);
        let (t0, t1) = ((t - 1.0).ceil() as i64, (t + 1.0).floor() as i64);
        let mut sum = [0.0f32; 3];
        let mut sum_w = 0.0f32;
        for it in t0..=t1 {
            let tt = it as f32 - t;
            for is in s0..=s1 {
                let ss = is as f32 - s;
                let r2 = ss * ss + tt * tt;
                if r2 < 1.0 {
                    let w = self.lut[((r2 * LUT_SIZE as f32) as usize).min(LUT_SIZE - 1)];
                    let v = self.texel(is, it);
                    for c in 0..3 {
                        sum[c] += w * v[c];
                    }
                    sum_w += w;
                }
            }
        }
        // The texel nearest to (s, t) is within √½ texel, so sum_w > 0.
        sum.map(|x| x / sum_w)
    }

    /// `st` in texel units with texel centres at integers (v3's `st · size − ½`), kept in a range where
    /// integer conversions are exact and neighbours do not overflow (the image repeats long before).
    #[inline]
    fn texel_coords(&self, st: [f32; 2]) -> [f32; 2] {
        const LIMIT: f32 = (1u64 << 40) as f32;
        let s = (st[0] * self.width as f32 - 0.5).clamp(-LIMIT, LIMIT);
        let t = (st[1] * self.height as f32 - 0.5).clamp(-LIMIT, LIMIT);
        [if s.is_nan() { 0.0 } else { s }, if t.is_nan() { 0.0 } else { t }]
    }
}

/// `x.rem_euclid(n)` for n > 0, without the 64-bit division when x is already in [0, n) (most lookups; a
/// bilinear lookup wraps eight coordinates, and the divisions were most of its cost).
#[inline]
fn repeat(x: i64, n: i64) -> i64 {
    if (x as u64) < n as u64 { x } else { x.rem_euclid(n) }
}

/// pbrt-v3's `Lanczos(x, τ = 2)`: the windowed sinc, 0 beyond |x| = 1.
pub fn lanczos(x: f32) -> f32 {
    const TAU: f32 = 2.0;
    let x = x.abs();
    if x < 1e-5 {
        return 1.0;
    }
    if x > 1.0 {
        return 0.0;
    }
    let x = x * std::f32::consts::PI;
    ((x * TAU).sin() / (x * TAU)) * (x.sin() / x)
}

/// One output texel's four source texels and their normalised weights (v3's `resampleWeights`).
fn resample_weights(old: usize, new: usize) -> Vec<(i64, [f32; 4])> {
    const FILTER_WIDTH: f32 = 2.0;
    (0..new)
        .map(|i| {
            let center = (i as f32 + 0.5) * old as f32 / new as f32;
            let first = ((center - FILTER_WIDTH) + 0.5).floor() as i64;
            let mut w: [f32; 4] =
                std::array::from_fn(|j| lanczos((first as f32 + j as f32 + 0.5 - center) / FILTER_WIDTH));
            let inv = 1.0 / (w[0] + w[1] + w[2] + w[3]);
            w.iter_mut().for_each(|x| *x *= inv);
            (first, w)
        })
        .collect()
}

/// The source index for tap `i` of a line of `n` texels under `wrap` (`None`: outside, contributes 0).
fn wrap_index(i: i64, n: usize, wrap: Wrap) -> Option<usize> {
    let n = n as i64;
    let i = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Black => i,
    };
    (0..n).contains(&i).then_some(i as usize)
}

/// v3's power-of-two resampling: Lanczos along s for every source row, then along t with the result
/// clamped to be non-negative.
fn resample(w: usize, h: usize, img: &[[f32; 3]], w2: usize, h2: usize, wrap: Wrap) -> Vec<[f32; 3]> {
    let sw = resample_weights(w, w2);
    let mut wide = vec![[0.0f32; 3]; w2 * h];
    for t in 0..h {
        for (s, (first, wt)) in sw.iter().enumerate() {
            let out = &mut wide[t * w2 + s];
            for (j, wj) in wt.iter().enumerate() {
                if let Some(src) = wrap_index(first + j as i64, w, wrap) {
                    let v = img[t * w + src];
                    for c in 0..3 {
                        out[c] += wj * v[c];
                    }
                }
            }
        }
    }
    let tw = resample_weights(h, h2);
    let mut out = vec![[0.0f32; 3]; w2 * h2];
    for s in 0..w2 {
        for (t, (first, wt)) in tw.iter().enumerate() {
            let mut acc = [0.0f32; 3];
            for (j, wj) in wt.iter().enumerate() {
                if let Some(src) = wrap_index(first + j as i64, h, wrap) {
                    let v = wide[src * w2 + s];
                    for c in 0..3 {
                        acc[c] += wj * v[c];
                    }
                }
            }
            out[t * w2 + s] = acc.map(|x| x.max(0.0));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeat_is_rem_euclid() {
        for n in [1i64, 2, 3, 7, 1024] {
            for x in (-3 * n - 2..=3 * n + 2).chain([i64::MIN + 1, i64::MAX, 1 << 40, -(1 << 40)]) {
                assert_eq!(repeat(x, n), x.rem_euclid(n), "{x} mod {n}");
            }
        }
    }

    /// A 4×2 image whose texel (s, t) is (s, t, s + 10t).
    fn ramp(wrap: Wrap) -> MipMap {
        let texels = (0..2).flat_map(|t| (0..4).map(move |s| [s as f32, t as f32, (s + 10 * t) as f32])).collect();
        MipMap::new(4, 2, texels, wrap).unwrap()
    }

    /// Texture coordinates of the centre of texel (s, t) in a `w`×`h` image.
    fn centre(s: f32, t: f32, w: f32, h: f32) -> [f32; 2] {
        [(s + 0.5) / w, (t + 0.5) / h]
    }

    #[test]
    fn both_filters_return_the_texel_at_its_centre() {
        let m = ramp(Wrap::Repeat);
        for t in 0..2 {
            for s in 0..4 {
                let st = centre(s as f32, t as f32, 4.0, 2.0);
                let want = [s as f32, t as f32, (s + 10 * t) as f32];
                assert_eq!(m.bilinear(st), want, "bilinear at texel ({s}, {t})");
                let e = m.ewa(st);
                assert!(e.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-5), "ewa at ({s}, {t}): {e:?}");
            }
        }
    }

    #[test]
    fn bilinear_interpolates_between_centres() {
        let m = ramp(Wrap::Clamp);
        // Halfway between texels (1, 0) and (2, 1): the mean of the four around it.
        let v = m.bilinear(centre(1.5, 0.5, 4.0, 2.0));
        assert_eq!(v, [1.5, 0.5, 6.5]);
        // A quarter of the way from (0, 0) to (1, 0).
        let v = m.bilinear(centre(0.25, 0.0, 4.0, 2.0));
        assert!((v[0] - 0.25).abs() < 1e-6);
    }

    #[test]
    fn ewa_limit_is_a_radial_gaussian_not_bilinear() {
        let m = ramp(Wrap::Clamp);
        // Halfway between two texel centres along s: both at distance ½, weight e^{−½}−e^{−2} each (table
        // entry 32), plus nothing else (every other texel is at least √(½²+1²) > 1 away).
        let v = m.ewa(centre(1.5, 0.0, 4.0, 2.0));
        assert!((v[0] - 1.5).abs() < 1e-6, "{v:?}");
        // A quarter of the way: weights w(1/16) and w(9/16) from the table, so not ¼ as bilinear gives.
        let lut = |r2: f32| m.lut[((r2 * 128.0) as usize).min(127)];
        let (w0, w1) = (lut(1.0 / 16.0), lut(9.0 / 16.0));
        // Texel (0, 1) is at distance √(1/16 + 1) > 1: excluded.
        let v = m.ewa(centre(0.25, 0.0, 4.0, 2.0));
        let want = w1 / (w0 + w1);
        assert!((v[0] - want).abs() < 1e-6, "{} vs {want}", v[0]);
        assert!((v[0] - 0.25).abs() > 0.02, "differs from bilinear");
    }

    #[test]
    fn wrap_modes_outside_the_image() {
        let repeat = ramp(Wrap::Repeat);
        assert_eq!(repeat.texel(-1, 0), [3.0, 0.0, 3.0]);
        assert_eq!(repeat.texel(4, 3), [0.0, 1.0, 10.0]);
        let clamp = ramp(Wrap::Clamp);
        assert_eq!(clamp.texel(-5, 9), [0.0, 1.0, 10.0]);
        assert_eq!(clamp.texel(7, -2), [3.0, 0.0, 3.0]);
        let black = ramp(Wrap::Black);
        assert_eq!(black.texel(-1, 0), [0.0; 3]);
        assert_eq!(black.texel(0, 2), [0.0; 3]);
        assert_eq!(black.texel(3, 1), [3.0, 1.0, 13.0]);
        // Repeat: s = 1.25 is texel column 1 of the next tile; black: beyond the image, 0.
        assert_eq!(repeat.bilinear(centre(5.0, 0.0, 4.0, 2.0)), [1.0, 0.0, 1.0]);
        assert_eq!(black.bilinear(centre(5.0, 0.0, 4.0, 2.0)), [0.0; 3]);
        assert_eq!(clamp.bilinear([7.0, -3.0]), [3.0, 0.0, 3.0]);
        assert_eq!(Wrap::from_name("clamp"), Some(Wrap::Clamp));
        assert_eq!(Wrap::from_name("mirror"), None);
    }

    #[test]
    fn huge_and_nan_coordinates_do_not_panic() {
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Black] {
            let m = ramp(wrap);
            for st in [[f32::NAN, 0.5], [1e30, -1e30], [f32::INFINITY, f32::NEG_INFINITY], [-3e9, 7e12]] {
                assert!(m.bilinear(st).iter().all(|x| x.is_finite()), "{wrap:?} {st:?}");
                assert!(m.ewa(st).iter().all(|x| x.is_finite()), "{wrap:?} {st:?}");
            }
        }
    }

    #[test]
    fn lanczos_matches_its_definition() {
        assert_eq!(lanczos(0.0), 1.0);
        assert_eq!(lanczos(1.5), 0.0);
        assert!(lanczos(1.0).abs() < 1e-6);
        // sinc(π·0.5·2)·sinc(π·0.5) = 0 · … : a zero of the outer sinc.
        assert!(lanczos(0.5).abs() < 1e-6);
        let x = 0.3f32 * std::f32::consts::PI;
        let want = ((2.0 * x).sin() / (2.0 * x)) * (x.sin() / x);
        assert!((lanczos(-0.3) - want).abs() < 1e-6);
    }

    #[test]
    fn non_power_of_two_images_are_resampled_up_and_keep_constants() {
        // A constant image stays constant (weights are normalised); size goes up to powers of two.
        let m = MipMap::new(3, 5, vec![[0.25, 0.5, 2.0]; 15], Wrap::Repeat).unwrap();
        assert_eq!(m.size(), [4, 8]);
        for t in 0..8 {
            for s in 0..4 {
                let v = m.texel(s, t);
                assert!((v[0] - 0.25).abs() < 1e-5 && (v[2] - 2.0).abs() < 1e-5, "{v:?}");
            }
        }
        // Black wrap: the taps beyond the edge count as 0 — edges darken, as in pbrt-v3.
        let b = MipMap::new(3, 1, vec![[1.0; 3]; 3], Wrap::Black).unwrap();
        assert!(b.texel(0, 0)[0] < 0.99 && b.texel(1, 0)[0] > b.texel(0, 0)[0]);
        assert!(MipMap::new(0, 4, vec![], Wrap::Repeat).is_none());
        assert!(MipMap::new(2, 2, vec![[0.0; 3]; 3], Wrap::Repeat).is_none());
    }
}
