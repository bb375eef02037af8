//! `cachert convert` (pbrt's `imgtool convert`: EXR/PFM/PNG in, scaled by 2^--exposure, the format of
//! OUT's extension out, an EXR's metadata carried to an EXR) and `cachert info IMAGE` (format, size,
//! windows, text attributes, channel statistics), run as the binary: output, exit status 2 and
//! `error: …` on bad input, and nothing written after a failure (issue 42).

mod common;

use std::process::{Command, Output};

use cachert::image::{self, Image, Metadata, Window};
use common::TempDir;

fn cachert(dir: &TempDir, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).current_dir(dir.path("")).output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A failed run: status 2, `error: ` first on stderr containing `needle`, nothing on stdout.
fn assert_fails(out: &Output, needle: &str) {
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: ") && err.contains(needle), "{err:?} should mention {needle:?}");
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
}

/// A 4×2 image, pixel (1, 0) = [0.1, 0.2, 0.4] (sRGB 8-bit code of 0.2 is 124), the rest 0.05.
fn small() -> Image {
    let mut im = Image::from_pixels(4, 2, vec![[0.05; 3]; 8]).unwrap();
    im.set(1, 0, [0.1, 0.2, 0.4]);
    im
}

#[test]
fn pfm_to_png_with_one_stop_doubles_the_values() {
    let dir = TempDir::new("convert-png");
    image::write(&small(), &dir.path("in.pfm")).unwrap();
    let out = cachert(&dir, &["convert", "in.pfm", "out.png", "--exposure", "1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("wrote out.png (4x2"), "{}", text(&out.stdout));
    let back = image::read(&dir.path("out.png")).unwrap();
    assert_eq!((back.width, back.height), (4, 2));
    // 0.2 × 2 = 0.4 through 8-bit sRGB: within a code value.
    let code = |v: f32| (image::linear_to_srgb(v) * 255.0 + 0.5).floor() / 255.0;
    let p = back.get(1, 0);
    for (got, want) in p.iter().zip([0.2f32, 0.4, 0.8]) {
        assert!((got - image::srgb_to_linear(code(want))).abs() < 1e-6, "{p:?}");
    }
    // A negative exposure halves (as a float format keeps it exactly).
    let out = cachert(&dir, &["convert", "in.pfm", "half.exr", "--exposure", "-1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(image::read(&dir.path("half.exr")).unwrap().get(1, 0), [0.05, 0.1, 0.2]);
}

#[test]
fn exr_metadata_goes_on_to_an_exr() {
    let dir = TempDir::new("convert-meta");
    let meta = Metadata {
        window: Some(Window { full: [10, 10], origin: [3, 5] }),
        attributes: vec![("cachert.seed".into(), "3".into()), ("owner".into(), "me".into())],
    };
    image::write_with(&small(), &dir.path("in.exr"), &meta).unwrap();
    let out = cachert(&dir, &["convert", "in.exr", "out.exr"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(image::read_metadata(&dir.path("out.exr")).unwrap(), meta);
    assert_eq!(image::read(&dir.path("out.exr")).unwrap(), small());
    // And `info` shows it.
    let out = cachert(&dir, &["info", "out.exr"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let info = text(&out.stdout);
    for line in [
        "format      EXR\n",
        "size        4x2\n",
        "display     (0, 0) .. (9, 9)\n",
        "data        (3, 5) .. (6, 6)\n",
        "attributes  2\n",
        "  cachert.seed  3\n",
        "  owner  me\n",
        "non-finite  0\n",
    ] {
        assert!(info.contains(line), "no {line:?} in\n{info}");
    }
    let r = info.lines().find(|l| l.trim_start().starts_with("R ")).unwrap();
    // R: mean (7 × 0.05 + 0.1) / 8 = 0.05625, min 0.05, max 0.1.
    assert!(r.contains("0.056250") && r.contains("0.050000") && r.contains("0.100000"), "{r}");
}

#[test]
fn info_counts_non_finite_values() {
    let dir = TempDir::new("info-image");
    let mut im = small();
    im.set(0, 1, [f32::NAN, f32::INFINITY, 1.0]);
    image::write(&im, &dir.path("nan.pfm")).unwrap();
    let out = cachert(&dir, &["info", "nan.pfm"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let info = text(&out.stdout);
    assert!(info.contains("format      PFM\n") && info.contains("non-finite  2\n"), "{info}");
    assert!(!info.contains("display"), "{info}");
    assert_fails(&cachert(&dir, &["info", "missing.exr"]), "missing.exr");
    dir.write("junk.png", "not a png");
    assert_fails(&cachert(&dir, &["info", "junk.png"]), "junk.png");
}

#[test]
fn bad_output_extension_or_folder_fails_before_reading() {
    let dir = TempDir::new("convert-bad-out");
    // The input does not exist, but the output is checked first.
    assert_fails(&cachert(&dir, &["convert", "missing.pfm", "out.jpg"]), ".exr, .pfm or .png");
    assert_fails(&cachert(&dir, &["convert", "missing.pfm", "no/such/out.png"]), "does not exist");
    assert_fails(&cachert(&dir, &["convert", "missing.pfm", "x.png", "--exposure", "1000"]), "--exposure");
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn missing_or_bad_input_writes_nothing() {
    let dir = TempDir::new("convert-bad-in");
    assert_fails(&cachert(&dir, &["convert", "missing.pfm", "out.png"]), "missing.pfm");
    dir.write("junk.exr", "not an exr");
    assert_fails(&cachert(&dir, &["convert", "junk.exr", "out.exr"]), "junk.exr");
    assert_fails(&cachert(&dir, &["convert", "in.tga", "out.exr"]), "in.tga");
    assert_eq!(dir.entries(), vec!["junk.exr"]);
}
