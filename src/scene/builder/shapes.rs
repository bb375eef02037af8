//! STAGE 2 (scene builder): the Shape directive — trianglemesh, plymesh, objmesh (our extension), sphere,
//! disk, cylinder, cone, paraboloid, hyperboloid, curve, and the meshes pbrt-v3 builds for loopsubdiv,
//! heightfield and nurbs — with pbrt-v3's per-shape material overrides and area lights.

use std::f64::consts::TAU;
use std::rc::Rc;

use glam::Affine3A;

use crate::error::{Error, Result, SourceLoc};
use crate::parse::{Named, TexOr};
use crate::scene::accel::check_extent;
use crate::scene::geometry::{ShapeId, ShapeInfo};
use crate::scene::light::AreaLightSpec;
use crate::scene::mesh::{TriangleMesh, trianglemesh_params};
use crate::scene::props::{Capture, schema_has};
use crate::scene::shapes::curve::Curve;
use crate::scene::shapes::heightfield::heightfield_params;
use crate::scene::shapes::loopsubdiv::loopsubdiv_params;
use crate::scene::shapes::mesh_data::MeshData;
use crate::scene::shapes::nurbs::nurbs_params;
use crate::scene::shapes::quadric::{Quadric, QuadricKind};
use crate::scene::shapes::{obj, ply};
use crate::scene::transform::Transform;

use super::SceneBuilder;
use super::curves::{CurveSpec, curve_params};

/// The shape types cachert reads: every pbrt-v3 shape, plus `objmesh`.
const SHAPES: [&str; 13] = [
    "trianglemesh",
    "plymesh",
    "objmesh",
    "sphere",
    "disk",
    "cylinder",
    "cone",
    "paraboloid",
    "hyperboloid",
    "curve",
    "loopsubdiv",
    "heightfield",
    "nurbs",
];

enum Built {
    Mesh(MeshData),
    Quadric(QuadricKind),
    Curves(CurveSpec),
}

impl SceneBuilder {
    pub(super) fn shape_directive(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        let built = match n.name.as_str() {
            "trianglemesh" => Built::Mesh(trianglemesh_params(&n.params, loc, &mut self.warnings)?),
            "plymesh" | "objmesh" => self.mesh_file(&n, loc)?,
            "loopsubdiv" => Built::Mesh(loopsubdiv_params(&n.params, loc, &mut self.warnings)?),
            "heightfield" => Built::Mesh(heightfield_params(&n.params, loc)?),
            "nurbs" => Built::Mesh(nurbs_params(&n.params, loc, &mut self.warnings)?),
            "sphere" | "disk" | "cylinder" | "cone" | "paraboloid" | "hyperboloid" => {
                Built::Quadric(quadric_params(&n)?)
            }
            "curve" => Built::Curves(curve_params(&n, &mut self.warnings)?),
            other => {
                return Err(Error::at(
                    &n.name_loc,
                    format!("unknown shape type \"{other}\"; expected one of {}", SHAPES.join(", ")),
                ));
            }
        };
        if self.alpha_hides(&n)? {
            self.report_unused(&n.params, "Shape");
            return Ok(());
        }
        let material = self.material_for_shape(&n)?;
        self.report_unused(&n.params, "Shape");
        self.shape_count += 1;
        *self.shape_types.entry(n.name.clone()).or_default() += 1;
        let xf = self.ctm[0];
        let reverse = self.gs.reverse_orientation;
        let shape = match built {
            Built::Mesh(data) => {
                let mesh = TriangleMesh::place(data, &xf, reverse, material)
                    .map_err(|e| Error::at(loc, format!("Shape \"{}\": {e}", n.name)))?;
                self.add_mesh(mesh).map(ShapeId::Mesh)
            }
            Built::Quadric(kind) => {
                let [world_from_object, object_from_world] = placement(&xf, &n.name, loc)?;
                let mut q = Quadric::new(kind, world_from_object, reverse ^ xf.swaps_handedness());
                // The placement's own inverse (from the transform stack) is kept rather than recomputed.
                q.object_from_world = object_from_world;
                let (lo, hi) = q.world_bounds();
                check_extent(lo, hi).map_err(|e| Error::at(loc, format!("Shape \"{}\": {e}", n.name)))?;
                let id = self.add_quadric(q, ShapeInfo { material, area_light: None });
                self.current_object.is_none().then_some(ShapeId::Quadric(id))
            }
            Built::Curves(spec) => {
                let placement = placement(&xf, &n.name, loc)?;
                let flip = reverse ^ xf.swaps_handedness();
                for piece in spec.pieces {
                    let curve = Curve::new(piece.cp, piece.width, spec.kind, piece.normals, placement, flip)
                        .ok_or_else(|| Error::at(loc, "curve: a normal \"N\" is zero"))?;
                    self.add_curve(curve, spec.split_depth, ShapeInfo { material, area_light: None })
                        .map_err(|e| Error::at(loc, format!("Shape \"curve\": {e}")))?;
                }
                if self.gs.area_light.is_some() {
                    self.warnings.at(loc, "area lights on curves are not supported (pbrt-v3 cannot sample curves); the curve does not emit");
                }
                return Ok(());
            }
        };
        self.attach_area_light(shape, loc);
        Ok(())
    }

    fn mesh_file(&mut self, n: &Named, loc: &SourceLoc) -> Result<Built> {
        let Some(file) = n.params.string("filename")? else {
            return Err(Error::at(loc, format!("Shape \"{}\": missing parameter \"string filename\"", n.name)));
        };
        let floc = n.params.loc_of("filename").unwrap_or(loc).clone();
        let path = self.path(&floc, file);
        let read = if n.name == "plymesh" { ply::read_ply } else { obj::read_obj };
        let data = read(&path, &mut self.warnings).map_err(|e| match e {
            Error::File { path, msg } => Error::at(&floc, format!("{} \"{}\": {msg}", n.name, path.display())),
            other => other,
        })?;
        Ok(Built::Mesh(data))
    }

    /// pbrt-v3's `alpha`/`shadowalpha`: a constant 0 makes the shape invisible (it is skipped); alpha
    /// textures are not evaluated yet (the shape stays opaque, with a warning).
    fn alpha_hides(&mut self, n: &Named) -> Result<bool> {
        let mut hidden = false;
        for name in ["alpha", "shadowalpha"] {
            match n.params.float_or_texture(name)? {
                Some(TexOr::Value(v)) if v == 0.0 && name == "alpha" => hidden = true,
                Some(TexOr::Texture(t)) => {
                    let loc = n.params.loc_of(name).unwrap_or(&n.name_loc);
                    self.warnings.at(
                        loc,
                        format!("alpha-mask texture \"{t}\" is not supported yet; the shape is treated as opaque"),
                    );
                }
                _ => {}
            }
        }
        Ok(hidden)
    }

    /// pbrt-v3 `GetMaterialForShape`: a shape may carry values for its material's parameters (`"rgb Kd"` on
    /// the Shape); then it gets its own copy of the current material with those values.
    fn material_for_shape(&mut self, n: &Named) -> Result<u32> {
        let current = self.gs.material;
        let schema = self.materials[current as usize].kind.schema();
        if !n.params.unused().any(|p| schema_has(schema, &p.name)) {
            return Ok(current);
        }
        let mut m = self.materials[current as usize].clone();
        let textures = Rc::clone(&self.gs.textures);
        Capture { textures: &textures, loc: &n.name_loc, warnings: &mut self.warnings }.read(
            &n.params,
            schema,
            &mut m.props,
        )?;
        self.materials.push(m);
        Ok(self.materials.len() as u32 - 1)
    }

    fn attach_area_light(&mut self, shape: Option<ShapeId>, loc: &SourceLoc) {
        let Some((props, light_loc)) = self.gs.area_light.clone() else { return };
        let Some(shape) = shape else {
            self.warnings.at(
                loc,
                "area lights are not supported inside object instances (as in pbrt-v3); the shape does not emit",
            );
            return;
        };
        let id = self.area_lights.len() as u32;
        self.area_lights.push(AreaLightSpec { props, shape, loc: light_loc });
        match shape {
            ShapeId::Mesh(m) => self.meshes[m as usize].area_light = Some(id),
            ShapeId::Quadric(q) => self.quadric_info[q as usize].area_light = Some(id),
        }
    }
}

/// The affine object → world and world → object maps of a shape placed with `xf` (an error at the Shape when
/// either is not finite or cannot be inverted).
fn placement(xf: &Transform, shape: &str, loc: &SourceLoc) -> Result<[Affine3A; 2]> {
    let at = |e: String| Error::at(loc, format!("Shape \"{shape}\": {e}"));
    Ok([xf.to_affine().map_err(at)?, xf.inverse().to_affine().map_err(at)?])
}

/// Reads sphere/disk/cylinder/cone/paraboloid/hyperboloid parameters with pbrt-v3's defaults and clamping.
fn quadric_params(n: &Named) -> Result<QuadricKind> {
    let p = &n.params;
    let positive = |name: &str, v: f64| -> Result<f64> {
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(Error::at(
                p.loc_of(name).unwrap_or(&n.name_loc),
                format!("{} \"{name}\" must be positive and finite, got {v}", n.name),
            ))
        }
    };
    let finite = |name: &str, v: f64| -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::at(p.loc_of(name).unwrap_or(&n.name_loc), format!("{} \"{name}\" must be finite", n.name)))
        }
    };
    let phi_max = finite("phimax", p.float_or("phimax", 360.0)?)?.clamp(0.0, 360.0).to_radians().min(TAU);
    Ok(match n.name.as_str() {
        "sphere" => {
            let r = positive("radius", p.float_or("radius", 1.0)?)?;
            let z0 = finite("zmin", p.float_or("zmin", -r)?)?;
            let z1 = finite("zmax", p.float_or("zmax", r)?)?;
            QuadricKind::Sphere { radius: r, z_min: z0.min(z1).clamp(-r, r), z_max: z0.max(z1).clamp(-r, r), phi_max }
        }
        "disk" => {
            let radius = positive("radius", p.float_or("radius", 1.0)?)?;
            let inner = finite("innerradius", p.float_or("innerradius", 0.0)?)?.max(0.0);
            QuadricKind::Disk {
                height: finite("height", p.float_or("height", 0.0)?)?,
                radius,
                inner_radius: inner,
                phi_max,
            }
        }
        "cone" => QuadricKind::Cone {
            height: positive("height", p.float_or("height", 1.0)?)?,
            radius: positive("radius", p.float_or("radius", 1.0)?)?,
            phi_max,
        },
        "paraboloid" => {
            let r = positive("radius", p.float_or("radius", 1.0)?)?;
            let z0 = finite("zmin", p.float_or("zmin", 0.0)?)?;
            let z1 = finite("zmax", p.float_or("zmax", 1.0)?)?;
            let (z_min, z_max) = (z0.min(z1), z0.max(z1));
            if z_max == 0.0 {
                // pbrt-v3's curvature is zmax/radius²: 0 makes the paraboloid an unbounded plane.
                let loc = p.loc_of(if z1 >= z0 { "zmax" } else { "zmin" }).unwrap_or(&n.name_loc);
                return Err(Error::at(
                    loc,
                    "paraboloid: the larger of \"zmin\"/\"zmax\" must not be 0 (it sets the curvature)",
                ));
            }
            QuadricKind::Paraboloid { radius: r, z_min, z_max, phi_max }
        }
        "hyperboloid" => hyperboloid_params(n, phi_max)?,
        _ => {
            let r = positive("radius", p.float_or("radius", 1.0)?)?;
            let z0 = finite("zmin", p.float_or("zmin", -1.0)?)?;
            let z1 = finite("zmax", p.float_or("zmax", 1.0)?)?;
            QuadricKind::Cylinder { radius: r, z_min: z0.min(z1), z_max: z0.max(z1), phi_max }
        }
    })
}

/// A hyperboloid from the line p1–p2 swept around the z axis (refused where pbrt-v3 would never finish
/// building it).
fn hyperboloid_params(n: &Named, phi_max: f64) -> Result<QuadricKind> {
    let p = &n.params;
    let point = |name: &str, default: [f64; 3]| -> Result<[f64; 3]> {
        let v = p.point3(name)?.unwrap_or(default);
        if v.iter().all(|c| c.is_finite()) {
            Ok(v)
        } else {
            Err(Error::at(p.loc_of(name).unwrap_or(&n.name_loc), format!("hyperboloid \"{name}\" must be finite")))
        }
    };
    let (p1, p2) = (point("p1", [0.0; 3])?, point("p2", [1.0; 3])?);
    QuadricKind::hyperboloid(p1, p2, phi_max).ok_or_else(|| {
        Error::at(
            p.loc_of("p2").or(p.loc_of("p1")).unwrap_or(&n.name_loc),
            format!(
                "hyperboloid: the line from p1 {p1:?} to p2 {p2:?} sweeps no surface pbrt-v3 can intersect \
                 (p1 = p2, p1.z = p2.z, or a line through the z axis such as the defaults; pbrt-v3 never \
                 finishes building it)"
            ),
        )
    })
}
