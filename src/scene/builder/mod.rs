//! STAGE 2 (scene): the scene builder — walks the directives in order, keeps pbrt-v3's graphics state
//! (transform stack, named coordinate systems, materials, textures, area light, ReverseOrientation,
//! object definitions) and produces a [`Scene`].
//!
//! One file per directive group: transforms, render options (before WorldBegin), attributes and
//! appearance (materials, textures, lights), shapes and instancing. Every problem is reported at the
//! directive or parameter that caused it.

mod appearance;
mod curves;
mod options;
mod shapes;
mod state;
mod transforms;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3A;

use crate::error::{Error, Result, SourceLoc, Warnings};
use crate::parse::{Directive, DirectiveKind, Named, ParamList};
use crate::scene::accel::{Accel, BuildPrim, PrimRef};
use crate::scene::camera::Camera;
use crate::scene::geometry::{Geometry, ObjectDef, ShapeInfo};
use crate::scene::light::{AreaLightSpec, LightSpec};
use crate::scene::material::MaterialSpec;
use crate::scene::mesh::TriangleMesh;
use crate::scene::shapes::curve::{Curve, CurveSegment};
use crate::scene::shapes::quadric::Quadric;
use crate::scene::texture::TextureSpec;
use crate::scene::transform::Transform;
use crate::scene::{LoadOptions, LoadStats, LoadedScene, Scene};
use state::{Block, Frame, GraphicsState};

/// Where in the file the builder is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Before WorldBegin: render options.
    Options,
    /// Between WorldBegin and WorldEnd.
    World,
    /// After WorldEnd.
    Done,
}

/// An object definition being recorded or already recorded.
struct ObjectRecord {
    def: ObjectDef,
    prims: Vec<BuildPrim>,
    loc: SourceLoc,
    /// Object-space bounds of `prims`, set at ObjectEnd (`None` while recording, or when empty).
    bounds: Option<(Vec3A, Vec3A)>,
}

/// Builds a [`Scene`] from directives.
pub(crate) struct SceneBuilder {
    opts: LoadOptions,
    phase: Phase,
    ctm: [Transform; 2],
    active: [bool; 2],
    named_coords: HashMap<String, [Transform; 2]>,
    gs: GraphicsState,
    stack: Vec<Frame>,
    warnings: Warnings,
    // Render options.
    camera: Option<(Named, Transform, SourceLoc)>,
    film: crate::scene::film::FilmSpec,
    film_loc: Option<SourceLoc>,
    sampler: crate::scene::sampler::SamplerSpec,
    filter: crate::scene::filter::FilterSpec,
    declared: crate::scene::Declared,
    integrator: Option<Named>,
    media: HashMap<String, SourceLoc>,
    media_warned: bool,
    // World contents.
    materials: Vec<MaterialSpec>,
    textures: Vec<TextureSpec>,
    lights: Vec<LightSpec>,
    area_lights: Vec<AreaLightSpec>,
    meshes: Vec<TriangleMesh>,
    top: Vec<BuildPrim>,
    quadrics: Vec<Quadric>,
    quadric_info: Vec<ShapeInfo>,
    curves: Vec<Curve>,
    curve_segments: Vec<CurveSegment>,
    curve_info: Vec<ShapeInfo>,
    objects: Vec<ObjectRecord>,
    object_names: HashMap<String, u32>,
    current_object: Option<u32>,
    instances: Vec<crate::scene::accel::InstanceXf>,
    shape_count: usize,
    shape_types: std::collections::BTreeMap<String, usize>,
    motion_warned: bool,
}

impl SceneBuilder {
    pub(crate) fn new(opts: LoadOptions) -> Self {
        SceneBuilder {
            opts,
            phase: Phase::Options,
            ctm: [Transform::IDENTITY; 2],
            active: [true, true],
            named_coords: HashMap::new(),
            gs: GraphicsState::default(),
            stack: Vec::new(),
            warnings: Warnings::default(),
            camera: None,
            film: Default::default(),
            film_loc: None,
            sampler: Default::default(),
            filter: Default::default(),
            declared: Default::default(),
            integrator: None,
            media: HashMap::new(),
            media_warned: false,
            materials: vec![MaterialSpec::default_matte()],
            textures: Vec::new(),
            lights: Vec::new(),
            area_lights: Vec::new(),
            meshes: Vec::new(),
            top: Vec::new(),
            quadrics: Vec::new(),
            quadric_info: Vec::new(),
            curves: Vec::new(),
            curve_segments: Vec::new(),
            curve_info: Vec::new(),
            objects: Vec::new(),
            object_names: HashMap::new(),
            current_object: None,
            instances: Vec::new(),
            shape_count: 0,
            shape_types: Default::default(),
            motion_warned: false,
        }
    }

    /// Runs every directive, then assembles the scene. `source` names the top-level file.
    pub(crate) fn build(
        mut self,
        directives: Vec<Directive>,
        source: &Path,
        mut stats: LoadStats,
    ) -> Result<LoadedScene> {
        let mut last_loc = None;
        for d in directives {
            last_loc = Some(d.loc.clone());
            self.directive(d)?;
        }
        let end = last_loc.unwrap_or_else(|| SourceLoc::new(source.into(), 1, 1));
        match self.phase {
            Phase::Options => {
                return Err(Error::at(
                    &end,
                    "the scene has no WorldBegin: expected WorldBegin … WorldEnd after the render options",
                ));
            }
            Phase::World => return Err(Error::at(&end, "the scene ends without WorldEnd")),
            Phase::Done => {}
        }
        self.finish(source, &mut stats)
    }

    fn directive(&mut self, d: Directive) -> Result<()> {
        use DirectiveKind as K;
        let loc = d.loc;
        if self.phase == Phase::Done {
            return Err(Error::at(&loc, format!("{} after WorldEnd: the scene description is over", d.kind.keyword())));
        }
        match d.kind {
            K::Identity
            | K::Translate(_)
            | K::Scale(_)
            | K::Rotate(_)
            | K::LookAt(_)
            | K::Transform(_)
            | K::ConcatTransform(_)
            | K::CoordinateSystem(_)
            | K::CoordSysTransform(_)
            | K::TransformTimes(..)
            | K::ActiveTransform(_) => self.transform_directive(d.kind, &loc),
            K::Camera(n) => self.options_only(&loc, "Camera").and_then(|_| self.camera_directive(n, &loc)),
            K::Film(n) => self.options_only(&loc, "Film").and_then(|_| self.film_directive(n, &loc)),
            K::Sampler(n) => self.options_only(&loc, "Sampler").and_then(|_| self.sampler_directive(n)),
            K::PixelFilter(n) => self.options_only(&loc, "PixelFilter").and_then(|_| self.filter_directive(n)),
            K::Integrator(n) => self.options_only(&loc, "Integrator").map(|_| self.integrator = Some(n)),
            K::Accelerator(n) => self.options_only(&loc, "Accelerator").map(|_| self.accelerator_directive(n)),
            K::MakeNamedMedium(n) => self.medium_directive(n, &loc),
            K::MediumInterface(a, b) => self.medium_interface(&a, &b, &loc),
            K::WorldBegin => self.world_begin(&loc),
            K::WorldEnd => self.world_end(&loc),
            K::AttributeBegin => self.world_only(&loc, "AttributeBegin").map(|_| self.push(Block::Attribute, &loc)),
            K::AttributeEnd => self.world_only(&loc, "AttributeEnd").and_then(|_| self.pop(Block::Attribute, &loc)),
            K::TransformBegin => self.world_only(&loc, "TransformBegin").map(|_| self.push(Block::Transform, &loc)),
            K::TransformEnd => self.world_only(&loc, "TransformEnd").and_then(|_| self.pop(Block::Transform, &loc)),
            K::ReverseOrientation => {
                self.world_only(&loc, "ReverseOrientation").map(|_| self.gs.reverse_orientation ^= true)
            }
            K::ObjectBegin(name) => self.world_only(&loc, "ObjectBegin").and_then(|_| self.object_begin(name, &loc)),
            K::ObjectEnd => self.world_only(&loc, "ObjectEnd").and_then(|_| self.object_end(&loc)),
            K::ObjectInstance(name) => {
                self.world_only(&loc, "ObjectInstance").and_then(|_| self.object_instance(&name, &loc))
            }
            K::LightSource(n) => self.world_only(&loc, "LightSource").and_then(|_| self.light_source(n, &loc)),
            K::AreaLightSource(n) => {
                self.world_only(&loc, "AreaLightSource").and_then(|_| self.area_light_source(n, &loc))
            }
            K::Material(n) => self.world_only(&loc, "Material").and_then(|_| self.material_directive(n, &loc)),
            K::MakeNamedMaterial(n) => {
                self.world_only(&loc, "MakeNamedMaterial").and_then(|_| self.make_named_material(n, &loc))
            }
            K::NamedMaterial(name) => {
                self.world_only(&loc, "NamedMaterial").and_then(|_| self.named_material(&name, &loc))
            }
            K::Texture { name, value_type, class } => {
                self.world_only(&loc, "Texture").and_then(|_| self.texture_directive(name, &value_type, class, &loc))
            }
            K::Shape(n) => self.world_only(&loc, "Shape").and_then(|_| self.shape_directive(n, &loc)),
        }
    }

    fn options_only(&self, loc: &SourceLoc, what: &str) -> Result<()> {
        match self.phase {
            Phase::Options => Ok(()),
            _ => Err(Error::at(loc, format!("{what} is a render option: it must come before WorldBegin"))),
        }
    }

    fn world_only(&self, loc: &SourceLoc, what: &str) -> Result<()> {
        match self.phase {
            Phase::World => Ok(()),
            _ => Err(Error::at(loc, format!("{what} must come between WorldBegin and WorldEnd (missing WorldBegin?)"))),
        }
    }

    /// Reports the parameters no lookup read as warnings at their own location.
    fn report_unused(&mut self, params: &ParamList, directive: &str) {
        for p in params.unused() {
            self.warnings.at(&p.loc, params.unused_message(directive, p));
        }
    }

    fn world_begin(&mut self, loc: &SourceLoc) -> Result<()> {
        if self.phase != Phase::Options {
            return Err(Error::at(loc, "WorldBegin appears twice"));
        }
        self.phase = Phase::World;
        self.ctm = [Transform::IDENTITY; 2];
        self.active = [true, true];
        self.named_coords.insert("world".into(), self.ctm);
        Ok(())
    }

    fn world_end(&mut self, loc: &SourceLoc) -> Result<()> {
        self.world_only(loc, "WorldEnd")?;
        if self.current_object.is_some() {
            return Err(Error::at(loc, "WorldEnd inside ObjectBegin: missing ObjectEnd"));
        }
        while let Some(f) = self.stack.pop() {
            self.warnings.at(&f.loc, format!("{} without a matching end before WorldEnd", f.block.begin_keyword()));
        }
        self.phase = Phase::Done;
        Ok(())
    }

    fn finish(mut self, source: &Path, stats: &mut LoadStats) -> Result<LoadedScene> {
        if let Some(r) = self.opts.resolution {
            // The flag's resolution replaces the Film's: a size too large is the flag's error, not the file's.
            if let Some(m) = crate::scene::film::memory_problem(r) {
                return Err(Error::usage(format!("--resolution {}x{}: {m}", r[0], r[1])));
            }
            self.film.resolution = r;
        }
        if let Some(c) = self.opts.crop {
            // pbrt-v3's --cropwindow replaces the Film's cropwindow.
            self.film.crop = c.0;
            let b = self.film.cropped_bounds();
            if b.max[0] <= b.min[0] || b.max[1] <= b.min[1] {
                let [x0, x1, y0, y1] = c.0;
                let [w, h] = self.film.resolution;
                return Err(Error::usage(format!(
                    "--crop {x0},{x1},{y0},{y1}: the window covers no pixel of the {w}x{h} film"
                )));
            }
        }
        let camera = match self.camera.take() {
            Some((named, world_from_camera, _)) => {
                let c = Camera::from_directive(&named, &world_from_camera, &self.film, &mut self.warnings)?;
                self.report_unused(&named.params, "Camera");
                c
            }
            None => {
                let named = Named {
                    name: "perspective".into(),
                    name_loc: SourceLoc::new(source.into(), 1, 1),
                    params: ParamList::default(),
                };
                Camera::from_directive(&named, &Transform::IDENTITY, &self.film, &mut self.warnings)?
            }
        };
        let t = Instant::now();
        let objects: Vec<ObjectRecord> = std::mem::take(&mut self.objects);
        let (defs, object_prims): (Vec<ObjectDef>, Vec<Vec<BuildPrim>>) =
            objects.into_iter().map(|o| (o.def, o.prims)).unzip();
        let accel = Accel::build(
            std::mem::take(&mut self.top),
            object_prims,
            std::mem::take(&mut self.instances),
            std::mem::take(&mut self.quadrics),
            std::mem::take(&mut self.curves),
            std::mem::take(&mut self.curve_segments),
        );
        stats.bvh_secs = t.elapsed().as_secs_f64();
        let geometry = Geometry::new(
            std::mem::take(&mut self.meshes),
            defs,
            std::mem::take(&mut self.quadric_info),
            std::mem::take(&mut self.curve_info),
            accel,
        );
        stats.shapes = self.shape_count;
        stats.shape_types = std::mem::take(&mut self.shape_types).into_iter().collect();
        stats.triangles = geometry.stored_triangles();
        let (_, _, instances) = geometry.accel.counts();
        stats.instances = instances;
        let scene = Scene {
            source: source.to_path_buf(),
            camera,
            film: self.film,
            filter: self.filter,
            sampler: self.sampler,
            geometry,
            materials: self.materials,
            textures: self.textures,
            lights: self.lights,
            area_lights: self.area_lights,
            declared: self.declared,
        };
        Ok(LoadedScene { scene, integrator: self.integrator, warnings: self.warnings, stats: stats.clone() })
    }

    /// Resolves `name` (as written in a scene file at `loc`) to a path.
    fn path(&self, loc: &SourceLoc, name: &str) -> PathBuf {
        crate::scene::resolve_path(loc, name)
    }

    /// Adds a placed mesh to the world or to the object being defined; returns its world mesh id.
    fn add_mesh(&mut self, mesh: TriangleMesh) -> Option<u32> {
        let n = mesh.triangle_count();
        let prims = |id: u32| (0..n).map(move |t| (id, t));
        match self.current_object {
            Some(o) => {
                let rec = &mut self.objects[o as usize];
                let id = rec.def.meshes.len() as u32;
                rec.prims.extend(prims(id).map(|(m, t)| tri_prim(&mesh, m, t)));
                rec.def.meshes.push(mesh);
                None
            }
            None => {
                let id = self.meshes.len() as u32;
                self.top.extend(prims(id).map(|(m, t)| tri_prim(&mesh, m, t)));
                self.meshes.push(mesh);
                Some(id)
            }
        }
    }

    /// Adds an analytic shape to the world or to the object being defined; returns its id.
    fn add_quadric(&mut self, q: Quadric, info: ShapeInfo) -> u32 {
        let id = self.quadrics.len() as u32;
        self.quadrics.push(q);
        self.quadric_info.push(info);
        let prim = BuildPrim { r: PrimRef::Quadric(id), verts: [[0.0; 3]; 3] };
        match self.current_object {
            Some(o) => self.objects[o as usize].prims.push(prim),
            None => self.top.push(prim),
        }
        id
    }

    /// Adds a curve piece, split into 2^`split_depth` segment primitives, to the world or to the object
    /// being defined; refuses a piece reaching beyond ±[`crate::scene::accel::MAX_COORD`] (before anything is added).
    fn add_curve(&mut self, curve: Curve, split_depth: u32, info: ShapeInfo) -> std::result::Result<(), String> {
        let id = self.curves.len() as u32;
        let segments: Vec<CurveSegment> = curve.segments(id, split_depth).collect();
        for seg in &segments {
            let (lo, hi) = curve.world_bounds(seg);
            crate::scene::accel::check_extent(lo, hi)?;
        }
        let first = self.curve_segments.len() as u32;
        self.curve_segments.extend(segments);
        let last = self.curve_segments.len() as u32;
        self.curves.push(curve);
        self.curve_info.push(info);
        let prims = (first..last).map(|s| BuildPrim { r: PrimRef::Curve(s), verts: [[0.0; 3]; 3] });
        match self.current_object {
            Some(o) => self.objects[o as usize].prims.extend(prims),
            None => self.top.extend(prims),
        }
        Ok(())
    }
}

fn tri_prim(mesh: &TriangleMesh, m: u32, t: usize) -> BuildPrim {
    BuildPrim { r: PrimRef::Triangle { mesh: m, tri: t as u32 }, verts: mesh.triangle(t) }
}
