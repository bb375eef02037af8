//! STAGE 6 (render): film accumulation with pbrt-v3's weighted reconstruction — each sample adds
//! filter-weighted radiance to every pixel within the filter radius; a pixel is Σ w·L / Σ w. Tiles
//! accumulate privately and are merged in tile order, so the sums never depend on thread scheduling.

use crate::image::Image;
use crate::scene::film::PixelBounds;
use crate::scene::filter::FilterSpec;

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

    /// The final image: Σ w·L / Σ w per pixel (0 where no sample landed), times `scale`.
    pub fn to_image(&self, scale: f32) -> Image {
        let [w, h] = self.bounds.size();
        let mut img = Image::new(w, h);
        for (i, s) in self.sums.iter().enumerate() {
            if s[3] != 0.0 {
                let inv = scale as f64 / s[3];
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
        let img = film.to_image(1.0);
        assert_eq!(img.get(3, 1), [4.0, 1.0, 1.0]);
        assert_eq!(img.get(0, 0), [1.0, 0.0, 1.0]);
    }

    #[test]
    fn wide_filters_spread_samples_to_neighbours() {
        let image = PixelBounds { min: [0, 0], max: [3, 3] };
        let f = FilterSpec { radius: [1.5, 1.5], kind: FilterKind::Triangle };
        let mut tile = FilmTile::new(PixelBounds { min: [1, 1], max: [2, 2] }, &f, &image);
        tile.add([1.5, 1.5], [1.0, 1.0, 1.0], &f);
        let mut film = Film::new(image);
        film.merge(&tile);
        let img = film.to_image(1.0);
        assert_eq!(img.get(0, 0), [1.0; 3]);
        assert_eq!(img.get(2, 1), [1.0; 3]);
    }
}
