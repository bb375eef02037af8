//! The fuzz targets: what each one feeds its input to, its seed inputs and its dictionary.

use std::path::{Path, PathBuf};

use cachert::error::Warnings;
use cachert::image::{self, Image};
use cachert::parse::integrator::IntegratorParams;
use cachert::render::ambient_occlusion::AmbientOcclusion;
use cachert::scene::shapes::{obj, ply};
use cachert::scene::{LoadOptions, load_str};

/// A reader under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `cachert::parse::parse_str` (tokenizer, parser, Include).
    Parse,
    /// `cachert::scene::load_str`: parse and build the whole scene (plymesh/objmesh files included).
    Scene,
    /// `cachert::scene::shapes::ply::read_ply`.
    Ply,
    /// `cachert::scene::shapes::obj::read_obj`.
    Obj,
    /// `cachert::image::read` (PFM and EXR).
    Image,
}

/// Every target, in the order the smoke test runs them.
pub const ALL: [Target; 5] = [Target::Parse, Target::Scene, Target::Ply, Target::Obj, Target::Image];

/// One seed input.
pub struct Seed {
    /// What to call it in messages.
    pub name: String,
    /// For parse/scene: the path the text is parsed as (in the seed's folder, so Include and mesh files
    /// resolve). For the file readers: the extension of the file the input is written to.
    pub path: PathBuf,
    /// The bytes.
    pub data: Vec<u8>,
}

/// The shared scene folder (`../shared` next to the crate, or `/work/shared`).
pub fn shared_dir() -> Option<PathBuf> {
    let next_to = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared");
    [next_to, PathBuf::from("/work/shared")].into_iter().find(|p| p.join("scenes").is_dir())
}

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Files under `dir` (recursively, sorted) whose extension is `ext`.
fn files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            files(&p, ext, out);
        } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)) {
            out.push(p);
        }
    }
}

/// Where seeds are looked for: the shared scenes, the crate's scenes and test data.
fn seed_roots() -> Vec<PathBuf> {
    let mut roots = Vec::new();
    if let Some(s) = shared_dir() {
        roots.push(s.join("scenes"));
        roots.push(s.join("flip-vectors"));
    }
    roots.push(crate_dir().join("scenes"));
    roots.push(crate_dir().join("tests/data"));
    roots
}

fn found(ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for r in seed_roots() {
        files(&r, ext, &mut out);
    }
    out
}

/// A small scene that uses most directives (a seed that works without the shared folder).
const BUILTIN_SCENE: &str = r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [45]
Film "image" "integer xresolution" [8] "integer yresolution" [8] "string filename" "x.exr"
Sampler "random" "integer pixelsamples" [1]
PixelFilter "box"
Integrator "ambientocclusion" "integer nsamples" [2]
WorldBegin
LightSource "point" "rgb I" [1 1 1]
Texture "c" "spectrum" "checkerboard" "float uscale" [4]
MakeNamedMaterial "m" "string type" "matte" "texture Kd" "c"
AttributeBegin
  NamedMaterial "m"
  Translate 0 1 0
  Shape "sphere" "float radius" [0.5]
AttributeEnd
ObjectBegin "tri"
  Shape "trianglemesh" "integer indices" [0 1 2] "point P" [0 0 0 1 0 0 0 1 0]
ObjectEnd
TransformBegin
  Rotate 30 0 1 0
  ObjectInstance "tri"
TransformEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4]
  Material "plastic" "rgb Kd" [.5 .5 .5] "float roughness" 0.1
  Shape "disk" "float radius" 2
AttributeEnd
Shape "cylinder" "float zmin" -1 "float zmax" 1
WorldEnd
"#;

/// An ascii PLY: a quad and a triangle, with normals and uvs.
const BUILTIN_PLY_ASCII: &str = "ply\nformat ascii 1.0\ncomment builtin\nelement vertex 4\n\
property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
property float u\nproperty float v\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n3 0 2 3\n";

/// A binary PLY in the given byte order: doubles, an extra element and a ushort-indexed face list.
fn builtin_ply_binary(big: bool) -> Vec<u8> {
    let order = if big { "binary_big_endian" } else { "binary_little_endian" };
    let mut out = format!(
        "ply\nformat {order} 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n\
         property uchar red\nelement material 1\nproperty int id\nelement face 2\n\
         property list uchar ushort vertex_indices\nproperty list uint float extra\nend_header\n"
    )
    .into_bytes();
    let f64b = |v: f64| if big { v.to_be_bytes() } else { v.to_le_bytes() };
    for p in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in p {
            out.extend_from_slice(&f64b(c));
        }
        out.push(200);
    }
    out.extend_from_slice(&if big { 7i32.to_be_bytes() } else { 7i32.to_le_bytes() });
    for _ in 0..2 {
        out.push(3);
        for i in [0u16, 1, 2] {
            out.extend_from_slice(&if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        out.extend_from_slice(&if big { 1u32.to_be_bytes() } else { 1u32.to_le_bytes() });
        out.extend_from_slice(&if big { 0.5f32.to_be_bytes() } else { 0.5f32.to_le_bytes() });
    }
    out
}

const BUILTIN_OBJ: &str = "mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 1\nvn 0 0 1\n\
o quad\nusemtl m\nf 1/1/1 2/2/1 3/3/1 4/4/1\ng pent\ns 1\nf 1/1 2/2 3/3 5/5 4/4\nf -1 -2 -3\nl 1 2\n";

const SCENE_DICT: &[&str] = &[
    "WorldBegin",
    "WorldEnd",
    "AttributeBegin",
    "AttributeEnd",
    "TransformBegin",
    "TransformEnd",
    "ObjectBegin \"o\"",
    "ObjectEnd",
    "ObjectInstance \"o\"",
    "Include \"fuzz-missing.pbrt\"",
    "Include",
    "Import",
    "Identity",
    "Translate 1 2 3",
    "Scale 0 0 0",
    "Scale 1e38 1e38 1e38",
    "Rotate 90 0 0 0",
    "LookAt 0 0 0 0 0 0 0 0 0",
    "Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]",
    "ConcatTransform [0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0]",
    "CoordinateSystem \"c\"",
    "CoordSysTransform \"camera\"",
    "ActiveTransform EndTime",
    "ActiveTransform All",
    "TransformTimes 0 1",
    "ReverseOrientation",
    "Camera \"perspective\"",
    "Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]",
    "Camera \"realistic\"",
    "Camera \"environment\"",
    "Film \"image\"",
    "\"integer xresolution\" [1000000000]",
    "\"integer yresolution\" [2147483647]",
    "\"float cropwindow\" [0 1 0 1]",
    "Sampler \"halton\"",
    "\"integer pixelsamples\" [2147483647]",
    "PixelFilter \"gaussian\"",
    "Integrator \"ambientocclusion\"",
    "\"integer nsamples\" [2147483647]",
    "\"float maxdistance\" [-1]",
    "Accelerator \"bvh\"",
    "MakeNamedMedium \"m\" \"string type\" \"homogeneous\"",
    "MediumInterface \"m\" \"\"",
    "LightSource \"point\"",
    "LightSource \"infinite\" \"string mapname\" \"x.exr\"",
    "LightSource \"spot\" \"float coneangle\" [1e38]",
    "AreaLightSource \"diffuse\"",
    "Material \"matte\"",
    "Material \"mix\" \"string namedmaterial1\" \"a\"",
    "Material \"\"",
    "MakeNamedMaterial \"a\" \"string type\" \"matte\"",
    "NamedMaterial \"a\"",
    "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"x.png\"",
    "Texture \"t\" \"float\" \"scale\" \"texture tex1\" \"t\"",
    "\"texture Kd\" \"t\"",
    "Shape \"sphere\"",
    "Shape \"disk\"",
    "Shape \"cylinder\"",
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0 1 0 0 0 1 0]",
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 2147483647] \"point P\" [0 0 0]",
    "Shape \"plymesh\" \"string filename\" \"fuzz-missing.ply\"",
    "Shape \"objmesh\" \"string filename\" \"fuzz-missing.obj\"",
    "Shape \"loopsubdiv\"",
    "\"float alpha\" [0]",
    "\"point P\" [nan inf -inf]",
    "\"normal N\" [0 0 0]",
    "\"float uv\" [0 0]",
    "\"rgb Kd\" [1e38 -1 nan]",
    "\"spectrum Kd\" [300 1 800 2]",
    "\"spectrum Kd\" \"fuzz-missing.spd\"",
    "\"blackbody L\" [6500 1]",
    "\"blackbody L\" [-1 1e38]",
    "\"xyz Kd\" [1 1 1]",
    "\"bool twosided\" \"true\"",
    "\"bool twosided\" [\"maybe\"]",
    "\"string type\" [\"matte\"]",
    "\"float\"",
    "\"integer a b\"",
    "\"\"",
    "[",
    "]",
    "[ ]",
    "\"",
    "#",
    "\n",
];

const PLY_DICT: &[&str] = &[
    "ply\n",
    "format ascii 1.0\n",
    "format binary_little_endian 1.0\n",
    "format binary_big_endian 1.0\n",
    "element vertex 1099511627776\n",
    "element face 1099511627776\n",
    "element vertex 4294967296\n",
    "element extra 1099511627776\n",
    "element vertex 0\n",
    "element face 0\n",
    "property float x\n",
    "property double y\n",
    "property uchar z\n",
    "property float nx\n",
    "property float u\n",
    "property list uchar int vertex_indices\n",
    "property list uint uint vertex_indices\n",
    "property list int float extra\n",
    "property list float int bad\n",
    "property list uint8 int32 vertex_index\n",
    "comment x\n",
    "obj_info x\n",
    "end_header\n",
    "end_header\r\n",
    "\r\n",
];

const OBJ_DICT: &[&str] = &[
    "v 0 0 0\n",
    "v 1e38 nan inf\n",
    "vt 0 0\n",
    "vn 0 0 1\n",
    "vn 0 0 0\n",
    "f 1 2 3\n",
    "f -1 -2 -3\n",
    "f 1/1/1 2/2/2 3/3/3\n",
    "f 1//1 2//2 3//3\n",
    "f 0 0 0\n",
    "f 2147483647 1 2\n",
    "f -2147483648 -1 -2\n",
    "f 4294967296 1 2\n",
    "f 1 2 3 4 5 6 7 8\n",
    "f 1\n",
    "l 1 2\n",
    "p 1\n",
    "o x\n",
    "g x\n",
    "s 1\n",
    "mtllib x.mtl\n",
    "usemtl x\n",
    "#",
    "/",
    "\\\n",
];

const IMAGE_DICT: &[&str] = &[
    "PF\n",
    "Pf\n",
    "-1.0\n",
    "1.0\n",
    "-0\n",
    "nan\n",
    "65535 65535\n",
    "0 0\n",
    "99999999999 1\n",
    "channels\0chlist\0",
    "compression\0compression\0",
    "dataWindow\0box2i\0",
    "displayWindow\0box2i\0",
    "lineOrder\0lineOrder\0",
    "tiles\0tiledesc\0",
    "pixelAspectRatio\0float\0",
    "screenWindowWidth\0float\0",
    "R\0",
    "G\0",
    "B\0",
    "A\0",
    "Y\0",
    "\x76\x2f\x31\x01",
];

impl Target {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Target::Parse => "parse",
            Target::Scene => "scene",
            Target::Ply => "ply",
            Target::Obj => "obj",
            Target::Image => "image",
        }
    }

    /// The target called `name`.
    pub fn from_name(name: &str) -> Option<Target> {
        ALL.into_iter().find(|t| t.name() == name)
    }

    /// Keywords and fragments the mutator inserts.
    pub fn dict(self) -> &'static [&'static str] {
        match self {
            Target::Parse | Target::Scene => SCENE_DICT,
            Target::Ply => PLY_DICT,
            Target::Obj => OBJ_DICT,
            Target::Image => IMAGE_DICT,
        }
    }

    /// The largest input the mutator makes.
    pub fn max_len(self) -> usize {
        match self {
            Target::Parse | Target::Scene => 256 << 10,
            Target::Ply | Target::Obj => 128 << 10,
            // EXR may hold 1100 times its size in pixels: 64 KiB keeps a decode well under 1 GiB.
            Target::Image => 64 << 10,
        }
    }

    /// The seed inputs: the built-in ones, then files found under the shared and crate folders.
    /// `scratch` is where generated seeds may be written.
    pub fn seeds(self, scratch: &Path) -> Vec<Seed> {
        let mut seeds = Vec::new();
        let builtin = |name: &str, path: PathBuf, data: Vec<u8>| Seed { name: name.into(), path, data };
        match self {
            Target::Parse | Target::Scene => {
                let path = crate_dir().join("scenes/fuzz-builtin.pbrt");
                seeds.push(builtin("builtin scene", path, BUILTIN_SCENE.into()));
                for p in found("pbrt") {
                    let slow = ["bitterli-bathroom", "buddha"].iter().any(|s| p.to_string_lossy().contains(s));
                    if self == Target::Scene && slow {
                        continue;
                    }
                    add_file(&mut seeds, &p, p.clone(), 256 << 10);
                }
            }
            Target::Ply => {
                seeds.push(builtin("builtin ascii ply", "ply".into(), BUILTIN_PLY_ASCII.into()));
                seeds.push(builtin("builtin binary LE ply", "ply".into(), builtin_ply_binary(false)));
                seeds.push(builtin("builtin binary BE ply", "ply".into(), builtin_ply_binary(true)));
                // One or two files per distinct header (the bathroom has hundreds of near-identical meshes),
                // smallest first, cut to 32 KiB.
                let mut paths = found("ply");
                paths.sort_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(u64::MAX));
                let mut headers: Vec<(Vec<u8>, usize)> = Vec::new();
                for p in paths {
                    let Ok(bytes) = std::fs::read(&p) else { continue };
                    let end = bytes.windows(10).position(|w| w == b"end_header").unwrap_or(bytes.len().min(512));
                    // The header's shape without its counts.
                    let key: Vec<u8> = bytes[..end].iter().copied().filter(|c| !c.is_ascii_digit()).collect();
                    match headers.iter_mut().find(|(k, _)| *k == key) {
                        Some((_, n)) if *n >= 2 => continue,
                        Some((_, n)) => *n += 1,
                        None => headers.push((key, 1)),
                    }
                    add_file(&mut seeds, &p, "ply".into(), 32 << 10);
                }
            }
            Target::Obj => {
                seeds.push(builtin("builtin obj", "obj".into(), BUILTIN_OBJ.into()));
                for p in found("obj") {
                    add_file(&mut seeds, &p, "obj".into(), 32 << 10);
                }
            }
            Target::Image => {
                for (name, ext) in [("pfm", "pfm"), ("exr", "exr")] {
                    for (w, h) in [(1, 1), (4, 3), (16, 2)] {
                        let img = gradient(w, h);
                        let path = scratch.join(format!("seed-{w}x{h}.{ext}"));
                        if image::write(&img, &path).is_ok()
                            && let Ok(data) = std::fs::read(&path)
                        {
                            seeds.push(builtin(&format!("written {w}x{h} {name}"), ext.into(), data));
                        }
                    }
                }
                // Grey and big-endian PFM, which cachert never writes.
                let mut grey = b"Pf\n3 2\n1.0\n".to_vec();
                for k in 0..6u8 {
                    grey.extend_from_slice(&(f32::from(k) * 0.25).to_be_bytes());
                }
                seeds.push(builtin("builtin grey big-endian pfm", "pfm".into(), grey));
                // Real files, cut to 8 KiB (their headers and first rows).
                for ext in ["pfm", "exr"] {
                    let mut paths = found(ext);
                    paths.sort_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(u64::MAX));
                    for p in paths.into_iter().take(3) {
                        add_file(&mut seeds, &p, ext.into(), 8 << 10);
                    }
                }
            }
        }
        seeds
    }

    /// Feeds `input` to the reader. `Ok` and `Err` are both fine; what matters is that it returns.
    pub fn run(self, input: &[u8], seed: &Seed, scratch: &Path) -> Result<(), String> {
        match self {
            Target::Parse => {
                let text = String::from_utf8_lossy(input);
                cachert::parse::parse_str(&text, &seed.path).map(drop).map_err(|e| e.to_string())
            }
            Target::Scene => {
                let text = String::from_utf8_lossy(input);
                let loaded = load_str(&text, &seed.path, LoadOptions::default()).map_err(|e| e.to_string())?;
                // The render stage's reading of the integrator's parameters (sample counts, distances).
                match &loaded.integrator {
                    Some(named) if named.name == "ambientocclusion" => {
                        let params = IntegratorParams::new(&named.name, &named.params, &[]);
                        AmbientOcclusion::from_params(&params, &loaded.scene.sampler, false)
                            .map(drop)
                            .map_err(|e| e.to_string())
                    }
                    _ => Ok(()),
                }
            }
            Target::Ply | Target::Obj | Target::Image => {
                let path = scratch.join(format!("input.{}", seed.path.display()));
                std::fs::write(&path, input).map_err(|e| format!("fuzz: cannot write {}: {e}", path.display()))?;
                let mut warnings = Warnings::default();
                let r = match self {
                    Target::Ply => ply::read_ply(&path, &mut warnings).map(drop),
                    Target::Obj => obj::read_obj(&path, &mut warnings).map(drop),
                    _ => image::read(&path).map(drop),
                };
                r.map_err(|e| e.to_string())
            }
        }
    }
}

fn add_file(seeds: &mut Vec<Seed>, file: &Path, path: PathBuf, max: usize) {
    if let Ok(mut data) = std::fs::read(file) {
        data.truncate(max);
        seeds.push(Seed { name: file.display().to_string(), path, data });
    }
}

fn gradient(w: usize, h: usize) -> Image {
    let pixels = (0..w * h).map(|i| [i as f32 * 0.1, 0.5, 1.0 - i as f32 * 0.01]).collect();
    Image { width: w, height: h, pixels }
}
