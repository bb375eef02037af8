//! STAGE 3: the scene's length scale L, the one length every scale-dependent default is a multiple of
//! (λ = 0.5/L, the exact-hit radius, the placement searches' bounds, cache AO's `maxdistance` = 0.1·L,
//! importance caching's d_c = `clamp`·L). The paper takes L to be the diagonal of the scene's bounding box;
//! on an open scene (a large ground plane around a small subject) that is the size of the ground, not of
//! what the image shows, so here L is bounded by what the camera sees:
//!
//! - the *view extent* V is the diagonal of the box spanning, on each axis, the [`TRIM`] and 1 − [`TRIM`]
//!   quantiles of the points seen through a [`GRID`]×[`GRID`] grid of camera rays evenly spread over the
//!   film (the pixel centres themselves when the image is at most that size): a coarse G-buffer, traced
//!   before anything else so that settings resolved before the G-buffer (cache AO's distance, importance
//!   caching's VPLs) and the G-buffer's consumers read the same L;
//! - L = min(D, [`VIEW_FACTOR`] · V), D the scene's bounding-box diagonal; D when no ray sees the scene.
//!
//! A closed scene (a room, a box) is seen across most of its extent, so 4·V ≥ D and L stays D exactly;
//! only a scene whose geometry reaches far beyond what the camera sees gets a smaller L.
//!
//! Deterministic: the grid is fixed by the film, rays are traced in parallel but collected in grid order,
//! and the quantiles are exact order statistics.

use glam::Vec3A;
use rayon::prelude::*;
use serde::Serialize;

use super::shading_point;
use crate::parse::integrator::json_f32;
use crate::scene::Scene;

/// Rays along each film axis of the grid that measures the view extent (fewer on an axis with fewer pixels).
pub const GRID: usize = 64;
/// The fraction of seen points cut at each end of each axis: the view box spans the TRIM and 1 − TRIM
/// quantiles, so a thin band of far-away points (ground seen near the horizon) does not set it.
pub const TRIM: f32 = 0.05;
/// L is at most this many view extents.
pub const VIEW_FACTOR: f32 = 4.0;

/// Where L came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ScaleSource {
    /// The scene's bounding-box diagonal D (the camera sees most of the scene, or nothing of it).
    SceneDiagonal,
    /// [`VIEW_FACTOR`] times the view extent V (smaller than D).
    CameraView,
}

/// The scene's length scale L and what it was made from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SceneScale {
    /// L: min(D, [`VIEW_FACTOR`] · V).
    #[serde(serialize_with = "short")]
    pub length: f32,
    /// Where L came from.
    pub source: ScaleSource,
    /// D: the diagonal of the scene's bounding box (0 for an empty scene).
    #[serde(serialize_with = "short")]
    pub scene_diagonal: f32,
    /// V: the diagonal of the trimmed box of the seen points (`None` when no ray saw the scene).
    #[serde(serialize_with = "short_opt")]
    pub view_extent: Option<f32>,
    /// Camera rays traced to measure V.
    pub rays: usize,
    /// Of those, the rays that saw a surface.
    pub seen: usize,
}

impl SceneScale {
    /// The scale of `scene` as its camera sees it through the cropped film.
    pub fn of(scene: &Scene) -> Self {
        let b = scene.film.cropped_bounds();
        let [w, h] = b.size();
        let (nx, ny) = (w.min(GRID), h.min(GRID));
        let (sx, sy) = (w as f32 / nx.max(1) as f32, h as f32 / ny.max(1) as f32);
        let points: Vec<Option<Vec3A>> = (0..nx * ny)
            .into_par_iter()
            .map(|i| {
                let x = b.min[0] as f32 + ((i % nx) as f32 + 0.5) * sx;
                let y = b.min[1] as f32 + ((i / nx) as f32 + 0.5) * sy;
                shading_point(scene, [x, y]).map(|sp| sp.p)
            })
            .collect();
        let seen: Vec<Vec3A> = points.into_iter().flatten().collect();
        Self::from_points(scene.diagonal(), nx * ny, &seen)
    }

    /// The scale of a scene of diagonal `scene_diagonal` whose camera saw `seen` through `rays` rays.
    pub fn from_points(scene_diagonal: f32, rays: usize, seen: &[Vec3A]) -> Self {
        let view_extent = view_extent(seen, TRIM);
        let (length, source) = match view_extent {
            Some(v) if VIEW_FACTOR * v < scene_diagonal => (VIEW_FACTOR * v, ScaleSource::CameraView),
            _ => (scene_diagonal, ScaleSource::SceneDiagonal),
        };
        SceneScale { length, source, scene_diagonal, view_extent, rays, seen: seen.len() }
    }

    /// L = D without looking through the camera (synthetic G-buffers, tests).
    pub fn diagonal_only(scene_diagonal: f32) -> Self {
        SceneScale {
            length: scene_diagonal,
            source: ScaleSource::SceneDiagonal,
            scene_diagonal,
            view_extent: None,
            rays: 0,
            seen: 0,
        }
    }
}

/// An `f32` in its shortest decimal form, as the rest of the report writes them.
fn short<S: serde::Serializer>(v: &f32, s: S) -> Result<S::Ok, S::Error> {
    json_f32(*v).serialize(s)
}

fn short_opt<S: serde::Serializer>(v: &Option<f32>, s: S) -> Result<S::Ok, S::Error> {
    v.map(json_f32).serialize(s)
}

/// The diagonal of the box spanning the `trim` and 1 − `trim` quantiles of `points` on each axis (exact
/// order statistics; non-finite points are left out); `None` without a finite point, or when the box is a
/// single point.
pub fn view_extent(points: &[Vec3A], trim: f32) -> Option<f32> {
    let finite: Vec<Vec3A> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let n = finite.len();
    if n == 0 {
        return None;
    }
    let k = ((trim.clamp(0.0, 0.5) * n as f32) as usize).min((n - 1) / 2);
    let mut side = [0f32; 3];
    let mut axis: Vec<f32> = Vec::with_capacity(n);
    for (a, s) in side.iter_mut().enumerate() {
        axis.clear();
        axis.extend(finite.iter().map(|p| p[a]));
        let lo = *axis.select_nth_unstable_by(k, f32::total_cmp).1;
        let hi = *axis.select_nth_unstable_by(n - 1 - k, f32::total_cmp).1;
        *s = hi - lo;
    }
    let d = Vec3A::from_array(side).length();
    (d.is_finite() && d > 0.0).then_some(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trimmed_extent_ignores_a_thin_far_tail() {
        // 100 points on a unit segment and 3 far away: a 5 % trim on 103 points cuts 5 at each end.
        let mut pts: Vec<Vec3A> = (0..100).map(|i| Vec3A::new(i as f32 / 99.0, 0.0, 0.0)).collect();
        pts.extend([Vec3A::new(1e4, 0.0, 0.0), Vec3A::new(2e4, 0.0, 0.0), Vec3A::new(3e4, 0.0, 0.0)]);
        let v = view_extent(&pts, 0.05).unwrap();
        assert!(v < 1.0 && v > 0.8, "{v}");
        assert_eq!(view_extent(&pts, 0.0), Some(3e4));
    }

    #[test]
    fn extent_of_nothing_or_one_point_is_none() {
        assert_eq!(view_extent(&[], 0.05), None);
        assert_eq!(view_extent(&[Vec3A::ONE; 4], 0.05), None);
        assert_eq!(view_extent(&[Vec3A::NAN], 0.05), None);
    }

    #[test]
    fn the_diagonal_is_kept_unless_the_view_is_much_smaller() {
        let corners = [Vec3A::ZERO, Vec3A::new(1.0, 1.0, 1.0)];
        let s = SceneScale::from_points(4.0 * 3f32.sqrt(), 2, &corners);
        assert_eq!((s.length, s.source), (4.0 * 3f32.sqrt(), ScaleSource::SceneDiagonal));
        let s = SceneScale::from_points(100.0, 2, &corners);
        assert_eq!((s.length, s.source), (4.0 * 3f32.sqrt(), ScaleSource::CameraView));
        let s = SceneScale::from_points(100.0, 5, &[]);
        assert_eq!((s.length, s.source, s.view_extent), (100.0, ScaleSource::SceneDiagonal, None));
    }
}
