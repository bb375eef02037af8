//! Inputs that once crashed, hung or blew up a reader (found by the fuzz harness in `examples/fuzz`, by
//! hand-built inputs while writing it, or named in the fuzzing issue), each asserting the clean error it
//! gives now. Memory is measured with the harness's counting allocator: no input here may grow the heap by
//! more than [`HEAP_BOUND`].

#[path = "../examples/fuzz/alloc.rs"]
#[allow(dead_code)]
mod alloc;
mod common;

use std::path::Path;
use std::sync::Mutex;

use cachert::Warnings;
use cachert::image::{self, Image};
use cachert::parse::integrator::IntegratorParams;
use cachert::render::ambient_occlusion::AmbientOcclusion;
use cachert::scene::shapes::{obj, ply};
use cachert::scene::{LoadOptions, LoadedScene, load, load_str};
use common::TempDir;

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

/// Heap growth allowed while one of these inputs is read (other tests run at the same time, so the bound
/// is loose; the failures it guards against allocate gigabytes).
const HEAP_BOUND: usize = 256 << 20;

/// Serialises the heap measurements (tests run on several threads).
static MEASURE: Mutex<()> = Mutex::new(());

/// Runs `f`, asserting the heap grew by less than [`HEAP_BOUND`] meanwhile.
fn bounded<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let _guard = MEASURE.lock().unwrap_or_else(|e| e.into_inner());
    let base = alloc::live();
    alloc::reset_peak();
    let r = f();
    let grew = alloc::peak().saturating_sub(base);
    assert!(grew < HEAP_BOUND, "{what}: the heap grew by {grew} bytes");
    r
}

const WORLD_HEADER: &str = "Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\nWorldBegin\n";

/// Loads `body` inside WorldBegin … WorldEnd as the file `scene.pbrt` (line 3 is the body's first line).
fn load_world(body: &str) -> cachert::Result<LoadedScene> {
    let text = format!("{WORLD_HEADER}{body}\nWorldEnd\n");
    bounded(body, || load_str(&text, Path::new("scene.pbrt"), LoadOptions::default()))
}

fn world_error(body: &str) -> String {
    match load_world(body) {
        Ok(_) => panic!("loaded, but it should not:\n{body}"),
        Err(e) => e.to_string(),
    }
}

// ---- found by the fuzzer ----

/// Fuzz finding (scene target, seed 1, first seconds): the hackmad `subsurface.pbrt` scene with one radius
/// replaced by 99999999999999999999999. The sphere's bounds are finite in f32, but obvhs's BVH build
/// multiplies surface areas in f32, they overflow near 1e19, and its CWBVH conversion indexed out of
/// bounds (panic in obvhs `bvh2_to_cwbvh.rs`). Shapes beyond ±1e12 were made an error at the Shape (now
/// ±1e9, see below).
#[test]
fn a_sphere_of_radius_1e23_is_an_error_not_a_bvh_panic() {
    let body = "Shape \"sphere\" \"float radius\" 1\nTranslate 3 0 0\nShape \"sphere\" \"float radius\" 1\n\
                Translate 3 0 0\nShape \"sphere\" \"float radius\" 99999999999999999999999\n\
                Shape \"sphere\" \"float radius\" 2";
    assert_eq!(
        world_error(body),
        "scene.pbrt:7:1: Shape \"sphere\": the geometry reaches 1e23 from the origin; \
         coordinates beyond ±1e9 are not supported"
    );
    // The same through a huge transform, for a disk and a cylinder.
    let e = world_error("Shape \"sphere\"\nScale 1e20 1e20 1e20\nShape \"disk\"");
    assert_eq!(
        e,
        "scene.pbrt:5:1: Shape \"disk\": the geometry reaches 1e20 from the origin; \
         coordinates beyond ±1e9 are not supported"
    );
    let e = world_error("Shape \"sphere\"\nTranslate 0 0 1e30\nShape \"cylinder\"");
    assert!(e.starts_with("scene.pbrt:5:1: Shape \"cylinder\": the geometry reaches 1e30"), "{e}");
    // Infinity after the transform.
    let e = world_error("Shape \"sphere\"\nScale 1e30 1e30 1e30\nShape \"sphere\" \"float radius\" 1e30");
    assert!(e.starts_with("scene.pbrt:5:1: Shape \"sphere\": the geometry reaches infinity"), "{e}");
}

/// Fuzz findings (scene target, overflow checks and debug assertions on, seed 300): the veach-mis scene with
/// a sphere radius replaced by 4294967295, and the Cornell box with one vertex's y replaced by -2147483649.
/// Both loaded in release builds, but obvhs's debug-only CWBVH validation failed: a node origin outside its
/// parent, and a quantized box that did not contain its triangle (a ray could miss it). Both thresholds lie
/// between 1.5e9 and 2^32, so geometry beyond ±1e9 is now an error; up to 1e8 next to unit-sized shapes loads.
#[test]
fn coordinates_near_2_to_the_31_are_refused_and_1e8_loads() {
    let small = "Shape \"sphere\" \"float radius\" 0.5\nTranslate 1 0 0\n\
                 Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0 1 0 0 0 1 0]\n";
    let e = world_error(&format!("{small}Shape \"sphere\" \"float radius\" 4294967295"));
    assert!(e.starts_with("scene.pbrt:6:1: Shape \"sphere\": the geometry reaches 4.2949673e9"), "{e}");
    let e = world_error(&format!(
        "{small}Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 1.2 0 1 -2147483649 0 0 1.2 1]"
    ));
    assert!(e.starts_with("scene.pbrt:6:1: Shape \"trianglemesh\": vertex 1 lies beyond ±1e9"), "{e}");
    let loaded = load_world(&format!(
        "{small}Shape \"sphere\" \"float radius\" 1e8\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 1.2 0 1 -1e8 0 0 1.2 1]"
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.stats.shapes, 4);
}

/// The same limit (±1e9) for triangle meshes and for object instances (whose object is fine but whose instance
/// transform takes it out of range).
#[test]
fn meshes_and_instances_beyond_1e9_are_errors() {
    let tri = "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0 1 0 0 0 1 0]";
    let e = world_error(&format!(
        "{tri}\nShape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0 1e20 0 0 0 1 0]"
    ));
    assert_eq!(
        e,
        "scene.pbrt:4:1: Shape \"trianglemesh\": vertex 1 lies beyond ±1e9 after the transform \
         (too far out for the BVH)"
    );
    let e = world_error(&format!("ObjectBegin \"o\"\n{tri}\nObjectEnd\n{tri}\nScale 1e20 1 1\nObjectInstance \"o\""));
    assert_eq!(
        e,
        "scene.pbrt:8:1: ObjectInstance \"o\": the geometry reaches 1e20 from the origin; \
         coordinates beyond ±1e9 are not supported"
    );
    // Objects made of analytic shapes too.
    let e = world_error("ObjectBegin \"s\"\nShape \"sphere\"\nObjectEnd\nTranslate 2e9 0 0\nObjectInstance \"s\"");
    assert!(e.starts_with("scene.pbrt:7:1: ObjectInstance \"s\": the geometry reaches 2e9"), "{e}");
    // Up to the limit everything loads.
    let ok = load_world(&format!(
        "{tri}\nShape \"sphere\" \"float radius\" 1e8\nObjectBegin \"o\"\n{tri}\nObjectEnd\n\
         Scale 1e8 1e8 1e8\nObjectInstance \"o\""
    ));
    let loaded = ok.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.stats.instances, 1);
}

// ---- known cases from the issue ----

/// A PLY header that declares 2^40 vertices or faces: refused (vertices: more than 32-bit indices allow) or
/// failing where the data runs out, never sized from the header, in all three formats.
#[test]
fn ply_headers_declaring_2_to_the_40_records_fail_without_allocating() {
    let dir = TempDir::new("fuzz-ply-huge");
    let huge = 1u64 << 40;
    let header = |format: &str, nv: u64, nf: u64| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let binary = |big: bool| {
        let mut out = Vec::new();
        for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            out.extend_from_slice(&if big { v.to_be_bytes() } else { v.to_le_bytes() });
        }
        out.push(3);
        for i in [0i32, 1, 2] {
            out.extend_from_slice(&if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        out
    };
    let (binary_body, big_body) = (binary(false), binary(true));
    let ascii_body = b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n".to_vec();
    for (format, body) in
        [("binary_little_endian", &binary_body), ("binary_big_endian", &big_body), ("ascii", &ascii_body)]
    {
        for (nv, nf, want) in [
            (huge, 1, format!("the header declares {huge} vertices; at most 4294967295 are supported")),
            (3, huge, format!("of {huge} faces")),
            (u32::MAX as u64, 1, "of 4294967295 vertices".to_string()),
        ] {
            let mut bytes = header(format, nv, nf).into_bytes();
            bytes.extend_from_slice(body);
            let path = dir.write("huge.ply", &bytes);
            let r = bounded(format, || ply::read_ply(&path, &mut Warnings::default()));
            let e = r.err().unwrap_or_else(|| panic!("{format} {nv} {nf}: read")).to_string();
            assert!(e.contains(&want), "{format} {nv}/{nf}: {e}");
        }
    }
    // An element nobody reads, declared 2^40 times with no properties: skipped at once.
    let header = header("binary_little_endian", 3, 1);
    let mut bytes = header.replace("end_header", &format!("element junk {huge}\nend_header")).into_bytes();
    bytes.extend_from_slice(&binary_body);
    let path = dir.write("junk.ply", &bytes);
    let mesh = bounded("junk", || ply::read_ply(&path, &mut Warnings::default())).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.triangle_count(), 1);
}

/// A file that includes itself, a cycle through two files, and a chain deeper than the limit.
#[test]
fn include_recursion_is_bounded_with_a_clear_error() {
    let dir = TempDir::new("fuzz-include");
    let me = dir.write("self.pbrt", "WorldBegin\nInclude \"self.pbrt\"\nWorldEnd\n");
    let e = bounded("self", || load(&me, LoadOptions::default())).err().map(|e| e.to_string());
    let d = dir.0.display();
    assert_eq!(e, Some(format!("{d}/self.pbrt:2:1: Include cycle: {d}/self.pbrt -> {d}/self.pbrt")));
    dir.write("a.pbrt", "Include \"b.pbrt\"\n");
    dir.write("b.pbrt", "\nInclude \"a.pbrt\"\n");
    let top = dir.write("top.pbrt", "WorldBegin\nInclude \"a.pbrt\"\nWorldEnd\n");
    let e = bounded("cycle", || load(&top, LoadOptions::default())).err().map(|e| e.to_string());
    assert_eq!(e, Some(format!("{d}/b.pbrt:2:1: Include cycle: {d}/a.pbrt -> {d}/b.pbrt -> {d}/a.pbrt")));
    for k in 0..150 {
        dir.write(&format!("chain{k}.pbrt"), format!("Include \"chain{}.pbrt\"\n", k + 1));
    }
    let top = dir.write("deep.pbrt", "WorldBegin\nInclude \"chain0.pbrt\"\nWorldEnd\n");
    let e = bounded("chain", || load(&top, LoadOptions::default())).err().map(|e| e.to_string());
    assert_eq!(e, Some(format!("{d}/chain98.pbrt:1:1: Include nested more than 100 files deep")));
}

/// Files that include the next one twice, 30 levels deep: no cycle and no deep chain, but 2^30 copies of the
/// last file's directives. Refused once the included text passes 64 times the distinct files' size.
#[test]
fn includes_that_double_at_every_level_are_refused_before_memory_runs_out() {
    let dir = TempDir::new("fuzz-include-fanout");
    for k in 0..30 {
        dir.write(&format!("l{k}.pbrt"), format!("Include \"l{n}.pbrt\"\nInclude \"l{n}.pbrt\"\n", n = k + 1));
    }
    dir.write("l30.pbrt", "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0 1 0 0 0 1 0]\n");
    let top = dir.write("top.pbrt", "WorldBegin\nInclude \"l0.pbrt\"\nWorldEnd\n");
    let e = bounded("fan-out", || load(&top, LoadOptions::default())).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains(": Include \"l"), "{e}");
    assert!(e.contains("the included files add up to"), "{e}");
}

/// An object that instances itself, or any object, while it is being defined.
#[test]
fn object_instance_recursion_is_an_error() {
    let e = world_error("ObjectBegin \"a\"\nShape \"sphere\"\nObjectInstance \"a\"\nObjectEnd");
    assert_eq!(e, "scene.pbrt:5:1: ObjectInstance inside the definition of \"a\": pbrt-v3 does not nest instances");
    let e = world_error(
        "ObjectBegin \"b\"\nShape \"sphere\"\nObjectEnd\nObjectBegin \"a\"\nObjectInstance \"b\"\nObjectEnd",
    );
    assert_eq!(e, "scene.pbrt:7:1: ObjectInstance inside the definition of \"a\": pbrt-v3 does not nest instances");
    let e = world_error("ObjectInstance \"never\"");
    assert!(e.starts_with("scene.pbrt:3:1: ObjectInstance: no object named \"never\""), "{e}");
}

/// Enormous numeric parameters are refused before anything is sized from them.
#[test]
fn enormous_numeric_parameters_are_refused() {
    let load_text = |text: &str| bounded(text, || load_str(text, Path::new("big.pbrt"), LoadOptions::default()));
    let film = |x: &str, y: &str| {
        format!("Film \"image\" \"integer xresolution\" [{x}] \"integer yresolution\" [{y}]\nWorldBegin\nWorldEnd\n")
    };
    let e = load_text(&film("1000000000", "1000000000")).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.starts_with("big.pbrt:1:6: film resolution 1000000000x1000000000 would need"), "{e}");
    let e = load_text(&film("1e9", "4")).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.starts_with("big.pbrt:1:"), "{e}");
    let e = load_text(&film("99999999999", "4")).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.starts_with("big.pbrt:1:"), "{e}");
    let e = load_text("Sampler \"random\" \"integer pixelsamples\" [2147483647]\nWorldBegin\nWorldEnd\n")
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("must be between 1 and 16777216"), "{e}");
    for n in ["2147483647", "1099511627776", "0", "-1"] {
        let text = format!("Integrator \"ambientocclusion\" \"integer nsamples\" [{n}]\nWorldBegin\nWorldEnd\n");
        let loaded = load_text(&text);
        let e = match loaded {
            Err(e) => e.to_string(),
            Ok(l) => {
                let named = l.integrator.expect("the integrator is kept");
                let params = IntegratorParams::new("ambientocclusion", &named.params, &[]);
                match AmbientOcclusion::from_params(&params, &l.scene.sampler, false) {
                    Ok(_) => panic!("nsamples {n} accepted"),
                    Err(e) => e.to_string(),
                }
            }
        };
        assert!(e.contains("nsamples"), "{n}: {e}");
    }
}

/// OBJ faces with absurd relative indices: tobj's index arithmetic overflows; a clean error either way.
#[test]
fn obj_faces_with_absurd_indices_are_errors_or_dropped() {
    let dir = TempDir::new("fuzz-obj");
    for face in ["f -2147483648 -1 -2", "f 2147483647 1 2", "f 4294967296 1 2", "f 0 0 0"] {
        let path = dir.write("bad.obj", format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n"));
        let r = bounded(face, || obj::read_obj(&path, &mut Warnings::default()));
        if let Ok(mesh) = r {
            assert!(mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()), "{face}: bad index kept");
        }
    }
}

/// An uncompressed scanline EXR of `w`×`h` float B, G, R pixels whose offset table points every line at
/// one zero-filled block for line 0 (`all_blocks`: a real block per line instead).
fn scanline_exr(w: i32, h: i32, all_blocks: bool) -> Vec<u8> {
    fn attr(out: &mut Vec<u8>, name: &str, ty: &str, data: &[u8]) {
        for s in [name, ty] {
            out.extend_from_slice(s.as_bytes());
            out.push(0);
        }
        out.extend_from_slice(&(data.len() as i32).to_le_bytes());
        out.extend_from_slice(data);
    }
    let ints = |v: &[i32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut chlist = Vec::new();
    for c in [b'B', b'G', b'R'] {
        chlist.extend_from_slice(&[c, 0]);
        chlist.extend_from_slice(&ints(&[2, 0, 1, 1])); // float, pLinear 0 + reserved, sampling 1 1
    }
    chlist.push(0);
    let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    attr(&mut out, "channels", "chlist", &chlist);
    attr(&mut out, "compression", "compression", &[0]);
    attr(&mut out, "dataWindow", "box2i", &ints(&[0, 0, w - 1, h - 1]));
    attr(&mut out, "displayWindow", "box2i", &ints(&[0, 0, w - 1, h - 1]));
    attr(&mut out, "lineOrder", "lineOrder", &[0]);
    attr(&mut out, "pixelAspectRatio", "float", &1f32.to_le_bytes());
    attr(&mut out, "screenWindowCenter", "v2f", &[0; 8]);
    attr(&mut out, "screenWindowWidth", "float", &1f32.to_le_bytes());
    out.push(0);
    let line = w as usize * 12;
    let start = (out.len() + 8 * h as usize) as u64;
    for y in 0..h as u64 {
        let block = if all_blocks { y } else { 0 };
        out.extend_from_slice(&(start + block * (8 + line as u64)).to_le_bytes());
    }
    for y in 0..if all_blocks { h } else { 1 } {
        out.extend_from_slice(&ints(&[y, line as i32]));
        out.resize(out.len() + line, 0);
    }
    out
}

/// Found with a hand-built input while writing the fuzz harness (the fuzzer itself did not reach it): a
/// 330 KB EXR whose header declares 16384×16384 float RGB pixels
/// but holds one scanline block. The exr crate fills the missing blocks in, so it "read" fine after
/// 10 s and 6 GB of memory. A layer may now hold at most 1100 times the file size (deflate's best is
/// 1032:1).
#[test]
fn an_exr_declaring_far_more_pixels_than_its_size_is_refused() {
    let dir = TempDir::new("fuzz-exr");
    let path = dir.write("big.exr", scanline_exr(16384, 16384, false));
    let e = bounded("big exr", || image::read(&path)).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("EXR header declares 3221225472 bytes of pixel data, more than a"), "{e}");
    assert!(e.ends_with("file can hold (a corrupt header or missing data)"), "{e}");
    // Complete files of the same layout read.
    let path = dir.write("small.exr", scanline_exr(64, 32, true));
    let img = image::read(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((img.width, img.height), (64, 32));
    // A constant image compresses as well as ZIP allows, and still reads back.
    let black = Image::new(1024, 1024);
    let path = dir.path("black.exr");
    image::write(&black, &path).unwrap_or_else(|e| panic!("{e}"));
    let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    assert!(size < 1024 * 1024 * 12 / 500, "{size} bytes: the bound is not exercised");
    assert_eq!(image::read(&path).unwrap_or_else(|e| panic!("{e}")), black);
}
