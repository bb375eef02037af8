//! LDR-FLIP on a pair of images already in linear RGB within [0, 1]: the colour pipeline (spatial
//! filtering in YCxCz, then Hunt-adjusted HyAB in CIELAB) and the feature pipeline (edges and points of
//! the achromatic channel) run side by side in two parallel passes over rows:
//!
//! 1. per row: prepare the pixels (clamp, or expose and tone map for HDR), convert to YCxCz, and filter
//!    horizontally with the spatial and the feature kernels;
//! 2. per row: filter vertically, then compute colour error, feature difference and their combination.
//!
//! Each output value is computed from its inputs alone in a fixed order, so the map is bit-identical
//! whatever the number of threads. Depends on nothing else in the crate.

use rayon::prelude::*;

use super::colour::{self, ColourScale};
use super::feature;
use super::filters::{self, Kernel, Lanes};

/// The filters and constants of LDR-FLIP for one pixels-per-degree value, reusable across images.
#[derive(Clone, Debug)]
pub(crate) struct Pipeline {
    spatial: Kernel,
    feature_horizontal: Kernel,
    feature_vertical: Kernel,
    scale: ColourScale,
}

/// Horizontal pass outputs for one image: spatial lanes (Y, Cx, Cz₁, Cz₂) and feature lanes (∂x, ∂²x, G, G).
struct Filtered {
    spatial: Vec<Lanes>,
    feature: Vec<Lanes>,
}

/// Per-thread scratch rows.
#[derive(Default)]
struct Scratch {
    spatial_in: Vec<Lanes>,
    feature_in: Vec<Lanes>,
    padded: Vec<Lanes>,
}

impl Pipeline {
    /// Builds the filters for `ppd` pixels per degree.
    pub(crate) fn new(ppd: f32) -> Pipeline {
        let (feature_horizontal, feature_vertical) = filters::feature_kernels(ppd);
        Pipeline {
            spatial: filters::spatial_kernel(ppd),
            feature_horizontal,
            feature_vertical,
            scale: ColourScale::new(),
        }
    }

    /// The LDR-FLIP map of `test` against `reference` (both `width`×`height`, row-major), after
    /// `prepare` has turned each linear RGB pixel into linear RGB within [0, 1].
    pub(crate) fn run<P>(&self, width: usize, reference: &[[f32; 3]], test: &[[f32; 3]], prepare: &P) -> Vec<f32>
    where
        P: Fn([f32; 3]) -> [f32; 3] + Sync,
    {
        let reference = self.horizontal_pass(width, reference, prepare);
        let test = self.horizontal_pass(width, test, prepare);
        self.vertical_pass(width, &reference, &test)
    }

    /// Pass 1 for one image.
    fn horizontal_pass<P>(&self, width: usize, image: &[[f32; 3]], prepare: &P) -> Filtered
    where
        P: Fn([f32; 3]) -> [f32; 3] + Sync,
    {
        let mut out = Filtered { spatial: vec![[0.0; 4]; image.len()], feature: vec![[0.0; 4]; image.len()] };
        out.spatial
            .par_chunks_mut(width)
            .zip(out.feature.par_chunks_mut(width))
            .zip(image.par_chunks(width))
            .for_each_init(Scratch::default, |s, ((spatial, feature), row)| {
                s.spatial_in.clear();
                s.feature_in.clear();
                for &p in row {
                    let ycxcz = colour::linear_rgb_to_ycxcz(prepare(p));
                    s.spatial_in.push(colour::spatial_lanes(ycxcz));
                    s.feature_in.push(feature::lanes(ycxcz));
                }
                filters::horizontal(&s.spatial_in, &self.spatial, &mut s.padded, spatial);
                filters::horizontal(&s.feature_in, &self.feature_horizontal, &mut s.padded, feature);
            });
        out
    }

    /// Pass 2: vertical filtering of both images and the per-pixel FLIP value.
    fn vertical_pass(&self, width: usize, reference: &Filtered, test: &Filtered) -> Vec<f32> {
        let mut map = vec![0.0f32; reference.spatial.len()];
        map.par_chunks_mut(width).enumerate().for_each_init(
            || (vec![vec![[0.0f32; 4]; width]; 4], Vec::new()),
            |(rows, sources), (y, out)| {
                for (row, (plane, kernel)) in rows.iter_mut().zip([
                    (&reference.spatial, &self.spatial),
                    (&test.spatial, &self.spatial),
                    (&reference.feature, &self.feature_vertical),
                    (&test.feature, &self.feature_vertical),
                ]) {
                    filters::vertical(plane, width, y, kernel, sources, row);
                }
                let [sr, st, fr, ft] = &rows[..] else { unreachable!("four rows") };
                for x in 0..width {
                    let colour_error =
                        self.scale.error(colour::filtered_to_hunt_lab(sr[x]), colour::filtered_to_hunt_lab(st[x]));
                    out[x] = feature::combine(colour_error, feature::difference(fr[x], ft[x]));
                }
            },
        );
        map
    }
}
