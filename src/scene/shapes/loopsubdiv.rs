//! STAGE 2 (scene loading): pbrt-v3's `loopsubdiv` shape — a triangle control mesh refined by Loop
//! subdivision, its vertices pushed to the limit surface, with limit-surface normals — turned into
//! [`MeshData`] in object space, as pbrt-v3's `LoopSubdivide` builds it.
//!
//! Input: the Shape's parameters (`levels`/`nlevels`, `indices`, `P`). Output: [`MeshData`] with positions,
//! per-vertex normals and indices; the scene builder places it like any other mesh.
//!
//! Depends only on `error`, the parameter list of `parse` and [`MeshData`]; nothing here knows about
//! transforms, materials or the BVH. Every size is checked before it is allocated, and no index taken from
//! the file is used unchecked.
//!
//! pbrt-v3 walks the faces around a vertex through neighbour links, which only works on a manifold,
//! consistently oriented control mesh (it hangs or crashes otherwise); such meshes are refused here with an
//! error naming the offending edge or triangle.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use std::collections::HashMap;
use std::f64::consts::PI;

use super::mesh_data::{MeshData, triangle_indices};
use crate::error::{Error, Result, SourceLoc, Warnings};
use crate::parse::ParamList;

/// Most triangles a subdivided mesh may have; larger `levels` are lowered to stay below it (with a warning).
/// Each level multiplies the count by 4, so an absurd level would otherwise exhaust memory; at this cap,
/// loading the mesh and building its BVH peaks near 2 GB.
pub const MAX_SUBDIVIDED_TRIANGLES: u64 = 1 << 22;

/// No neighbour across an edge.
const NONE: u32 = u32::MAX;

const fn next(i: usize) -> usize {
    (i + 1) % 3
}

const fn prev(i: usize) -> usize {
    (i + 2) % 3
}

type P3 = [f64; 3];

fn add(a: P3, b: P3) -> P3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(s: f64, a: P3) -> P3 {
    [s * a[0], s * a[1], s * a[2]]
}

fn cross(a: P3, b: P3) -> P3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// A vertex of the subdivision mesh.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    p: P3,
    /// One face that uses the vertex (pbrt-v3's `startFace`).
    start: u32,
    /// Whether the faces around the vertex do not close into a full ring.
    boundary: bool,
}

/// A triangle of the subdivision mesh: its vertices, and the neighbour across edge `i` (from `v[i]` to
/// `v[next(i)]`), or [`NONE`].
#[derive(Clone, Copy, Debug)]
struct Face {
    v: [u32; 3],
    f: [u32; 3],
}

impl Face {
    /// Which corner of the face `vert` is (the first match; faces never repeat a vertex).
    fn vnum(&self, vert: u32) -> usize {
        self.v.iter().position(|&x| x == vert).unwrap_or(0)
    }
}

/// A manifold, consistently oriented triangle mesh with neighbour links, as pbrt-v3's `SDVertex`/`SDFace`.
struct Mesh {
    verts: Vec<Vertex>,
    faces: Vec<Face>,
}

impl Mesh {
    fn next_face(&self, f: u32, v: u32) -> u32 {
        let face = &self.faces[f as usize];
        face.f[face.vnum(v)]
    }

    fn prev_face(&self, f: u32, v: u32) -> u32 {
        let face = &self.faces[f as usize];
        face.f[prev(face.vnum(v))]
    }

    fn next_vert(&self, f: u32, v: u32) -> u32 {
        let face = &self.faces[f as usize];
        face.v[next(face.vnum(v))]
    }

    fn prev_vert(&self, f: u32, v: u32) -> u32 {
        let face = &self.faces[f as usize];
        face.v[prev(face.vnum(v))]
    }

    /// The one-ring of vertex `v` in pbrt-v3's order, written into `ring` (cleared first). Its length is the
    /// valence: the number of faces around an interior vertex, one more for a boundary vertex.
    ///
    /// Interior: the next vertex of each face, walking forward from the start face. Boundary: walk forward to
    /// the last face, take its next vertex, then the previous vertex of each face walking back.
    /// Every walk is bounded by the face count, so a broken link can never loop forever.
    fn one_ring(&self, v: u32, ring: &mut Vec<P3>) {
        ring.clear();
        let vert = &self.verts[v as usize];
        let limit = self.faces.len();
        if !vert.boundary {
            let mut f = vert.start;
            for _ in 0..limit {
                ring.push(self.verts[self.next_vert(f, v) as usize].p);
                f = self.next_face(f, v);
                if f == vert.start || f == NONE {
                    break;
                }
            }
        } else {
            let mut f = vert.start;
            for _ in 0..limit {
                let f2 = self.next_face(f, v);
                if f2 == NONE {
                    break;
                }
                f = f2;
            }
            ring.push(self.verts[self.next_vert(f, v) as usize].p);
            for _ in 0..limit {
                ring.push(self.verts[self.prev_vert(f, v) as usize].p);
                f = self.prev_face(f, v);
                if f == NONE {
                    break;
                }
            }
        }
    }

    /// pbrt-v3's `weightOneRing`: `(1 - valence·β) p + β Σ ring`.
    fn weight_one_ring(&self, v: u32, beta: impl Fn(usize) -> f64, ring: &mut Vec<P3>) -> P3 {
        self.one_ring(v, ring);
        let b = beta(ring.len());
        let mut p = scale(1.0 - ring.len() as f64 * b, self.verts[v as usize].p);
        for &r in ring.iter() {
            p = add(p, scale(b, r));
        }
        p
    }

    /// pbrt-v3's `weightBoundary`: `(1 - 2β) p + β (first + last of the ring)`.
    fn weight_boundary(&self, v: u32, beta: f64, ring: &mut Vec<P3>) -> P3 {
        self.one_ring(v, ring);
        let p = self.verts[v as usize].p;
        match (ring.first(), ring.last()) {
            (Some(&a), Some(&b)) => add(scale(1.0 - 2.0 * beta, p), add(scale(beta, a), scale(beta, b))),
            _ => p,
        }
    }

    /// One level of Loop subdivision: every face split in four (child `k < 3` at corner `k`, child 3 in the
    /// middle), even vertices moved by the one-ring or boundary rule, one odd vertex per edge.
    fn refine(&self) -> Mesh {
        let mut ring = Vec::new();
        let nv = self.verts.len();
        let mut verts: Vec<Vertex> = Vec::with_capacity(nv + self.faces.len() * 3 / 2 + 1);
        // Even vertices keep their index; the child of vertex i is vertex i of the next level.
        for (i, v) in self.verts.iter().enumerate() {
            let p = if v.boundary {
                self.weight_boundary(i as u32, 1.0 / 8.0, &mut ring)
            } else {
                // A regular vertex (valence 6) uses 1/16, which is also beta(6).
                self.weight_one_ring(i as u32, beta, &mut ring)
            };
            let start_face = &self.faces[v.start as usize];
            let start = 4 * v.start + start_face.vnum(i as u32) as u32;
            verts.push(Vertex { p, start, boundary: v.boundary });
        }
        // Odd vertices, one per edge, created by the first face (in order) that has the edge.
        let mut odd = vec![NONE; 3 * self.faces.len()];
        for (fi, face) in self.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face.v[k], face.v[next(k)]);
                let g = face.f[k];
                if g != NONE && (g as usize) < fi {
                    let other = &self.faces[g as usize];
                    let shared = (0..3).find(|&j| other.f[j] == fi as u32 && (other.v[j], other.v[next(j)]) == (b, a));
                    if let Some(j) = shared {
                        odd[3 * fi + k] = odd[3 * g as usize + j];
                        continue;
                    }
                }
                let (pa, pb) = (self.verts[a as usize].p, self.verts[b as usize].p);
                let p = if g == NONE {
                    scale(0.5, add(pa, pb))
                } else {
                    let c = face.v[3 - k - next(k)];
                    let other = &self.faces[g as usize];
                    let d = other.v.iter().copied().find(|&x| x != a && x != b).unwrap_or(c);
                    let pc = self.verts[c as usize].p;
                    let pd = self.verts[d as usize].p;
                    add(scale(3.0 / 8.0, add(pa, pb)), scale(1.0 / 8.0, add(pc, pd)))
                };
                odd[3 * fi + k] = verts.len() as u32;
                verts.push(Vertex { p, start: 4 * fi as u32 + 3, boundary: g == NONE });
            }
        }
        // The children's neighbour links and vertices.
        let mut faces = vec![Face { v: [0; 3], f: [NONE; 3] }; 4 * self.faces.len()];
        for (fi, face) in self.faces.iter().enumerate() {
            let c = 4 * fi;
            for j in 0..3 {
                faces[c + 3].f[j] = (c + next(j)) as u32;
                faces[c + j].f[next(j)] = (c + 3) as u32;
                let across = |f2: u32| {
                    if f2 == NONE { NONE } else { 4 * f2 + self.faces[f2 as usize].vnum(face.v[j]) as u32 }
                };
                faces[c + j].f[j] = across(face.f[j]);
                faces[c + j].f[prev(j)] = across(face.f[prev(j)]);
            }
            for j in 0..3 {
                let vert = odd[3 * fi + j];
                faces[c + j].v[j] = face.v[j];
                faces[c + j].v[next(j)] = vert;
                faces[c + next(j)].v[j] = vert;
                faces[c + 3].v[j] = vert;
            }
        }
        Mesh { verts, faces }
    }

    /// Positions on the limit surface (pbrt-v3: boundary rule with 1/5, one-ring rule with `loopGamma`).
    fn limit_positions(&self) -> Vec<P3> {
        let mut ring = Vec::new();
        (0..self.verts.len() as u32)
            .map(|v| {
                if self.verts[v as usize].boundary {
                    self.weight_boundary(v, 1.0 / 5.0, &mut ring)
                } else {
                    self.weight_one_ring(v, gamma, &mut ring)
                }
            })
            .collect()
    }

    /// pbrt-v3's limit-surface normals `S × T` from the tangents of each vertex's one-ring (not normalised).
    fn limit_normals(&self) -> Vec<P3> {
        let mut ring = Vec::new();
        (0..self.verts.len() as u32)
            .map(|v| {
                let vert = &self.verts[v as usize];
                self.one_ring(v, &mut ring);
                let n = ring.len();
                let (mut s, mut t) = ([0.0; 3], [0.0; 3]);
                if n == 0 {
                    return s;
                }
                if !vert.boundary {
                    for (j, &r) in ring.iter().enumerate() {
                        let a = 2.0 * PI * j as f64 / n as f64;
                        s = add(s, scale(a.cos(), r));
                        t = add(t, scale(a.sin(), r));
                    }
                } else {
                    let p = vert.p;
                    s = sub(ring[n - 1], ring[0]);
                    t = match n {
                        2 => sub(add(ring[0], ring[1]), scale(2.0, p)),
                        3 => sub(ring[1], p),
                        4 => {
                            let w = add(scale(-1.0, add(ring[0], ring[3])), scale(2.0, add(ring[1], ring[2])));
                            sub(w, scale(2.0, p))
                        }
                        _ => {
                            let theta = PI / (n - 1) as f64;
                            let mut t = scale(theta.sin(), add(ring[0], ring[n - 1]));
                            for (k, &r) in ring.iter().enumerate().take(n - 1).skip(1) {
                                let w = (2.0 * theta.cos() - 2.0) * (k as f64 * theta).sin();
                                t = add(t, scale(w, r));
                            }
                            scale(-1.0, t)
                        }
                    };
                }
                cross(s, t)
            })
            .collect()
    }
}

/// pbrt-v3's `beta`: the one-ring weight of an interior even vertex of the given valence.
fn beta(valence: usize) -> f64 {
    if valence == 3 { 3.0 / 16.0 } else { 3.0 / (8.0 * valence as f64) }
}

/// pbrt-v3's `loopGamma`: the one-ring weight that moves an interior vertex to the limit surface.
fn gamma(valence: usize) -> f64 {
    1.0 / (valence as f64 + 3.0 / (8.0 * beta(valence)))
}

/// Builds the neighbour links of the control mesh. `indices` must be in range (checked by the caller) and
/// every position used. Fails, naming the triangle or edge, on a triangle that repeats a vertex, an edge
/// shared by more than two triangles, or two triangles that traverse their shared edge the same way.
fn build(positions: &[P3], indices: &[u32]) -> std::result::Result<Mesh, String> {
    let nf = indices.len() / 3;
    let mut faces: Vec<Face> = Vec::with_capacity(nf);
    let mut verts: Vec<Vertex> = positions.iter().map(|&p| Vertex { p, start: NONE, boundary: false }).collect();
    // Directed edge (a, b) -> (face, edge number).
    let mut edges: HashMap<(u32, u32), (u32, usize)> = HashMap::with_capacity(3 * nf);
    for (fi, tri) in indices.chunks_exact(3).enumerate() {
        let v = [tri[0], tri[1], tri[2]];
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            return Err(format!(
                "triangle {fi} uses vertex {} more than once ({}, {}, {})",
                repeated(v),
                v[0],
                v[1],
                v[2]
            ));
        }
        for &x in &v {
            verts[x as usize].start = fi as u32;
        }
        faces.push(Face { v, f: [NONE; 3] });
        for k in 0..3 {
            let (a, b) = (v[k], v[next(k)]);
            if let Some(&(g, _)) = edges.get(&(a, b)) {
                let why = if edges.contains_key(&(b, a)) {
                    "is shared by more than two triangles"
                } else {
                    "is traversed in the same direction by both triangles (they are not consistently oriented)"
                };
                return Err(format!("the edge from vertex {a} to vertex {b} of triangles {g} and {fi} {why}"));
            }
            edges.insert((a, b), (fi as u32, k));
        }
    }
    for (&(a, b), &(f, k)) in &edges {
        if let Some(&(g, _)) = edges.get(&(b, a)) {
            faces[f as usize].f[k] = g;
        }
    }
    let mut mesh = Mesh { verts: Vec::new(), faces };
    let limit = mesh.faces.len();
    for (i, vert) in verts.iter_mut().enumerate() {
        let v = i as u32;
        let start = vert.start;
        let mut f = start;
        let mut boundary = true;
        for _ in 0..limit {
            f = mesh.next_face(f, v);
            if f == NONE {
                break;
            }
            if f == start {
                boundary = false;
                break;
            }
        }
        vert.boundary = boundary;
    }
    mesh.verts = verts;
    Ok(mesh)
}

/// The vertex a degenerate triangle repeats.
fn repeated(v: [u32; 3]) -> u32 {
    if v[0] == v[1] || v[0] == v[2] { v[0] } else { v[1] }
}

/// The result of [`subdivide`]: the mesh, and notes for the caller to report as warnings.
#[derive(Debug)]
pub struct Subdivided {
    /// The limit-surface mesh: positions, normals (one per position) and indices; no uvs.
    pub mesh: MeshData,
    /// How many control vertices no triangle uses (they are left out, where pbrt-v3 would crash).
    pub unused_vertices: usize,
}

/// Loop-subdivides the control mesh `levels` times and pushes its vertices to the limit surface, as
/// pbrt-v3's `LoopSubdivide` does; the normals are pbrt-v3's limit-surface normals.
///
/// `indices` must hold whole triangles with every index `< positions.len()`, and `levels` must keep the
/// triangle count within [`MAX_SUBDIVIDED_TRIANGLES`] (see [`max_levels`]). The error names the first
/// problem: an index out of range, a triangle that repeats a vertex, an edge shared by more than two
/// triangles, or two triangles that traverse their shared edge the same way.
pub fn subdivide(positions: &[[f64; 3]], indices: &[u32], levels: u32) -> std::result::Result<Subdivided, String> {
    if !indices.len().is_multiple_of(3) {
        return Err(format!("{} vertex indices is not a multiple of 3", indices.len()));
    }
    if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(format!("vertex index {i} is out of range: there are {} vertices", positions.len()));
    }
    // Keep only the vertices some triangle uses, in their order.
    let mut remap = vec![NONE; positions.len()];
    for &i in indices {
        remap[i as usize] = 0;
    }
    let mut used = Vec::new();
    for (i, r) in remap.iter_mut().enumerate() {
        if *r == 0 {
            *r = used.len() as u32;
            used.push(positions[i]);
        }
    }
    let unused_vertices = positions.len() - used.len();
    let indices: Vec<u32> = indices.iter().map(|&i| remap[i as usize]).collect();
    let mut mesh = build(&used, &indices)?;
    for _ in 0..levels {
        mesh = mesh.refine();
    }
    let limit = mesh.limit_positions();
    for (v, p) in mesh.verts.iter_mut().zip(&limit) {
        v.p = *p;
    }
    let normals = mesh.limit_normals();
    let to_f32 = |p: &P3| p.map(|x| x as f32);
    let data = MeshData {
        positions: limit.iter().map(to_f32).collect(),
        normals: normals.iter().map(to_f32).collect(),
        uvs: Vec::new(),
        indices: mesh.faces.iter().flat_map(|f| f.v).collect(),
    };
    Ok(Subdivided { mesh: data, unused_vertices })
}

/// The most levels that keep `triangles` control triangles within [`MAX_SUBDIVIDED_TRIANGLES`] after
/// subdivision (each level multiplies the count by 4).
pub fn max_levels(triangles: u64) -> u32 {
    let mut levels = 0;
    let mut n = triangles.max(1);
    while n.saturating_mul(4) <= MAX_SUBDIVIDED_TRIANGLES {
        n *= 4;
        levels += 1;
    }
    levels
}

/// Reads the parameters of `Shape "loopsubdiv"` (pbrt-v3 `CreateLoopSubdiv`: `"integer levels"`, else
/// `"integer nlevels"`, default 3; `"integer indices"`; `"point3 P"`) and builds its mesh.
///
/// Negative levels count as 0 (pbrt-v3 then does no refinement); levels that would exceed
/// [`MAX_SUBDIVIDED_TRIANGLES`] are lowered with a warning. Missing or bad indices and non-manifold control
/// meshes are errors at the parameter's location.
pub fn loopsubdiv_params(params: &ParamList, loc: &SourceLoc, warnings: &mut Warnings) -> Result<MeshData> {
    let at = |name: &str| params.loc_of(name).unwrap_or(loc).clone();
    let levels_name = if params.loc_of("levels").is_some() { "levels" } else { "nlevels" };
    let levels = match params.int("levels")? {
        Some(l) => l,
        None => params.int_or("nlevels", 3)?,
    };
    let _ = params.string("scheme")?;
    let Some(ix) = params.ints("indices")? else {
        return Err(Error::at(loc, "loopsubdiv: missing required parameter \"integer indices\""));
    };
    let Some(p) = params.point3s("P")? else {
        return Err(Error::at(loc, "loopsubdiv: missing required parameter \"point3 P\""));
    };
    let indices = triangle_indices(ix, p.len(), &at("indices"), "loopsubdiv: ")?;
    if let Some((i, q)) = p.iter().enumerate().find(|(_, q)| !q.iter().all(|c| c.is_finite())) {
        return Err(Error::at(
            &at("P"),
            format!("loopsubdiv: vertex {i} has a non-finite position ({}, {}, {})", q[0], q[1], q[2]),
        ));
    }
    if indices.is_empty() {
        warnings.at(&at("indices"), "loopsubdiv with no triangles: nothing is drawn");
        return Ok(MeshData::default());
    }
    let cap = max_levels(indices.len() as u64 / 3);
    let levels = if levels < 0 {
        warnings.at(&at(levels_name), format!("loopsubdiv: {levels} levels; no subdivision is done (as pbrt-v3)"));
        0
    } else if levels > cap as i64 {
        warnings.at(
            &at(levels_name),
            format!(
                "loopsubdiv: {levels} levels would make more than {MAX_SUBDIVIDED_TRIANGLES} triangles from {} \
                 control triangles; using {cap} levels",
                indices.len() / 3
            ),
        );
        cap
    } else {
        levels as u32
    };
    let out = subdivide(&p, &indices, levels).map_err(|e| Error::at(&at("indices"), format!("loopsubdiv: {e}")))?;
    if out.unused_vertices > 0 {
        warnings.at(
            &at("P"),
            format!(
                "loopsubdiv: {} of {} vertices are used by no triangle; ignoring them",
                out.unused_vertices,
                p.len()
            ),
        );
    }
    let mut data = out.mesh;
    if let Err(e) = data.validate() {
        return Err(Error::at(&at("P"), format!("loopsubdiv: {e}")));
    }
    if data.drop_unusable_normals() > 0 {
        warnings.at(&at("P"), "loopsubdiv: some limit-surface normals are zero or not finite; using none");
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    type V = [f64; 3];

    fn lin(terms: &[(f64, V)]) -> V {
        terms.iter().fold([0.0; 3], |acc, &(w, p)| add(acc, scale(w, p)))
    }

    /// Asserts that `got` holds the points of `want` in some order (each within 1e-6).
    fn same_points(got: &[[f32; 3]], want: &[V]) {
        assert_eq!(got.len(), want.len(), "vertex count");
        let mut taken = vec![false; got.len()];
        for w in want {
            let i = (0..got.len())
                .find(|&i| !taken[i] && (0..3).all(|c| (got[i][c] as f64 - w[c]).abs() < 1e-6))
                .unwrap_or_else(|| panic!("no vertex at {w:?} in {got:?}"));
            taken[i] = true;
        }
    }

    const A: V = [1.0, 1.0, 1.0];
    const B: V = [1.0, -1.0, -1.0];
    const C: V = [-1.0, 1.0, -1.0];
    const D: V = [-1.0, -1.0, 1.0];
    /// A regular tetrahedron centred on the origin, consistently oriented (outward).
    const TETRA: [u32; 12] = [0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2];

    /// Level 1 of the tetrahedron by hand, before the limit push. Even vertices (valence 3, β = 3/16):
    /// 7/16 p + 3/16 Σ others. Odd vertex on edge ab: 3/8 (a + b) + 1/8 (c + d).
    fn tetra_level1() -> (Vec<V>, Vec<V>) {
        let pts = [A, B, C, D];
        let even: Vec<V> = (0..4)
            .map(|i| {
                let others: Vec<(f64, V)> = (0..4).filter(|&j| j != i).map(|j| (3.0 / 16.0, pts[j])).collect();
                add(scale(7.0 / 16.0, pts[i]), lin(&others))
            })
            .collect();
        let mut odd = Vec::new();
        for i in 0..4 {
            for j in i + 1..4 {
                let rest: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
                odd.push(lin(&[
                    (3.0 / 8.0, pts[i]),
                    (3.0 / 8.0, pts[j]),
                    (1.0 / 8.0, pts[rest[0]]),
                    (1.0 / 8.0, pts[rest[1]]),
                ]));
            }
        }
        (even, odd)
    }

    #[test]
    fn tetrahedron_level_one_then_limit() {
        let pts = [A, B, C, D];
        let (even, odd) = tetra_level1();
        // Sanity of the hand values: the centroid is the origin, so even = p/4 and odd = (a + b)/4.
        assert!((even[0][0] - 0.25).abs() < 1e-12 && (odd[0][0] - 0.5).abs() < 1e-12);
        // Limit push. Even vertices keep valence 3: γ = 1/(3 + 3/(8·3/16)) = 1/5, ring = the three odd
        // vertices on its edges. Odd vertices have valence 6: γ = 1/12, ring = the two even ends and the
        // four odd vertices of the two faces beside the edge.
        let odd_of = |i: usize, j: usize| {
            let (i, j) = (i.min(j), i.max(j));
            let k = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)].iter().position(|&e| e == (i, j)).unwrap();
            odd[k]
        };
        let mut want = Vec::new();
        for (i, &e) in even.iter().enumerate() {
            let ring: Vec<(f64, V)> = (0..4).filter(|&j| j != i).map(|j| (1.0 / 5.0, odd_of(i, j))).collect();
            want.push(add(scale(1.0 - 3.0 / 5.0, e), lin(&ring)));
        }
        for i in 0..4 {
            for j in i + 1..4 {
                let mut ring = vec![(1.0 / 12.0, even[i]), (1.0 / 12.0, even[j])];
                for k in (0..4).filter(|&k| k != i && k != j) {
                    ring.push((1.0 / 12.0, odd_of(i, k)));
                    ring.push((1.0 / 12.0, odd_of(j, k)));
                }
                want.push(add(scale(1.0 - 6.0 / 12.0, odd_of(i, j)), lin(&ring)));
            }
        }
        let out = subdivide(&pts, &TETRA, 1).unwrap();
        assert_eq!(out.unused_vertices, 0);
        let m = out.mesh;
        assert_eq!(m.triangle_count(), 16);
        assert_eq!(m.validate(), Ok(()));
        same_points(&m.positions, &want);
        // The limit point of an original vertex does not depend on the level: a/5 from level 0 too.
        let m0 = subdivide(&pts, &TETRA, 0).unwrap().mesh;
        same_points(&m0.positions, &[scale(0.2, A), scale(0.2, B), scale(0.2, C), scale(0.2, D)]);
        same_points(&m.positions[..4], &[scale(0.2, A), scale(0.2, B), scale(0.2, C), scale(0.2, D)]);
    }

    #[test]
    fn tetrahedron_limit_normals_are_radial_and_consistent() {
        let pts = [A, B, C, D];
        for levels in 0..3 {
            let m = subdivide(&pts, &TETRA, levels).unwrap().mesh;
            assert_eq!(m.normals.len(), m.positions.len());
            assert_eq!(m.triangle_count(), 4 * 4usize.pow(levels));
            // Every vertex of a symmetric mesh's level-0 normal is along its position; at any level, all
            // normals point the same way (in or out) relative to the centre.
            let signs: Vec<bool> = m.positions.iter().zip(&m.normals).map(|(p, n)| dot32(p, n) > 0.0).collect();
            assert!(signs.iter().all(|&s| s == signs[0]), "level {levels}: {signs:?}");
            if levels == 0 {
                for (p, n) in m.positions.iter().zip(&m.normals) {
                    let c = cross(p.map(f64::from), n.map(f64::from));
                    assert!(c.iter().all(|x| x.abs() < 1e-5), "{p:?} {n:?}");
                }
            }
        }
    }

    fn dot32(a: &[f32; 3], b: &[f32; 3]) -> f32 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    #[test]
    fn open_quad_uses_the_boundary_rules() {
        // Two triangles sharing the diagonal 0-2; the four outer edges are boundary edges.
        let p: [V; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 1.0]];
        let idx = [0, 1, 2, 0, 2, 3];
        // Level 1 by hand. Boundary even vertex: 3/4 p + 1/8 (its two boundary neighbours). Boundary odd
        // vertex: the midpoint. Interior odd vertex (edge 02): 3/8 (p0 + p2) + 1/8 (p1 + p3).
        let nb = |i: usize| [(i + 3) % 4, (i + 1) % 4];
        let even: Vec<V> =
            (0..4).map(|i| lin(&[(3.0 / 4.0, p[i]), (1.0 / 8.0, p[nb(i)[0]]), (1.0 / 8.0, p[nb(i)[1]])])).collect();
        let mid = |i: usize, j: usize| lin(&[(0.5, p[i]), (0.5, p[j])]);
        let m01 = mid(0, 1);
        let m12 = mid(1, 2);
        let m23 = mid(2, 3);
        let m30 = mid(3, 0);
        let m02 = lin(&[(3.0 / 8.0, p[0]), (3.0 / 8.0, p[2]), (1.0 / 8.0, p[1]), (1.0 / 8.0, p[3])]);
        // Limit. Boundary vertices: 3/5 p + 1/5 (their two boundary neighbours). The diagonal's odd vertex
        // is interior with valence 6 (γ = 1/12): its ring is p0', p2' and the four boundary odd vertices.
        let bl = |v: V, a: V, b: V| lin(&[(3.0 / 5.0, v), (1.0 / 5.0, a), (1.0 / 5.0, b)]);
        let want = vec![
            bl(even[0], m01, m30),
            bl(even[1], m01, m12),
            bl(even[2], m12, m23),
            bl(even[3], m23, m30),
            bl(m01, even[0], even[1]),
            bl(m12, even[1], even[2]),
            bl(m23, even[2], even[3]),
            bl(m30, even[3], even[0]),
            lin(&[
                (0.5, m02),
                (1.0 / 12.0, even[0]),
                (1.0 / 12.0, even[2]),
                (1.0 / 12.0, m01),
                (1.0 / 12.0, m12),
                (1.0 / 12.0, m23),
                (1.0 / 12.0, m30),
            ]),
        ];
        let m = subdivide(&p, &idx, 1).unwrap().mesh;
        assert_eq!(m.triangle_count(), 8);
        same_points(&m.positions, &want);
    }

    #[test]
    fn a_flat_grid_stays_flat_with_normals_along_z() {
        // A 3×3-vertex grid in z = 0: interior vertex 4 has valence 6 (regular), corners valence 2 or 3.
        let p: Vec<V> = (0..9).map(|i| [(i % 3) as f64, (i / 3) as f64, 0.0]).collect();
        let mut idx = Vec::new();
        for y in 0..2 {
            for x in 0..2 {
                let v = |dx: u32, dy: u32| (y + dy) * 3 + x + dx;
                idx.extend([v(0, 0), v(1, 0), v(1, 1), v(0, 0), v(1, 1), v(0, 1)]);
            }
        }
        for levels in 0..3 {
            let m = subdivide(&p, &idx, levels).unwrap().mesh;
            for (q, n) in m.positions.iter().zip(&m.normals) {
                assert_eq!(q[2], 0.0);
                assert!(n[0].abs() < 1e-5 && n[1].abs() < 1e-5 && n[2].abs() > 1e-3, "{q:?} {n:?}");
                assert!(n[2] * m.normals[0][2] > 0.0, "normals agree in sign");
            }
        }
    }

    #[test]
    fn bad_topology_is_an_error_not_a_panic() {
        let p: Vec<V> = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        let e = subdivide(&p, &[0, 1, 2, 0, 1, 3], 1).unwrap_err();
        assert!(e.contains("not consistently oriented"), "{e}");
        let e = subdivide(&p, &[0, 1, 2, 1, 0, 3, 0, 1, 4], 1).unwrap_err();
        assert!(e.contains("more than two triangles"), "{e}");
        let e = subdivide(&p, &[0, 1, 1], 1).unwrap_err();
        assert!(e.contains("triangle 0 uses vertex 1 more than once"), "{e}");
        let e = subdivide(&p, &[0, 1, 7], 1).unwrap_err();
        assert!(e.contains("out of range"), "{e}");
        let e = subdivide(&p, &[0, 1], 1).unwrap_err();
        assert!(e.contains("multiple of 3"), "{e}");
        // Unused vertices are left out.
        let out = subdivide(&p, &[0, 1, 2], 1).unwrap();
        assert_eq!(out.unused_vertices, 2);
        assert_eq!(out.mesh.triangle_count(), 4);
        // A bow-tie (two fans meeting at vertex 0) subdivides without hanging.
        let p2: Vec<V> = vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [-1.0, -1.0, 0.0]];
        assert_eq!(subdivide(&p2, &[0, 1, 2, 0, 3, 4], 2).unwrap().mesh.triangle_count(), 32);
    }

    #[test]
    fn level_cap() {
        assert_eq!(max_levels(1), 11);
        assert_eq!(max_levels(4), 10);
        assert_eq!(max_levels(5), 9);
        assert_eq!(max_levels(MAX_SUBDIVIDED_TRIANGLES), 0);
        assert_eq!(max_levels(u64::MAX), 0);
    }
}
