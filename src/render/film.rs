//! STAGE 6 (render): film accumulation with pbrt-v3's weighted reconstruction — each sample adds
//! filter-weighted radiance to every pixel within the filter radius; a pixel is Σ w·L / Σ w. Tiles
//! accumulate privately and are merged in tile order, so the sums never depend on thread scheduling.
//!
//! Also the two Film settings every integrator honours, per-pixel and cache-based alike, each in one
//! function: the per-sample clamp `"float maxsampleluminance"` ([`clamp_sample_luminance`], pbrt-v3's
//! `Film::AddSample`) and the image scale `"float scale"` ([`apply_scale`], pbrt-v3's `Film::WriteImage`).

use crate::image::Image;
use crate::scene::film::{FilmSpec, PixelBounds};
use crate::scene::filter::FilterSpec;

/// A sample's radiance `l` clamped as pbrt-v3's `Film::AddSample` does: when its luminance y(l) exceeds
/// `max_luminance`, `l` is scaled by `max_luminance / y(l)` (so its luminance becomes the limit and its
/// colour is kept); otherwise, and for an infinite limit (the default: off), `l` is returned unchanged.
/// y uses pbrt-v3's weights (`RGBToXYZ`'s middle row: 0.212671, 0.715160, 0.072169). Every integrator's
/// samples go through here: the per-pixel pixel loop's and the cache driver's sub-pixel samples.
#[inline]
pub fn clamp_sample_luminance(l: [f32; 3], max_luminance: f32) -> [f32; 3] {
    let y = 0.212671 * l[0] + 0.715160 * l[1] + 0.072169 * l[2];
    if y > max_luminance {
        let s = max_luminance / y;
        return l.map(|v| v * s);
    }
    l
}

/// Multiplies every pixel of a finished image by the Film's `"float scale"`, once, in f32, as pbrt-v3's
/// `Film::WriteImage` does. Every integrator's image passes through here exactly once: the per-pixel
/// integrators' in `integrator::render`, the cache-based ones' (the sum of the cached image and any
/// per-pixel term, so irradiance caching's `output full` is scaled once) in `integrator::cache::render_with`.
/// A scale of 1 leaves the image untouched.
pub fn apply_scale(image: &mut Image, film: &FilmSpec) {
    let scale = film.scale;
    if scale != 1.0 {
        image.pixels.iter_mut().for_each(|p| *p = p.map(|v| v * scale));
    }
}

/// Weighted sums for a rectangle of pixels.
#[derive(Clone, Debug)]
pub struct FilmTile {
    bounds: PixelBounds,
    sums: Vec<[f32; 4]>,
}

impl FilmTile {
    /// A tile for the samples of `sample_px` (its pixel rectangle grown by the filter radius, clipped to `image`).
    pub fn new(sample_px: PixelBounds, filter: &FilterSpec, image: &PixelBounds) -> Self {
        let grow = |v: i32, r: f32, up: bool| {
            if up { (v as f32 - 0.5 + r).ceil() as i32 } else { (v as f32 + 0.5 - r).floor() as i32 }
        };
        let bounds = PixelBounds {
            min: [0, 1].map(|i| grow(sample_px.min[i], filter.radius[i], false).max(image.min[i])),
            max: [0, 1].map(|i| grow(sample_px.max[i], filter.radius[i], true).min(image.max[i])),
        };
        FilmTile { bounds, sums: vec![[0.0; 4]; bounds.area()] }
    }

    /// Adds radiance `l` seen through film position `p` (raster coordinates).
    #[inline]
    pub fn add(&mut self, p: [f32; 2], l: [f32; 3], filter: &FilterSpec) {
        let d = [p[0] - 0.5, p[1] - 0.5];
        let b = self.bounds;
        let x0 = ((d[0] - filter.radius[0]).ceil() as i32).max(b.min[0]);
        let x1 = ((d[0] + filter.radius[0]).floor() as i32 + 1).min(b.max[0]);
        let y0 = ((d[1] - filter.radius[1]).ceil() as i32).max(b.min[1]);
        let y1 = ((d[1] + filter.radius[1]).floor() as i32 + 1).min(b.max[1]);
        let w = (b.max[0] - b.min[0]) as usize;
        for y in y0..y1 {
            for x in x0..x1 {
                let wt = filter.eval(x as f32 - d[0], y as f32 - d[1]);
                if wt == 0.0 {
                    continue;
                }
                let s = &mut self.sums[(y - b.min[1]) as usize * w + (x - b.min[0]) as usize];
                s[0] += wt * l[0];
                s[1] += wt * l[1];
                s[2] += wt * l[2];
                s[3] += wt;
            }
        }
    }
}

/// The whole (cropped) film: sums in f64.
#[derive(Clone, Debug)]
pub struct Film {
    bounds: PixelBounds,
    sums: Vec<[f64; 4]>,
}

impl Film {
    /// An empty film covering `bounds` (the cropped image).
    pub fn new(bounds: PixelBounds) -> Self {
        Film { bounds, sums: vec![[0.0; 4]; bounds.area()] }
    }

    /// Adds a tile's sums (call in a fixed tile order for reproducible results).
    pub fn merge(&mut self, tile: &FilmTile) {
        let (tb, fb) = (tile.bounds, self.bounds);
        let tw = (tb.max[0] - tb.min[0]).max(0) as usize;
        let fw = (fb.max[0] - fb.min[0]).max(0) as usize;
        for y in tb.min[1]..tb.max[1] {
            for x in tb.min[0]..tb.max[0] {
                let t = tile.sums[(y - tb.min[1]) as usize * tw + (x - tb.min[0]) as usize];
                let f = &mut self.sums[(y - fb.min[1]) as usize * fw + (x - fb.min[0]) as usize];
                for k in 0..4 {
                    f[k] += t[k] as f64;
                }
            }
        }
    }

    /// The reconstructed image: Σ w·L / Σ w per pixel (0 where no sample landed), before the Film's
    /// scale ([`apply_scale`]).
    pub fn to_image(&self) -> Image {
        let [w, h] = self.bounds.size();
        let mut img = Image::new(w, h);
        for (i, s) in self.sums.iter().enumerate() {
            if s[3] != 0.0 {
                let inv = 1.0 / s[3];
                img.set(i % w, i / w, [(s[0] * inv) as f32, (s[1] * inv) as f32, (s[2] * inv) as f32]);
            }
        }
        img
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::filter::FilterKind;

    #[test]
    fn box_filter_puts_each_sample_in_its_own_pixel_and_tiles_merge_exactly() {
        let image = PixelBounds { min: [0, 0], max: [4, 2] };
        let f = FilterSpec::default();
        let mut film = Film::new(image);
        for tx in 0..2 {
            let px = PixelBounds { min: [2 * tx, 0], max: [2 * tx + 2, 2] };
            let mut tile = FilmTile::new(px, &f, &image);
            for y in 0..2 {
                for x in px.min[0]..px.max[0] {
                    tile.add([x as f32 + 0.25, y as f32 + 0.75], [x as f32, y as f32, 1.0], &f);
                    tile.add([x as f32 + 0.75, y as f32 + 0.25], [x as f32 + 2.0, y as f32, 1.0], &f);
                }
            }
            film.merge(&tile);
        }
        let img = film.to_image();
        assert_eq!(img.get(3, 1), [4.0, 1.0, 1.0]);
        assert_eq!(img.get(0, 0), [1.0, 0.0, 1.0]);
    }

    #[test]
    fn the_clamp_keeps_colour_and_sets_luminance_to_the_limit() {
        let l = [10.0, 20.0, 40.0];
        assert_eq!(clamp_sample_luminance(l, f32::INFINITY), l);
        assert_eq!(clamp_sample_luminance(l, 100.0), l);
        let c = clamp_sample_luminance(l, 2.0);
        let y = 0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2];
        assert!((y - 2.0).abs() < 1e-6, "{y}");
        assert!((c[2] / c[0] - 4.0).abs() < 1e-6, "{c:?}");
    }

    #[test]
    fn wide_filters_spread_samples_to_neighbours() {
        let image = PixelBounds { min: [0, 0], max: [3, 3] };
        let f = FilterSpec { radius: [1.5, 1.5], kind: FilterKind::Triangle };
        let mut tile = FilmTile::new(PixelBounds { min: [1, 1], max: [2, 2] }, &f, &image);
        tile.add([1.5, 1.5], [1.0, 1.0, 1.0], &f);
        let mut film = Film::new(image);
        film.merge(&tile);
        let img = film.to_image();
        assert_eq!(img.get(0, 0), [1.0; 3]);
        assert_eq!(img.get(2, 1), [1.0; 3]);
    }
}
