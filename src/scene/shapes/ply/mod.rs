//! STAGE 2 (scene loading): reads PLY files (`Shape "plymesh"`) into [`MeshData`].
//!
//! Input: a path. Output: the file's triangles in object space, plus warnings for what was dropped. The
//! behaviour follows pbrt-v3's `plymesh` (which reads through rply), with clearer errors:
//!
//! - formats `ascii`, `binary_little_endian` and `binary_big_endian` (version 1.0), every PLY scalar type;
//!   elements and properties other than the ones below are skipped;
//! - vertex: `x y z` required; `nx ny nz` used when all three are there; uvs from the first complete pair
//!   among `u v`, `s t`, `texture_u texture_v`, `texture_s texture_t`;
//! - face: the list `vertex_indices` (or `vertex_index`); triangles kept, quads `a b c d` split into
//!   `a b c` and `d a c` as pbrt-v3 does, other faces skipped with one warning per file; `face_indices`
//!   and other face properties are ignored;
//! - errors (never panics) for a missing or non-PLY file, an unsupported format, missing `x y z`, a vertex
//!   index out of range, a truncated body (saying how many records were expected), a malformed ascii number
//!   (with its line) and a non-finite position;
//! - normals: if any is NaN, infinite or zero, the whole normal array is dropped with a warning (see
//!   [`MeshData::drop_unusable_normals`]).
//!
//! The whole file is read into memory and binary data is decoded straight from the byte slice. Header counts
//! never size an allocation on their own: capacities are capped by what the remaining bytes can hold, so a
//! header that claims 2^40 vertices fails at the end of the data instead of allocating.
//!
//! Depends only on `error` (and its sibling [`super::mesh_data`]).
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use std::collections::BTreeMap;
use std::path::Path;

mod body;
mod header;

use super::mesh_data::MeshData;
use body::{Ascii, Binary, Body, BodyErr};
use header::{Element, Format, Header, Kind, Scalar, parse_header};

/// Faces skipped because they are neither triangles nor quads: vertex count → how many.
type Ignored = BTreeMap<u64, u64>;

use crate::error::{Error, Result, Warnings};

/// Reads the PLY file at `path` into a [`MeshData`] (see the module doc for what is read and what is not).
///
/// Problems that lose data without making the mesh wrong (faces that are not triangles or quads, unusable
/// normals, no triangles at all) are recorded in `warnings`, each naming the file. Everything else is an
/// [`Error::File`] naming the file and, where it applies, the element number or ascii line.
pub fn read_ply(path: &Path, warnings: &mut Warnings) -> Result<MeshData> {
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read PLY file: {e}")))?;
    let fail = |msg: String| Error::file(path, msg);
    let header = parse_header(&bytes).map_err(fail)?;
    let plan = plan(&header).map_err(fail)?;
    let body = bytes.get(header.body_start..).unwrap_or_default();
    let (mut mesh, ignored) = match header.format {
        Format::Ascii => read_body(&header, &plan, &mut Ascii { data: body, pos: 0, line: header.body_line }),
        Format::BinaryLe => read_body(&header, &plan, &mut Binary::<false> { data: body, pos: 0 }),
        Format::BinaryBe => read_body(&header, &plan, &mut Binary::<true> { data: body, pos: 0 }),
    }
    .map_err(fail)?;

    report_losses(path, &ignored, &mut mesh, warnings);
    mesh.validate().map_err(fail)?;
    Ok(mesh)
}

/// Warns about what was dropped: faces other than triangles and quads (one warning for all of them),
/// unusable normals (dropped here), and an empty result.
fn report_losses(path: &Path, ignored: &Ignored, mesh: &mut MeshData, warnings: &mut Warnings) {
    let name = path.display();
    if !ignored.is_empty() {
        let plural = |n: u64| if n == 1 { "" } else { "s" };
        let counts: Vec<String> =
            ignored.iter().map(|(k, n)| format!("{n} face{} with {k} vertices", plural(*n))).collect();
        let counts = counts.join(", ");
        warnings.general(format!("{name}: plymesh: ignored {counts} (only triangles and quads are supported)"));
    }
    let bad = mesh.drop_unusable_normals();
    if bad > 0 {
        let n = mesh.positions.len();
        warnings.general(format!(
            "{name}: plymesh: {bad} of {n} vertex normals are NaN, infinite or zero; \
             ignoring all normals of this mesh"
        ));
    }
    if mesh.triangle_count() == 0 {
        warnings.general(format!("{name}: plymesh: the file has no triangles, so the shape is empty"));
    }
}

/// Slots of the per-vertex scratch array that vertex properties are decoded into.
const X: usize = 0;
const NX: usize = 3;
const U: usize = 6;

/// What to extract from the body, worked out from the header before any data is read.
#[derive(Debug)]
struct Plan {
    /// For each vertex property, the scratch slot it goes to (`None`: skipped).
    slots: Vec<Option<usize>>,
    normals: bool,
    uvs: bool,
    vertex_count: u64,
    /// Position of the face's vertex index list and its types, when there is a face element.
    face_list: Option<(usize, Scalar, Scalar)>,
}

/// Checks that the header describes a mesh and decides where each used property goes.
fn plan(header: &Header) -> Result<Plan, String> {
    let vertex = header.elements.iter().find(|e| e.name == "vertex").ok_or("no \"vertex\" element in the header")?;
    if vertex.count > u64::from(u32::MAX) {
        return Err(format!("the header declares {} vertices; at most {} are supported", vertex.count, u32::MAX));
    }
    let mut slots = vec![None; vertex.props.len()];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let p = vertex.scalar(name).ok_or_else(|| format!("the vertex element has no \"{name}\" property"))?;
        slots[p] = Some(X + k);
    }
    let normals = assign(vertex, &mut slots, &["nx", "ny", "nz"], NX);
    let pairs = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"], ["texture_s", "texture_t"]];
    let uvs = pairs.iter().any(|pair| assign(vertex, &mut slots, pair, U));
    let face_list = match header.elements.iter().find(|e| e.name == "face") {
        None => None,
        Some(face) => {
            let found = ["vertex_indices", "vertex_index"].iter().find_map(|name| {
                face.props.iter().enumerate().find_map(|(i, p)| match p.kind {
                    Kind::List { len, item } if p.name == *name => Some((i, len, item)),
                    _ => None,
                })
            });
            Some(found.ok_or("the face element has no \"vertex_indices\" list property")?)
        }
    };
    Ok(Plan { slots, normals, uvs, vertex_count: vertex.count, face_list })
}

/// Sends the scalar properties `names` to consecutive slots from `first` when all of them exist.
fn assign(vertex: &Element, slots: &mut [Option<usize>], names: &[&str], first: usize) -> bool {
    let found: Option<Vec<usize>> = names.iter().map(|n| vertex.scalar(n)).collect();
    let Some(found) = found else { return false };
    for (k, p) in found.into_iter().enumerate() {
        slots[p] = Some(first + k);
    }
    true
}

/// Reads every element in header order, keeping vertices and faces.
fn read_body<B: Body>(header: &Header, plan: &Plan, body: &mut B) -> Result<(MeshData, Ignored), String> {
    let mut mesh = MeshData::default();
    let mut ignored = Ignored::new();
    for el in &header.elements {
        match (el.name.as_str(), plan.face_list) {
            ("vertex", _) => read_vertices(el, plan, body, &mut mesh)?,
            ("face", Some(list)) => read_faces(el, list, plan.vertex_count, body, &mut mesh, &mut ignored)?,
            _ => skip_element(el, body)?,
        }
    }
    Ok((mesh, ignored))
}

/// How many of `el`'s records to reserve room for.
fn capacity<B: Body>(el: &Element, body: &B) -> usize {
    usize::try_from(el.count).unwrap_or(usize::MAX).min(body.max_records(el))
}

fn read_vertices<B: Body>(el: &Element, plan: &Plan, body: &mut B, mesh: &mut MeshData) -> Result<(), String> {
    let cap = capacity(el, body);
    mesh.positions.reserve(cap);
    mesh.normals.reserve(if plan.normals { cap } else { 0 });
    mesh.uvs.reserve(if plan.uvs { cap } else { 0 });
    let mut v = [0.0f32; 8];
    for i in 0..el.count {
        for (prop, slot) in el.props.iter().zip(&plan.slots) {
            let read = match (prop.kind, slot) {
                (Kind::Scalar(ty), Some(s)) => body.value(ty).map(|x| v[*s] = x as f32),
                (kind, _) => skip_property(kind, body),
            };
            read.map_err(|e| e.describe(i, el, prop))?;
        }
        mesh.positions.push([v[X], v[X + 1], v[X + 2]]);
        if plan.normals {
            mesh.normals.push([v[NX], v[NX + 1], v[NX + 2]]);
        }
        if plan.uvs {
            mesh.uvs.push([v[U], v[U + 1]]);
        }
    }
    Ok(())
}

/// Reads the faces; `list` is the vertex index list's position and types from the [`Plan`].
fn read_faces<B: Body>(
    el: &Element,
    list: (usize, Scalar, Scalar),
    vertex_count: u64,
    body: &mut B,
    mesh: &mut MeshData,
    ignored: &mut Ignored,
) -> Result<(), String> {
    let (list_at, len_ty, item_ty) = list;
    mesh.indices.reserve(3 * capacity(el, body));
    for i in 0..el.count {
        for (p, prop) in el.props.iter().enumerate() {
            let describe = |e: BodyErr| e.describe(i, el, prop);
            if p != list_at {
                skip_property(prop.kind, body).map_err(describe)?;
                continue;
            }
            let n = list_len(body, len_ty).map_err(describe)?;
            if n != 3 && n != 4 {
                *ignored.entry(n).or_default() += 1;
                body.skip(item_ty, n).map_err(describe)?;
                continue;
            }
            let mut f = [0u32; 4];
            for slot in f.iter_mut().take(n as usize) {
                let raw = body.value(item_ty).map_err(describe)?;
                *slot = vertex_ref(raw, i, vertex_count)?;
            }
            mesh.indices.extend_from_slice(&f[..3]);
            if n == 4 {
                // pbrt-v3's split of a quad a b c d: a b c, then d a c.
                mesh.indices.extend_from_slice(&[f[3], f[0], f[2]]);
            }
        }
    }
    Ok(())
}

/// Checks a vertex index read from face `face` and narrows it.
fn vertex_ref(raw: f64, face: u64, vertex_count: u64) -> Result<u32, String> {
    if raw.fract() != 0.0 {
        return Err(format!("face {face} has vertex index {raw}, which is not a whole number"));
    }
    if raw < 0.0 || raw >= vertex_count as f64 {
        return Err(format!("face {face} references vertex {raw}, but there are {vertex_count} vertices"));
    }
    Ok(raw as u32)
}

/// Reads a list length.
fn list_len<B: Body>(body: &mut B, ty: Scalar) -> Result<u64, BodyErr> {
    let n = body.value(ty)?;
    if n < 0.0 {
        return Err(BodyErr::Bad(format!("negative list length {n}")));
    }
    Ok(n as u64)
}

fn skip_property<B: Body>(kind: Kind, body: &mut B) -> Result<(), BodyErr> {
    match kind {
        Kind::Scalar(ty) => body.skip(ty, 1),
        Kind::List { len, item } => {
            let n = list_len(body, len)?;
            body.skip(item, n)
        }
    }
}

fn skip_element<B: Body>(el: &Element, body: &mut B) -> Result<(), String> {
    if el.props.is_empty() {
        return Ok(());
    }
    for i in 0..el.count {
        for prop in &el.props {
            skip_property(prop.kind, body).map_err(|e| e.describe(i, el, prop))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    use crate::scene::shapes::test_files::{self as tf, scene_dir};

    /// Reads `bytes` as a PLY file.
    fn read(bytes: &[u8]) -> (Result<MeshData>, Warnings) {
        tf::read(read_ply, "ply", bytes)
    }

    fn ok(bytes: &[u8]) -> MeshData {
        tf::ok(read_ply, "ply", bytes)
    }

    /// The error message without the path.
    fn err(bytes: &[u8]) -> String {
        tf::err(read_ply, "ply", bytes)
    }

    fn warning_texts(w: &Warnings) -> Vec<String> {
        w.iter().map(|w| w.msg.clone()).collect()
    }

    /// A binary value of a given PLY type.
    #[derive(Clone, Copy)]
    enum V {
        C(i8),
        B(u8),
        S(i16),
        US(u16),
        I(i32),
        U(u32),
        F(f32),
        D(f64),
    }

    fn binary(values: &[V], big: bool) -> Vec<u8> {
        let mut out = Vec::new();
        for v in values {
            macro_rules! put {
                ($x:expr) => {
                    out.extend_from_slice(&if big { $x.to_be_bytes() } else { $x.to_le_bytes() })
                };
            }
            match *v {
                V::C(x) => put!(x),
                V::B(x) => put!(x),
                V::S(x) => put!(x),
                V::US(x) => put!(x),
                V::I(x) => put!(x),
                V::U(x) => put!(x),
                V::F(x) => put!(x),
                V::D(x) => put!(x),
            }
        }
        out
    }

    fn file(header: &str, body: &[u8]) -> Vec<u8> {
        let mut out = header.as_bytes().to_vec();
        out.extend_from_slice(body);
        out
    }

    /// A unit square as two triangles, positions only, binary, with `faces` faces declared.
    fn square(format: &str, vertices: u64, faces: u64) -> String {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
             property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
        )
    }

    fn square_body(big: bool) -> Vec<u8> {
        use V::*;
        let mut v = vec![F(0.), F(0.), F(0.), F(1.), F(0.), F(0.), F(1.), F(1.), F(0.), F(0.), F(1.), F(0.)];
        v.extend([B(3), I(0), I(1), I(2), B(3), I(0), I(2), I(3)]);
        binary(&v, big)
    }

    fn square_mesh() -> MeshData {
        MeshData {
            positions: vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            indices: vec![0, 1, 2, 0, 2, 3],
            ..Default::default()
        }
    }

    #[test]
    fn ascii_with_normals_and_uvs() {
        let text = "ply\nformat ascii 1.0\ncomment made by hand\nobj_info nothing\nelement vertex 3\n\
                    property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n\
                    property float nz\nproperty float u\nproperty float v\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n\
                    0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 2.5 -1e-1 0 0 2 0 1\n3 0 1 2\n";
        let mesh = ok(text.as_bytes());
        let expected = MeshData {
            positions: vec![[0., 0., 0.], [1., 0., 0.], [0., 2.5, -0.1]],
            normals: vec![[0., 0., 1.], [0., 0., 1.], [0., 0., 2.]],
            uvs: vec![[0., 0.], [1., 0.], [0., 1.]],
            indices: vec![0, 1, 2],
        };
        assert_eq!(mesh, expected);
    }

    #[test]
    fn binary_little_and_big_endian_read_the_same() {
        assert_eq!(ok(&file(&square("binary_little_endian", 4, 2), &square_body(false))), square_mesh());
        assert_eq!(ok(&file(&square("binary_big_endian", 4, 2), &square_body(true))), square_mesh());
        let ascii = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
        assert_eq!(ok(&file(&square("ascii", 4, 2), ascii.as_bytes())), square_mesh());
    }

    #[test]
    fn uvs_come_from_the_first_complete_pair() {
        use V::*;
        // `u` without `v` does not count; `s t` is the first complete pair.
        let header = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                      property float z\nproperty float u\nproperty float s\nproperty float t\n\
                      property float texture_u\nproperty float texture_v\nelement face 1\n\
                      property list uchar uint vertex_indices\nend_header\n";
        let mut v = Vec::new();
        for k in 0..3 {
            let k = k as f32;
            v.extend([F(k), F(0.), F(0.), F(9.), F(k / 2.), F(1.), F(7.), F(7.)]);
        }
        v.extend([B(3), U(0), U(1), U(2)]);
        let mesh = ok(&file(header, &binary(&v, true)));
        assert_eq!(mesh.uvs, vec![[0., 1.], [0.5, 1.], [1., 1.]]);
        assert!(mesh.normals.is_empty());
    }

    #[test]
    fn a_quad_is_split_like_pbrt() {
        let text = format!("{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", square("ascii", 4, 1));
        assert_eq!(ok(text.as_bytes()).indices, vec![0, 1, 2, 3, 0, 2]);
    }

    #[test]
    fn other_polygons_are_skipped_with_one_warning() {
        let text = format!("{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n5 0 1 2 3 0\n3 0 1 2\n5 3 2 1 0 3\n", square("ascii", 4, 3));
        let (mesh, warnings) = read(text.as_bytes());
        assert_eq!(mesh.unwrap().indices, vec![0, 1, 2]);
        let texts = warning_texts(&warnings);
        assert_eq!(texts.len(), 1, "{texts:?}");
        assert!(
            texts[0].ends_with("plymesh: ignored 2 faces with 5 vertices (only triangles and quads are supported)"),
            "{texts:?}"
        );
        // Several sizes still make one warning.
        let text = format!("{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 1\n3 0 1 2\n6 0 1 2 3 0 1\n", square("ascii", 4, 3));
        let (_, warnings) = read(text.as_bytes());
        let texts = warning_texts(&warnings);
        assert_eq!(texts.len(), 1);
        assert!(texts[0].contains("ignored 1 face with 2 vertices, 1 face with 6 vertices"), "{texts:?}");
    }

    #[test]
    fn a_truncated_binary_file_says_what_was_expected() {
        let body = square_body(false);
        let header = square("binary_little_endian", 4, 2);
        let cut = |n: usize| err(&file(&header, &body[..body.len() - n]));
        assert_eq!(cut(1), "file ends after 1 of 2 faces (the file is truncated, or its header is wrong)");
        assert!(cut(13).starts_with("file ends after 1 of 2 faces"));
        assert!(cut(14).starts_with("file ends after 0 of 2 faces"));
        assert!(cut(30).starts_with("file ends after 3 of 4 vertices"));
        assert!(err(header.as_bytes()).starts_with("file ends after 0 of 4 vertices"));
        // Truncated right after the header line: no body bytes at all, not even the newline.
        assert!(err(&header.as_bytes()[..header.len() - 1]).contains("no end_header line"));
    }

    #[test]
    fn an_out_of_range_index_is_an_error() {
        let text = format!("{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 4\n", square("ascii", 4, 2));
        assert_eq!(err(text.as_bytes()), "face 1 references vertex 4, but there are 4 vertices");
        let text = format!("{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 -1 2\n", square("ascii", 4, 1));
        assert_eq!(err(text.as_bytes()), "face 0 references vertex -1, but there are 4 vertices");
        let header = square("binary_little_endian", 4, 2).replace("uchar int", "uchar float");
        let mut body = square_body(false);
        body.truncate(48);
        body.extend(binary(&[V::B(3), V::F(0.), V::F(1.5), V::F(2.)], false));
        assert_eq!(err(&file(&header, &body)), "face 0 has vertex index 1.5, which is not a whole number");
    }

    #[test]
    fn huge_header_counts_fail_fast_without_allocating() {
        let body = square_body(false);
        let huge = 1u64 << 40;
        let msg = err(&file(&square("binary_little_endian", huge, 2), &body));
        assert_eq!(msg, format!("the header declares {huge} vertices; at most 4294967295 are supported"));
        let msg = err(&file(&square("binary_little_endian", 4_000_000_000, 2), &body));
        assert!(msg.starts_with("file ends after 6 of 4000000000 vertices"), "{msg}");
        let msg = err(&file(&square("binary_little_endian", 4, huge), &body));
        assert!(msg.starts_with(&format!("file ends after 2 of {huge} faces")), "{msg}");
        let msg = err(&file(&square("ascii", 4, huge), b"0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n"));
        assert!(msg.starts_with(&format!("file ends after 1 of {huge} faces")), "{msg}");
        // An unknown element is skipped record by record, so it also stops at the end of the data.
        let header = square("binary_little_endian", 4, 2)
            .replace("end_header", "element junk 1099511627776\nproperty list int double j\nend_header");
        let msg = err(&file(&header, &body));
        assert!(msg.starts_with("file ends after 0 of 1099511627776 \"junk\" elements"), "{msg}");
        // A list length that runs past the end of the data.
        let mut body = square_body(false);
        body.truncate(48);
        body.extend(binary(&[V::B(255), V::I(0)], false));
        assert!(err(&file(&square("binary_little_endian", 4, 1), &body)).starts_with("file ends after 0 of 1 faces"));
    }

    #[test]
    fn files_that_are_not_ply_are_refused() {
        assert_eq!(err(b"OFF\n3 1 0\n"), "not a PLY file (the first line is not \"ply\")");
        assert_eq!(err(b""), "not a PLY file (the first line is not \"ply\")");
        assert_eq!(err(b"plyx\n"), "not a PLY file (the first line is not \"ply\")");
        let mut warnings = Warnings::default();
        let missing = std::env::temp_dir().join("cachert-ply-test-does-not-exist.ply");
        let e = read_ply(&missing, &mut warnings).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: cannot read PLY file: ", missing.display())), "{e}");
    }

    #[test]
    fn header_mistakes_name_the_line() {
        let good = square("binary_little_endian", 4, 2);
        let bad = |from: &str, to: &str| err(&file(&good.replace(from, to), &square_body(false)));
        assert_eq!(
            bad("binary_little_endian", "binary_middle_endian"),
            "header line 2: unsupported format \"binary_middle_endian\" \
             (expected ascii, binary_little_endian or binary_big_endian)"
        );
        assert_eq!(bad(" 1.0", " 2.0"), "header line 2: unsupported PLY version \"2.0\" (only 1.0 is known)");
        assert_eq!(bad("format binary_little_endian 1.0\n", ""), "the header has no format line");
        assert_eq!(bad("property float z", "property float w"), "the vertex element has no \"z\" property");
        assert_eq!(bad("property float z", "property list uchar float z"), "the vertex element has no \"z\" property");
        assert_eq!(bad("float y", "float4 y"), "header line 5: unknown property type \"float4\"");
        assert_eq!(bad("list uchar", "list float"), "header line 8: list length type \"float\" is not an integer type");
        assert_eq!(bad("vertex_indices", "indices"), "the face element has no \"vertex_indices\" list property");
        assert_eq!(
            bad("vertex 4", "vertex four"),
            "header line 3: element count \"four\" is not a non-negative integer"
        );
        assert_eq!(bad("element vertex", "elephant vertex"), "header line 3: unknown header keyword \"elephant\"");
        assert_eq!(bad("element vertex 4\n", ""), "header line 3: a property before any element");
        assert_eq!(bad("element face 2", "element vertex 2"), "header line 7: a second \"vertex\" element");
        assert_eq!(bad("element vertex 4", "element points 4"), "no \"vertex\" element in the header");
        assert_eq!(bad("end_header", "end"), "header line 9: unknown header keyword \"end\"");
        assert_eq!(bad("end_header\n", "end_header"), "the header has no end_header line");
    }

    #[test]
    fn malformed_ascii_numbers_give_the_line() {
        let text = format!("{}0 0 0\n1 0 0\n1 1.0abc 0\n0 1 0\n3 0 1 2\n", square("ascii", 4, 1));
        assert_eq!(err(text.as_bytes()), "line 12: expected a number, found \"1.0abc\" (property \"y\" of vertex 2)");
        let text = format!("{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n\n3 0 1.0 2\n", square("ascii", 4, 1));
        assert_eq!(
            err(text.as_bytes()),
            "line 15: expected an integer, found \"1.0\" (property \"vertex_indices\" of face 0)"
        );
    }

    #[test]
    fn non_finite_positions_are_errors() {
        let text = format!("{}0 0 0\n1 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", square("ascii", 4, 1));
        assert_eq!(err(text.as_bytes()), "vertex 2 has a non-finite position (1, NaN, 0)");
        let mut body = square_body(true);
        body[20..24].copy_from_slice(&f32::INFINITY.to_be_bytes());
        let msg = err(&file(&square("binary_big_endian", 4, 2), &body));
        assert_eq!(msg, "vertex 1 has a non-finite position (1, 0, inf)");
    }

    #[test]
    fn bad_normals_are_dropped_with_a_warning() {
        let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                      property float nx\nproperty float ny\nproperty float nz\nelement face 1\n\
                      property list uchar int vertex_indices\nend_header\n";
        let text = format!("{header}0 0 0 0 0 1\n1 0 0 nan 0 1\n0 1 0 0 0 0\n3 0 1 2\n");
        let (mesh, warnings) = read(text.as_bytes());
        let mesh = mesh.unwrap();
        assert!(mesh.normals.is_empty());
        assert_eq!(mesh.positions.len(), 3);
        let texts = warning_texts(&warnings);
        assert_eq!(texts.len(), 1);
        assert!(
            texts[0].ends_with("2 of 3 vertex normals are NaN, infinite or zero; ignoring all normals of this mesh")
        );
    }

    #[test]
    fn every_type_and_unknown_data_are_read_or_skipped() {
        use V::*;
        let header = "ply\nformat binary_little_endian 1.0\nelement material 2\nproperty list uint16 float32 colour\n\
                      property int8 id\nelement vertex 3\nproperty char x\nproperty ushort y\nproperty double z\n\
                      property uchar red\nproperty list short int junk\nproperty int nx\nproperty uint ny\n\
                      property short nz\nelement face 2\nproperty uint8 flags\n\
                      property list int uint16 vertex_indices\nproperty list uchar int face_indices\n\
                      element edge 1\nproperty int a\nproperty int b\nend_header\n";
        let mut v = vec![US(2), F(0.5), F(0.25), C(1), US(0), C(2)];
        v.extend([C(-1), US(0), D(0.5), B(255), S(2), I(7), I(8), I(0), U(0), S(-1)]);
        v.extend([C(1), US(65535), D(0.0), B(0), S(0), I(0), U(1), S(0)]);
        v.extend([C(0), US(3), D(-2.0), B(9), S(1), I(-9), I(0), U(0), S(5)]);
        v.extend([B(1), I(3), US(0), US(1), US(2), B(1), I(0)]);
        v.extend([B(0), I(3), US(2), US(1), US(0), B(0)]);
        v.extend([I(0), I(1)]);
        for big in [false, true] {
            let header = if big { header.replace("little", "big") } else { header.to_string() };
            let mesh = ok(&file(&header, &binary(&v, big)));
            assert_eq!(mesh.positions, vec![[-1., 0., 0.5], [1., 65535., 0.], [0., 3., -2.]]);
            assert_eq!(mesh.normals, vec![[0., 0., -1.], [0., 1., 0.], [0., 0., 5.]]);
            assert_eq!(mesh.indices, vec![0, 1, 2, 2, 1, 0]);
        }
    }

    #[test]
    fn faces_may_come_first_and_use_vertex_index() {
        let text = "ply\r\nformat ascii 1.0\r\nelement face 1\r\nproperty list uint uint vertex_index\r\n\
                    element vertex 3\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\nend_header\r\n\
                    3 2 1 0\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n";
        let mesh = ok(text.as_bytes());
        assert_eq!(mesh.indices, vec![2, 1, 0]);
        assert_eq!(mesh.positions.len(), 3);
    }

    #[test]
    fn a_file_without_faces_is_empty_with_a_warning() {
        let header = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                      end_header\n1 2 3\n";
        let (mesh, warnings) = read(header.as_bytes());
        let mesh = mesh.unwrap();
        assert_eq!(mesh.triangle_count(), 0);
        assert_eq!(mesh.positions, vec![[1., 2., 3.]]);
        assert!(warning_texts(&warnings)[0].ends_with("plymesh: the file has no triangles, so the shape is empty"));
    }

    /// The `.ply` files in `dir`, sorted.
    fn plys_in(dir: &Path) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "ply"))
            .collect();
        files.sort();
        files
    }

    /// Reads every PLY in `dir` without warnings; returns (files, triangles).
    fn read_all(dir: &Path) -> (usize, usize) {
        let files = plys_in(dir);
        let mut triangles = 0;
        for f in &files {
            let mut warnings = Warnings::default();
            let mesh = read_ply(f, &mut warnings).unwrap();
            assert!(warnings.is_empty(), "{warnings:?}");
            triangles += mesh.triangle_count();
        }
        (files.len(), triangles)
    }

    #[test]
    fn reads_every_bathroom_ply() {
        let Some(dir) = scene_dir("bitterli-bathroom/models") else {
            return;
        };
        assert_eq!(read_all(&dir), (855, 592_186));
    }

    #[test]
    fn reads_the_other_real_scenes() {
        if let Some(dir) = scene_dir("bitterli-staircase2/models") {
            assert_eq!(read_all(&dir), (19, 30_911));
        }
        if let Some(dir) = scene_dir("pbrtv3scenes-veach-mis/geometry") {
            assert_eq!(read_all(&dir), (5, 12));
        }
        if let Some(dir) = scene_dir("mcguire-sibenik-geometry") {
            let mesh = read_ply(&dir.join("sibenik-ply.ply"), &mut Warnings::default()).unwrap();
            assert_eq!((mesh.positions.len(), mesh.triangle_count()), (40_981, 75_284));
            assert!(mesh.normals.is_empty() && mesh.uvs.is_empty());
        }
    }

    #[test]
    fn reads_the_buddha() {
        let Some(dir) = scene_dir("pbrtv3scenes-buddha-fractal/geometry") else {
            return;
        };
        let mut warnings = Warnings::default();
        let mesh = read_ply(&dir.join("buddha.ply"), &mut warnings).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!((mesh.positions.len(), mesh.triangle_count()), (89_670, 29_890));
        assert_eq!((mesh.normals.len(), mesh.uvs.len()), (89_670, 89_670));
    }
}
