//! The image files the renderer writes and the metrics read: round trips through every format,
//! all-or-nothing writes, and errors that name the file.

use std::path::{Path, PathBuf};

use cachert::Error;
use cachert::image::{self, Image, Metadata, Window};

/// A fresh scratch directory under the system temp dir.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cachert-image-io-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

fn gradient(width: usize, height: usize) -> Image {
    let mut im = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            im.set(x, y, [x as f32 / width as f32, y as f32 / height as f32 * 10.0, 0.001 * (x * y) as f32]);
        }
    }
    im
}

#[test]
fn exr_and_pfm_round_trip_exactly() {
    let dir = scratch("exact");
    let im = gradient(13, 7);
    for name in ["a.exr", "a.pfm", "UPPER.EXR"] {
        let path = dir.join(name);
        image::write(&im, &path).unwrap();
        assert_eq!(image::read(&path).unwrap(), im, "{name}");
    }
    assert_eq!(entries(&dir), vec!["UPPER.EXR", "a.exr", "a.pfm"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn png_is_an_srgb_preview() {
    let dir = scratch("png");
    let mut im = Image::new(3, 1);
    im.set(0, 0, [0.214_041_14, 0.0, 1.0]); // sRGB 0.5 → code 128
    im.set(1, 0, [5.0, -1.0, f32::NAN]); // clamped
    let path = dir.join("p.png");
    image::write(&im, &path).unwrap();
    let back = image::read(&path).unwrap();
    assert!((back.get(0, 0)[0] - image::srgb_to_linear(128.0 / 255.0)).abs() < 1e-6);
    assert_eq!(back.get(1, 0), [1.0, 0.0, 0.0]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn pfm_is_written_like_pbrt_v3() {
    let dir = scratch("pfm-layout");
    let mut im = Image::new(2, 2);
    im.set(0, 1, [1.0, 2.0, 3.0]); // bottom left: the first pixel in the file
    let path = dir.join("b.pfm");
    image::write(&im, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header = b"PF\n2 2\n-1\n";
    assert!(bytes.starts_with(header));
    assert_eq!(bytes.len(), header.len() + 2 * 2 * 3 * 4);
    assert_eq!(f32::from_le_bytes(bytes[header.len()..header.len() + 4].try_into().unwrap()), 1.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn failed_writes_leave_nothing() {
    let dir = scratch("fail");
    let im = gradient(4, 4);
    // Into a directory that does not exist.
    let e = image::write(&im, &dir.join("nope/out.exr")).unwrap_err();
    assert!(e.to_string().contains("nope/out.exr"), "{e}");
    // An image that cannot be written (its pixel count does not match its size).
    let broken = Image { width: 4, height: 4, pixels: vec![[0.0; 3]; 3] };
    for name in ["x.exr", "x.pfm", "x.png"] {
        assert!(image::write(&broken, &dir.join(name)).is_err());
    }
    // A failed write over an existing file keeps the old file.
    let keep = dir.join("keep.pfm");
    image::write(&im, &keep).unwrap();
    assert!(image::write(&broken, &keep).is_err());
    assert_eq!(image::read(&keep).unwrap(), im);
    assert_eq!(entries(&dir), vec!["keep.pfm"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unknown_extensions_are_usage_errors() {
    let e = image::write(&gradient(2, 2), Path::new("out.tiff")).unwrap_err();
    assert!(matches!(e, Error::Usage(_)));
    assert!(e.to_string().contains(".exr, .pfm or .png"), "{e}");
    assert!(matches!(image::read(Path::new("in.hdr")).unwrap_err(), Error::Usage(_)));
}

#[test]
fn bad_files_are_errors_that_name_the_file() {
    let dir = scratch("bad");
    let cases: [(&str, &[u8], &str); 5] = [
        ("trunc.pfm", b"PF\n4 4\n-1\n\0\0\0\0", "truncated"),
        ("header.pfm", b"P7\n4 4\n-1\n", "not a PFM"),
        ("junk.exr", b"definitely not an exr file", "EXR"),
        ("empty.exr", b"", "EXR"),
        ("junk.png", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR", "PNG"),
    ];
    for (name, bytes, needle) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = image::read(&path).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(needle), "{name}: {e}");
    }
    let e = image::read(&dir.join("missing.pfm")).unwrap_err().to_string();
    assert!(e.contains("missing.pfm") && e.contains("cannot read"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `write` (default metadata) gives the same bytes as before metadata existed: the fixture was written
/// by the previous `image::write` (commit f5936be) from `gradient(5, 3)`, and the goldens compare EXR files.
#[test]
fn default_exr_bytes_are_unchanged() {
    let dir = scratch("default-bytes");
    let fixture = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/image_io/default-5x3.exr")).unwrap();
    let (plain, with) = (dir.join("plain.exr"), dir.join("with.exr"));
    image::write(&gradient(5, 3), &plain).unwrap();
    image::write_with(&gradient(5, 3), &with, &Metadata::default()).unwrap();
    assert_eq!(std::fs::read(&plain).unwrap(), fixture);
    assert_eq!(std::fs::read(&with).unwrap(), fixture);
    assert_eq!(image::read_metadata(&plain).unwrap(), Metadata::default());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A crop written like pbrt-v3's (display window the film, data window the crop) reads back with its window,
/// its text attributes in order and its own pixels; PFM and PNG drop the metadata.
#[test]
fn window_and_attributes_round_trip() {
    let dir = scratch("meta");
    let im = gradient(6, 4);
    let meta = Metadata {
        window: Some(Window { full: [32, 24], origin: [10, 20] }),
        attributes: vec![
            ("cachert.integrator".into(), "irradiancecache".into()),
            ("comments".into(), "a crop".into()),
            ("cachert.seed".into(), "7".into()),
        ],
    };
    for name in ["crop.exr", "crop.pfm", "crop.png"] {
        image::write_with(&im, &dir.join(name), &meta).unwrap();
    }
    assert_eq!(image::read_metadata(&dir.join("crop.exr")).unwrap(), meta);
    assert_eq!(image::read(&dir.join("crop.exr")).unwrap(), im);
    assert_eq!(image::read_metadata(&dir.join("crop.pfm")).unwrap(), Metadata::default());
    assert_eq!(image::read_metadata(&dir.join("crop.png")).unwrap(), Metadata::default());
    // A window that does not hold the image is refused, for every format, and nothing is written.
    let off = Metadata { window: Some(Window { full: [32, 24], origin: [30, 0] }), attributes: vec![] };
    for name in ["off.exr", "off.pfm"] {
        let e = image::write_with(&im, &dir.join(name), &off).unwrap_err();
        assert!(matches!(e, Error::Usage(_)) && e.to_string().contains("does not fit"), "{e}");
    }
    assert_eq!(entries(&dir), vec!["crop.exr", "crop.pfm", "crop.png"]);
    let e = image::read_metadata(&dir.join("missing.exr")).unwrap_err().to_string();
    assert!(e.contains("missing.exr") && e.contains("cannot read"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
