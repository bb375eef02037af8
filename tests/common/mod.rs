//! Helpers shared by the behaviour tests: scratch folders, small scene texts, the third-party scene folder
//! and one-call load-and-render.
#![allow(dead_code)] // each test binary uses its own subset

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use cachert::Warnings;
use cachert::image::Image;
use cachert::integrator::{RenderOutput, RenderSettings, render};
use cachert::scene::{LoadOptions, LoadedScene, load, load_str};

/// A fresh folder under the system temp dir, unique per process and call, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    /// Makes `cachert-<tag>-<pid>-<n>` under `std::env::temp_dir()`.
    pub fn new(tag: &str) -> Self {
        static COUNT: AtomicUsize = AtomicUsize::new(0);
        let n = COUNT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("cachert-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("the temp dir is writable");
        TempDir(dir)
    }

    /// `name` inside the folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Writes `contents` to `name` (folders made as needed) and returns its path.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.0.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("the temp dir is writable");
        }
        std::fs::write(&path, contents).expect("the temp dir is writable");
        path
    }

    /// The names in the folder, sorted (hidden temporary files included).
    pub fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&self.0)
            .expect("the temp dir exists")
            .map(|e| e.expect("readable entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Render options for a tiny test image: `res`×`res` pixels, `spp` random-sampler samples, box filter,
/// pbrt-v3 `ambientocclusion` with `nsamples` rays.
pub fn header(res: u32, spp: u32, nsamples: u32) -> String {
    format!(
        "Film \"image\" \"integer xresolution\" [{res}] \"integer yresolution\" [{res}]\n\
         Sampler \"random\" \"integer pixelsamples\" [{spp}]\n\
         PixelFilter \"box\"\n\
         Integrator \"ambientocclusion\" \"integer nsamples\" [{nsamples}]\n"
    )
}

/// Whether the tests run under CI: the environment variable `CI` set to anything but empty, `false` or `0`
/// (CI services set `CI=true`). Under CI every piece of data a test needs must be there: its absence fails.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        let v = v.trim();
        !(v.is_empty() || v == "0" || v.eq_ignore_ascii_case("false"))
    })
}

/// The folder of third-party data beside the repository: `$CACHERT_SHARED` when set (so that the policy of
/// [`unavailable`] can be tried without touching the real folder), else `CARGO_MANIFEST_DIR/../shared`.
pub fn shared_root() -> PathBuf {
    match std::env::var_os("CACHERT_SHARED") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"),
    }
}

/// What a test does when data it needs is not here (`why` names it): under CI ([`in_ci`]) it fails with
/// the reason; elsewhere it prints one line, `skipped <test>: <why>`, on stderr and the caller returns. Each
/// test binary that reads shared data also has a test `shared_…_present` that fails whenever the data is
/// absent, so a plain `cargo test` shows the skip as one failure instead of passing in silence.
pub fn unavailable(why: &str) {
    if in_ci() {
        panic!("{why}; under CI (the environment variable CI is set) everything the tests need must be there");
    }
    // The harness names each test's thread after the test, and captures `eprintln!`: the line goes to the
    // stream itself, in one write, so that a plain `cargo test` shows it whole.
    let test = std::thread::current().name().unwrap_or("a test").to_string();
    let _ = std::io::stderr().write_all(format!("skipped {test}: {why}\n").as_bytes());
}

/// `rel` under [`shared_root`] when `marker` (a file or folder inside it) is there, or why not.
fn shared_path(rel: &str, marker: &str, what: &str) -> Result<PathBuf, String> {
    let dir = shared_root().join(rel);
    let needed = if marker.is_empty() { dir.clone() } else { dir.join(marker) };
    if needed.exists() {
        Ok(dir)
    } else {
        Err(format!("{} is absent ({what} live there; CACHERT_SHARED names another copy)", needed.display()))
    }
}

/// The shared scenes folder, or why it is not here.
fn shared_scenes_dir() -> Result<PathBuf, String> {
    shared_path("scenes", "", "the third-party scenes and their pbrt-v3 references")
}

/// The third-party scenes folder (`<shared>/scenes`), or `None` after [`unavailable`] (a failure under CI).
pub fn shared_scenes() -> Option<PathBuf> {
    shared_scenes_dir().map_err(|why| unavailable(&why)).ok()
}

/// A file that a test needs inside the shared scenes (`root` from [`shared_scenes`]), or `None` after
/// [`unavailable`]: a partial copy of the folder skips outside CI and fails under it.
pub fn shared_file(root: &Path, rel: &str) -> Option<PathBuf> {
    let path = root.join(rel);
    if path.exists() {
        Some(path)
    } else {
        unavailable(&format!("{} is absent from the shared scenes", path.display()));
        None
    }
}

/// Fails, whatever `CI` says, when the shared scenes are absent: the body of each binary's
/// `shared_scenes_present` test.
pub fn assert_shared_scenes_present() {
    if let Err(why) = shared_scenes_dir() {
        panic!("{why}: the tests that need them did not run");
    }
}

/// The shared FLIP test vectors (`<shared>/flip-vectors`, with `expected.txt`), or `None` after
/// [`unavailable`].
pub fn flip_vectors() -> Option<PathBuf> {
    flip_vectors_dir().map_err(|why| unavailable(&why)).ok()
}

fn flip_vectors_dir() -> Result<PathBuf, String> {
    shared_path("flip-vectors", "expected.txt", "NVIDIA FLIP's test vectors")
}

/// Fails, whatever `CI` says, when the FLIP test vectors are absent.
pub fn assert_flip_vectors_present() {
    if let Err(why) = flip_vectors_dir() {
        panic!("{why}: the tests that need them did not run");
    }
}

/// Settings with a seed and everything else at its default.
pub fn settings(seed: u64) -> RenderSettings {
    RenderSettings { seed, ..Default::default() }
}

/// Loads scene text (as the file `name`) and renders it with `s`; panics with the error text on failure.
pub fn render_text(text: &str, name: &str, s: &RenderSettings) -> (RenderOutput, LoadedScene) {
    let loaded = load_str(text, Path::new(name), LoadOptions::default()).unwrap_or_else(|e| panic!("load: {e}"));
    let out = render_loaded(&loaded, s).unwrap_or_else(|e| panic!("render: {e}"));
    (out, loaded)
}

/// Renders a loaded scene with `s`, collecting warnings into the loaded scene's list.
pub fn render_loaded(loaded: &LoadedScene, s: &RenderSettings) -> cachert::Result<RenderOutput> {
    let mut w: Warnings = loaded.warnings.clone();
    render(&loaded.scene, loaded.integrator.as_ref(), s, &mut w)
}

/// Loads the scene file at `path` and renders it.
pub fn render_file(path: &Path, opts: LoadOptions, s: &RenderSettings) -> cachert::Result<(RenderOutput, LoadedScene)> {
    let loaded = load(path, opts)?;
    let out = render_loaded(&loaded, s)?;
    Ok((out, loaded))
}

/// Mean of the three channels over all pixels.
pub fn mean(im: &Image) -> f64 {
    let m = im.mean();
    (m[0] + m[1] + m[2]) / 3.0
}

/// Compares `ours` with two pbrt-v3 renders of the same scene, `a` and `b`, made with different samplers
/// (the `tests/data/pbrt-v3/*/make.sh` convention: `a` random, `b` stratified, and ours rendered with `b`'s
/// settings). RMSE(a, b) is pbrt-v3's noise floor and a correct renderer lands near it from `a`, so this asserts
/// RMSE(ours, a) ≤ 1.3 × floor and the mean within 0.5 % of `a`'s, printing both. With the environment
/// variable `CACHERT_DUMP_DIR` set, `ours` is also written there as `<name>-ours.pfm` for inspection.
pub fn assert_matches_pbrt_pair(name: &str, ours: &Image, a_path: &Path, b_path: &Path) {
    let a = cachert::image::read(a_path).unwrap_or_else(|e| panic!("{name}: reference a: {e}"));
    let b = cachert::image::read(b_path).unwrap_or_else(|e| panic!("{name}: reference b: {e}"));
    let floor = cachert::metrics::rmse(&b, &a).expect("the references have one size");
    assert_within_floor(name, ours, &a, floor, 0.005);
}

/// Loads `<dir>/<scene>.pbrt` (no warnings allowed), renders it with seed 4 and checks it against
/// `<scene>-a.pfm` and `<scene>-b.pfm` beside it with [`assert_matches_pbrt_pair`].
pub fn file_matches_pbrt_pair(dir: &Path, scene: &str) -> LoadedScene {
    let loaded = load(&dir.join(format!("{scene}.pbrt")), LoadOptions::default()).expect("loads");
    assert_eq!(loaded.warnings.len(), 0, "{scene}: {:?}", loaded.warnings);
    let out = render_loaded(&loaded, &settings(4)).expect("renders");
    assert_matches_pbrt_pair(
        scene,
        &out.image,
        &dir.join(format!("{scene}-a.pfm")),
        &dir.join(format!("{scene}-b.pfm")),
    );
    loaded
}

/// Averages `f`×`f` blocks of pixels: a box-filtered pbrt-v3 reference at `f`× our resolution becomes the
/// same estimator at ours.
pub fn downsample(im: &Image, f: usize) -> Image {
    let (w, h) = (im.width / f, im.height / f);
    let mut out = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let mut c = [0.0f32; 3];
            for dy in 0..f {
                for dx in 0..f {
                    let p = im.get(x * f + dx, y * f + dy);
                    (0..3).for_each(|k| c[k] += p[k]);
                }
            }
            out.set(x, y, c.map(|v| v / (f * f) as f32));
        }
    }
    out
}

/// Compares two renders of ours (`a`, `b`: the same estimator, two seeds) with one pbrt-v3 reference that
/// used `ref_per_ours` times as many samples per (our) pixel. The noise model: σ² = RMSE(a, b)²/2 is the
/// variance of one of our renders, pbrt-v3's is σ²/ref_per_ours, so a correct renderer lands at
/// RMSE(a, ref) ≈ σ·√(1 + 1/ref_per_ours). Asserts RMSE(a, ref) ≤ 1.3× that and the mean within `mean_tol`
/// (relative), printing the figures. With `CACHERT_DUMP_DIR` set, `a` is written there for inspection.
pub fn assert_matches_pbrt_single(
    name: &str,
    a: &Image,
    b: &Image,
    reference: &Image,
    ref_per_ours: f64,
    mean_tol: f64,
) {
    let sigma = cachert::metrics::rmse(a, b).expect("same size") / 2f64.sqrt();
    assert_within_floor(name, a, reference, sigma * (1.0 + 1.0 / ref_per_ours).sqrt(), mean_tol);
}

/// Asserts that `ours` is finite, within 1.3 × `floor` of `reference` in RMSE and within `mean_tol`
/// (relative) of its mean, printing the figures. With the environment variable `CACHERT_DUMP_DIR` set,
/// `ours` is also written there as `<name>-ours.pfm` for inspection.
fn assert_within_floor(name: &str, ours: &Image, reference: &Image, floor: f64, mean_tol: f64) {
    let err = cachert::metrics::rmse(ours, reference).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (m_ours, m_theirs) = (mean(ours), mean(reference));
    let dev = (m_ours - m_theirs).abs() / m_theirs.abs().max(1e-12);
    if let Some(dump) = std::env::var_os("CACHERT_DUMP_DIR") {
        cachert::image::write(ours, &Path::new(&dump).join(format!("{name}-ours.pfm"))).expect("dump");
    }
    eprintln!(
        "{name}: RMSE {err:.5}, noise floor {floor:.5}, ratio {:.3}; mean {m_ours:.5} vs pbrt-v3 {m_theirs:.5} ({:.3} %)",
        err / floor,
        100.0 * dev
    );
    assert!(ours.first_non_finite().is_none(), "{name}: a non-finite pixel");
    assert!(err <= 1.3 * floor, "{name}: RMSE {err} is {:.2}× the noise floor {floor}", err / floor);
    assert!(dev <= mean_tol, "{name}: mean {m_ours} vs pbrt-v3's {m_theirs}");
}

/// An 8×8 view of a matte plane under a point light, with `integrator` (an `Integrator` line, or empty)
/// before the camera: for tests of what a scene's integrator line does.
pub fn lit_plane(integrator: &str) -> String {
    format!(
        "{integrator}\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [30]\n\
         Film \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8]\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 0 3] \"rgb I\" [5 5 5]\nMaterial \"matte\"\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-5 -5 0  5 -5 0  5 5 0  -5 5 0]\n\
         WorldEnd\n"
    )
}
