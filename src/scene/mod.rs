//! STAGE 2: directives → a [`Scene`]: camera, film, sampler and filter settings, geometry with its BVHs,
//! materials, textures and lights.
//!
//! The scene keeps *descriptions*: what the file said, checked and with its source locations
//! ([`film::FilmSpec`], [`sampler::SamplerSpec`], [`filter::FilterSpec`], [`material::MaterialSpec`],
//! [`texture::TextureSpec`], [`light::LightSpec`], [`light::AreaLightSpec`]). `shading` builds the evaluated
//! objects from them (`Materials`, `Textures`, `Lights`), and `render` the film that accumulates samples.
//!
//! [`load`] runs stages 1 and 2 for a scene file. Depends on `parse` (for directives) and `sampling`;
//! nothing here knows about integrators, caches or images.

pub mod accel;
mod builder;
pub mod camera;
pub mod film;
pub mod filter;
pub mod geometry;
pub mod light;
pub mod material;
pub mod mesh;
pub mod props;
pub mod ray;
pub mod sampler;
pub mod shapes;
pub mod texture;
pub mod transform;

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3A;

use crate::error::{Result, SourceLoc, Warnings};
use crate::parse::Named;

/// Options that change how a scene is loaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// pbrt-v3's `--quick`: film resolution ÷ 4 and one sample per pixel.
    pub quick: bool,
    /// Film resolution instead of the scene's (the camera's screen window follows the new aspect ratio).
    pub resolution: Option<[u32; 2]>,
    /// Crop window instead of the Film's `cropwindow` (pbrt-v3's `--cropwindow`).
    pub crop: Option<CropWindow>,
}

/// A crop window given on the command line: fractions x0, x1, y0, y1 of the film, each in [0, 1], with
/// x0 < x1 and y0 < y1 ([`CropWindow::parse`] makes only such windows, so equality is that of the numbers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CropWindow(pub [f64; 4]);

impl Eq for CropWindow {}

impl CropWindow {
    /// Reads `x0,x1,y0,y1` (pbrt-v3's `--cropwindow` order); the message says what is wrong.
    pub fn parse(s: &str) -> std::result::Result<CropWindow, String> {
        let v: Vec<f64> = s
            .split([',', ' '])
            .filter(|t| !t.is_empty())
            .map(|t| t.trim().parse::<f64>().map_err(|_| format!("\"{t}\" is not a number")))
            .collect::<std::result::Result<_, _>>()?;
        let [x0, x1, y0, y1] = v[..] else {
            return Err(format!("expected four numbers x0,x1,y0,y1, got {}", v.len()));
        };
        if v.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err("each of x0,x1,y0,y1 must be between 0 and 1".into());
        }
        if x0 >= x1 || y0 >= y1 {
            return Err("the window is empty: x0 < x1 and y0 < y1 are needed".into());
        }
        Ok(CropWindow([x0, x1, y0, y1]))
    }
}

/// What loading took and produced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadStats {
    /// Seconds spent reading and parsing scene text.
    pub parse_secs: f64,
    /// Seconds spent turning directives into geometry (mesh files included), BVH excluded.
    pub build_secs: f64,
    /// Seconds spent building BVHs.
    pub bvh_secs: f64,
    /// Shape directives turned into geometry.
    pub shapes: usize,
    /// The same, per shape type (`"sphere"`, `"plymesh"`, …), sorted by name.
    pub shape_types: Vec<(String, usize)>,
    /// Triangles stored (object definitions counted once).
    pub triangles: usize,
    /// Object instances.
    pub instances: usize,
}

/// A scene ready to render.
#[derive(Debug)]
pub struct Scene {
    /// The top-level scene file.
    pub source: PathBuf,
    /// The camera.
    pub camera: camera::Camera,
    /// Film settings.
    pub film: film::FilmSpec,
    /// Pixel reconstruction filter.
    pub filter: filter::FilterSpec,
    /// Sampler settings.
    pub sampler: sampler::SamplerSpec,
    /// Everything rays can hit.
    pub geometry: geometry::Geometry,
    /// Materials; id 0 is pbrt-v3's default matte.
    pub materials: Vec<material::MaterialSpec>,
    /// Textures.
    pub textures: Vec<texture::TextureSpec>,
    /// Non-area light sources.
    pub lights: Vec<light::LightSpec>,
    /// Emitting shapes.
    pub area_lights: Vec<light::AreaLightSpec>,
    /// Where the scene wrote the render options that integrators may not use (so they can say so).
    pub declared: Declared,
}

/// Where the scene file set render options explicitly (`None`: not written, the default applies).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Declared {
    /// The `Sampler` directive.
    pub sampler: Option<SourceLoc>,
    /// The `PixelFilter` directive.
    pub filter: Option<SourceLoc>,
}

impl Scene {
    /// World bounds of all geometry (`None` for an empty world).
    pub fn bounds(&self) -> Option<(Vec3A, Vec3A)> {
        self.geometry.accel.bounds()
    }

    /// Length of the diagonal of the world bounds (0 for an empty world): ALGORITHMS.md's L.
    pub fn diagonal(&self) -> f32 {
        self.bounds().map_or(0.0, |(lo, hi)| (hi - lo).length())
    }

    /// Whether material `id` has no BSDF (pbrt-v3 passes camera rays through such surfaces).
    pub fn is_null_material(&self, id: u32) -> bool {
        self.materials.get(id as usize).is_some_and(|m| m.is_null())
    }
}

/// A loaded scene with the parts that belong to the render stage and the problems found.
#[derive(Debug)]
pub struct LoadedScene {
    /// The scene.
    pub scene: Scene,
    /// The `Integrator` directive, if any (read by the render stage, which knows the integrators).
    pub integrator: Option<Named>,
    /// Warnings from parsing and building, in file order.
    pub warnings: Warnings,
    /// Timings and counts.
    pub stats: LoadStats,
}

/// Parses and builds the scene file at `path`.
pub fn load(path: &Path, opts: LoadOptions) -> Result<LoadedScene> {
    let t = Instant::now();
    let directives = crate::parse::parse_file(path)?;
    let stats = LoadStats { parse_secs: t.elapsed().as_secs_f64(), ..Default::default() };
    build(directives, path, opts, stats)
}

/// Parses and builds scene text given in memory (as if it were the file `name`).
pub fn load_str(text: &str, name: &Path, opts: LoadOptions) -> Result<LoadedScene> {
    let t = Instant::now();
    let directives = crate::parse::parse_str(text, name)?;
    let stats = LoadStats { parse_secs: t.elapsed().as_secs_f64(), ..Default::default() };
    build(directives, name, opts, stats)
}

fn build(
    directives: Vec<crate::parse::Directive>,
    path: &Path,
    opts: LoadOptions,
    stats: LoadStats,
) -> Result<LoadedScene> {
    let t = Instant::now();
    let mut loaded = builder::SceneBuilder::new(opts).build(directives, path, stats)?;
    loaded.stats.build_secs = t.elapsed().as_secs_f64() - loaded.stats.bvh_secs;
    Ok(loaded)
}

/// Resolves a file name written in a scene file: absolute names as they are, relative names against the
/// folder of the file that names them (the same rule as `Include`).
pub fn resolve_path(loc: &SourceLoc, name: &str) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    match loc.file.parent() {
        Some(dir) => dir.join(p),
        None => p.to_path_buf(),
    }
}
