//! STAGE 2 (scene): everything a ray can hit — world meshes, object definitions, analytic shapes, curves and the
//! acceleration structure over them — and the surface interaction at a hit (position with its error
//! bound, geometric and shading normals, uv, material), computed as pbrt-v3 does.

use glam::Vec3A;

use crate::scene::accel::{Accel, Hit, OccluderCache, OccluderHint, PrimOrigin, PrimRef};
use crate::scene::mesh::TriangleMesh;
use crate::scene::ray::{Ray, gamma, offset_ray_origin};
use crate::scene::shapes::curve::CurveHit;
use crate::scene::shapes::quadric::QuadricHit;
use crate::scene::transform::{transform_normal, transform_point_with_error};

/// A shape that can carry an area light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeId {
    /// A world-level triangle mesh.
    Mesh(u32),
    /// An analytic shape.
    Quadric(u32),
}

/// Material and emission of an analytic shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeInfo {
    /// Material id.
    pub material: u32,
    /// Area light id.
    pub area_light: Option<u32>,
}

/// An object definition (`ObjectBegin … ObjectEnd`): its meshes in definition space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectDef {
    /// The object's name.
    pub name: String,
    /// Its triangle meshes.
    pub meshes: Vec<TriangleMesh>,
}

/// The scene's geometry and its acceleration structure.
#[derive(Debug, Default)]
pub struct Geometry {
    /// World-level meshes.
    pub meshes: Vec<TriangleMesh>,
    /// Object definitions (instanced geometry).
    pub objects: Vec<ObjectDef>,
    /// Material/emission of each analytic shape (same index as `accel.quadrics`).
    pub quadric_info: Vec<ShapeInfo>,
    /// Material of each curve piece (same index as `accel.curves`; curves never emit).
    pub curve_info: Vec<ShapeInfo>,
    /// The BVHs.
    pub accel: Accel,
    /// Per world mesh, per triangle: what [`triangle_interaction`] computes from the vertices and uvs alone
    /// (see [`TriangleFrame`]); filled by [`Geometry::new`].
    frames: Vec<Vec<TriangleFrame>>,
}

/// The parts of a triangle's surface interaction that do not depend on where it is hit: the unit normal of
/// its vertex winding (before any flip), ∂p/∂u, and the shading normal of a flat face. Computed once per
/// triangle instead of at every hit — the normalisations and the division by the uv determinant sat on the
/// chain a path waits on for its next ray. The first two are exactly what a hit computed before. Stored as
/// plain arrays: 36 bytes per world triangle (21 MB for the bathroom's 592 188).
#[derive(Clone, Copy, Debug, PartialEq)]
struct TriangleFrame {
    ng: [f32; 3],
    dpdu: [f32; 3],
    /// The shading normal when the three vertex normals are equal (a flat face of a mesh with normals), else
    /// zero: it is then the same at every point, and interpolating and normalising it at each hit would only
    /// add rounding.
    ns_flat: [f32; 3],
}

impl TriangleFrame {
    fn of(mesh: &TriangleMesh, tri: usize) -> TriangleFrame {
        let [p0, p1, p2] = mesh.triangle(tri).map(Vec3A::from);
        let idx = &mesh.indices[3 * tri..3 * tri + 3];
        let [uv0, uv1, uv2] = triangle_uvs(mesh, idx);
        let (dp02, dp12) = (p0 - p2, p1 - p2);
        let mut ng = dp02.cross(dp12).normalize_or_zero();
        if ng == Vec3A::ZERO {
            ng = Vec3A::Z;
        }
        let duv02 = [uv0[0] - uv2[0], uv0[1] - uv2[1]];
        let duv12 = [uv1[0] - uv2[0], uv1[1] - uv2[1]];
        let det = duv02[0] * duv12[1] - duv02[1] * duv12[0];
        let mut dpdu = if det.abs() < 1e-8 { Vec3A::ZERO } else { (dp02 * duv12[1] - dp12 * duv02[1]) / det };
        if dpdu.cross(ng).length_squared() == 0.0 {
            dpdu = crate::sampling::Frame::from_normal(ng).s;
        }
        let ns_flat = match mesh.normals.is_empty() {
            true => Vec3A::ZERO,
            false => {
                let [n0, n1, n2] = [0, 1, 2].map(|k| Vec3A::from(mesh.normals[idx[k] as usize]));
                if n0 == n1 && n1 == n2 { n0.normalize_or_zero() } else { Vec3A::ZERO }
            }
        };
        TriangleFrame { ng: ng.to_array(), dpdu: dpdu.to_array(), ns_flat: ns_flat.to_array() }
    }
}

/// The uvs of a triangle's vertices `idx` (pbrt-v3's defaults (0,0), (1,0), (1,1) for a mesh without uvs).
#[inline]
fn triangle_uvs(mesh: &TriangleMesh, idx: &[u32]) -> [[f32; 2]; 3] {
    if mesh.uvs.is_empty() {
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]
    } else {
        [mesh.uvs[idx[0] as usize], mesh.uvs[idx[1] as usize], mesh.uvs[idx[2] as usize]]
    }
}

/// What is known about the surface at a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceInteraction {
    /// World position.
    pub p: Vec3A,
    /// Absolute floating-point error bound of `p`.
    pub p_error: Vec3A,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Unit geometric normal (pbrt-v3's orientation rules: toward the shading normal when there is one).
    pub ng: Vec3A,
    /// Unit shading normal, on the same side as `ng`.
    pub ns: Vec3A,
    /// ∂p/∂u.
    pub dpdu: Vec3A,
    /// Surface (u, v).
    pub uv: [f32; 2],
    /// Material id.
    pub material: u32,
    /// Area light id, when the surface emits.
    pub area_light: Option<u32>,
    /// The primitive hit (for skipping it in shadow queries from this point).
    pub origin: PrimOrigin,
}

impl SurfaceInteraction {
    /// A ray leaving the surface in direction `d`, offset past the error bound (pbrt-v3 `SpawnRay`).
    #[inline]
    pub fn spawn_ray(&self, d: Vec3A) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_error, self.ng, d), d)
    }
}

impl Geometry {
    /// The geometry of a scene: its meshes, object definitions, analytic shapes and curves (their material and
    /// emission) and the BVHs over them.
    pub fn new(
        meshes: Vec<TriangleMesh>,
        objects: Vec<ObjectDef>,
        quadric_info: Vec<ShapeInfo>,
        curve_info: Vec<ShapeInfo>,
        accel: Accel,
    ) -> Geometry {
        let frames =
            meshes.iter().map(|m| (0..m.triangle_count()).map(|t| TriangleFrame::of(m, t)).collect()).collect();
        Geometry { meshes, objects, quadric_info, curve_info, accel, frames }
    }

    /// The nearest surface along `ray`.
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = self.accel.intersect(ray)?;
        Some(self.interaction(&hit, ray))
    }

    /// [`Geometry::intersect`] for a ray leaving the surface `from` (which is then not tested: a ray leaving a
    /// planar triangle cannot hit it, see `PrimOrigin`); the hit is the same.
    #[inline]
    pub fn intersect_from(&self, ray: &Ray, from: Option<PrimOrigin>) -> Option<SurfaceInteraction> {
        let hit = self.accel.intersect_from(ray, from)?;
        Some(self.interaction(&hit, ray))
    }

    /// Whether anything blocks `ray` before its t_max.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
    }

    /// [`Geometry::occluded`] for a ray leaving `from` (not tested), trying the previous blocker in `hint`
    /// first (see [`OccluderHint`]).
    #[inline]
    pub fn occluded_hinted(&self, ray: &Ray, from: Option<PrimOrigin>, hint: &mut OccluderHint) -> bool {
        self.accel.occluded_hinted(ray, from, hint)
    }

    /// [`Geometry::occluded_hinted`] that also tries the blockers `cache` remembers for the ray's direction
    /// (see [`OccluderCache`]; the answer never depends on what `hint` or `cache` hold).
    #[inline]
    pub fn occluded_cached(
        &self,
        ray: &Ray,
        from: Option<PrimOrigin>,
        hint: &mut OccluderHint,
        cache: &mut OccluderCache,
    ) -> bool {
        self.accel.occluded_cached(ray, from, hint, cache)
    }

    /// [`Geometry::occluded`] for a ray leaving the surface `from` (which is then not tested).
    #[inline]
    pub fn occluded_from(&self, ray: &Ray, from: PrimOrigin) -> bool {
        self.accel.occluded_from(ray, from)
    }

    /// Total triangles stored (object definitions counted once).
    pub fn stored_triangles(&self) -> usize {
        let world: usize = self.meshes.iter().map(|m| m.triangle_count()).sum();
        let objects: usize = self.objects.iter().flat_map(|o| &o.meshes).map(|m| m.triangle_count()).sum();
        world + objects
    }

    fn interaction(&self, hit: &Hit, ray: &Ray) -> SurfaceInteraction {
        let meshes = match hit.instance {
            Some(i) => &self.objects[self.accel.instance(i).object as usize].meshes,
            None => &self.meshes,
        };
        let mut si = match hit.prim {
            PrimRef::Triangle { mesh, tri } => {
                let (m, t) = (&meshes[mesh as usize], tri as usize);
                let frame = match hit.instance {
                    None => self.frames.get(mesh as usize).and_then(|f| f.get(t)).copied(),
                    Some(_) => None,
                };
                triangle_interaction(m, t, hit, frame.unwrap_or_else(|| TriangleFrame::of(m, t)))
            }
            PrimRef::Quadric(q) => {
                let s = self.accel.quadrics[q as usize].surface(&QuadricHit {
                    t: hit.t,
                    p: hit.quadric_p,
                    p_error: hit.quadric_err,
                });
                analytic_interaction(hit, [s.p, s.p_error, s.n, s.dpdu], s.uv, self.quadric_info[q as usize])
            }
            PrimRef::Curve(c) => {
                let seg = &self.accel.curve_segments[c as usize];
                // The curve's normal depends on the ray, seen in the space the curve was placed in.
                let local = match hit.instance {
                    Some(i) => self.accel.instance(i).local_ray(ray, ray.t_max),
                    None => *ray,
                };
                let [u, v] = hit.b;
                let s = self.accel.curves[seg.curve as usize].surface(&local, &CurveHit { t: hit.t, u, v });
                let info = ShapeInfo { area_light: None, ..self.curve_info[seg.curve as usize] };
                analytic_interaction(hit, [s.p, s.p_error, s.n, s.dpdu], s.uv, info)
            }
            PrimRef::Instance(_) => unreachable!("instances are resolved by the accelerator"),
        };
        if let Some(i) = hit.instance {
            let m = &self.accel.instance(i).world_from_object;
            let (p, err) = transform_point_with_error(m, si.p, si.p_error);
            si.p = p;
            si.p_error = err;
            si.ng = transform_normal(m, si.ng);
            si.ns = transform_normal(m, si.ns);
            si.dpdu = m.transform_vector3a(si.dpdu);
            si.area_light = None;
        }
        si.t = hit.t;
        si.origin = PrimOrigin { prim: hit.prim, instance: hit.instance };
        debug_assert!(ray.d.is_finite());
        si
    }
}

/// The interaction at a hit on an analytic shape or a curve, from its position, error bound, normal (also
/// the shading normal) and ∂p/∂u (`[p, p_error, n, dpdu]`), its uv, and its material and emission.
fn analytic_interaction(
    hit: &Hit,
    [p, p_error, n, dpdu]: [Vec3A; 4],
    uv: [f32; 2],
    info: ShapeInfo,
) -> SurfaceInteraction {
    SurfaceInteraction {
        p,
        p_error,
        t: hit.t,
        ng: n,
        ns: n,
        dpdu,
        uv,
        material: info.material,
        area_light: info.area_light,
        origin: PrimOrigin { prim: hit.prim, instance: hit.instance },
    }
}

/// pbrt-v3 `Triangle::Intersect`'s surface data from barycentrics.
fn triangle_interaction(mesh: &TriangleMesh, tri: usize, hit: &Hit, frame: TriangleFrame) -> SurfaceInteraction {
    let [b1, b2] = hit.b;
    let b0 = 1.0 - b1 - b2;
    let [p0, p1, p2] = mesh.triangle(tri).map(Vec3A::from);
    let p = p0 * b0 + p1 * b1 + p2 * b2;
    let p_abs_sum = (p0 * b0).abs() + (p1 * b1).abs() + (p2 * b2).abs();
    let idx = &mesh.indices[3 * tri..3 * tri + 3];
    let [uv0, uv1, uv2] = triangle_uvs(mesh, idx);
    let (mut ng, dpdu, ns_flat) = (Vec3A::from(frame.ng), Vec3A::from(frame.dpdu), Vec3A::from(frame.ns_flat));
    let uv = [b0 * uv0[0] + b1 * uv1[0] + b2 * uv2[0], b0 * uv0[1] + b1 * uv1[1] + b2 * uv2[1]];
    let mut ns = ng;
    if mesh.normals.is_empty() {
        if mesh.flip_normals {
            ng = -ng;
        }
        ns = ng;
    } else {
        if ns_flat != Vec3A::ZERO {
            ns = ns_flat;
        } else {
            let n = |k: usize| Vec3A::from(mesh.normals[idx[k] as usize]);
            let interp = (n(0) * b0 + n(1) * b1 + n(2) * b2).normalize_or_zero();
            if interp != Vec3A::ZERO {
                ns = interp;
            }
        }
        if ng.dot(ns) < 0.0 {
            ng = -ng;
        }
    }
    SurfaceInteraction {
        p,
        p_error: p_abs_sum * gamma(7),
        t: hit.t,
        ng,
        ns,
        dpdu,
        uv,
        material: mesh.material,
        area_light: mesh.area_light,
        origin: PrimOrigin { prim: hit.prim, instance: hit.instance },
    }
}
