//! What a new user meets first (issue 42), through the binary: pbrt-v3 integrators cachert renders with
//! its own, any `maxdepth`, placement names in any case with a did-you-mean, and a negative cache budget
//! that is a clear error rather than clap's tip, misspelt parameters named with their nearest, warnings printed
//! before the render, and routine facts as notes.

mod common;

use std::path::Path;
use std::process::Command;

use common::TempDir;

/// Runs `cachert render` on `text` (written to a file in `dir`) with `args`: exit code, stderr, and whether
/// the image was written.
fn render(dir: &TempDir, text: &str, args: &[&str]) -> (i32, String, bool) {
    let file = dir.write("scene.pbrt", text);
    let out = dir.path("out.pfm");
    let _ = std::fs::remove_file(&out);
    let o = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .arg("render")
        .arg(&file)
        .args(["--outfile", out.to_str().unwrap()])
        .args(args)
        .output()
        .unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned(), out.exists())
}

#[test]
fn pbrt_v3_integrators_we_do_not_have_render_with_the_one_of_the_same_image() {
    let dir = TempDir::new("first-hour-standins");
    for (line, by) in [
        ("Integrator \"volpath\" \"integer maxdepth\" [65]", "path"),
        ("Integrator \"bdpt\" \"integer maxdepth\" [3] \"bool visualizestrategies\" \"false\"", "path"),
        ("Integrator \"mlt\"", "path"),
        ("Integrator \"sppm\"", "path"),
        ("Integrator \"whitted\" \"integer maxdepth\" [3]", "directlighting"),
    ] {
        let (code, err, written) = render(&dir, &common::lit_plane(line), &["--spp", "1"]);
        assert!(code == 0 && written, "{line}: {err}");
        assert!(err.contains(&format!("is rendered by \"{by}\"")), "{line}: {err}");
    }
    // The stand-in reads the line's parameters: bdpt's own are unused, maxdepth is not.
    let (_, err, _) = render(
        &dir,
        &common::lit_plane("Integrator \"bdpt\" \"integer maxdepth\" [3] \"bool visualizestrategies\" \"false\""),
        &[],
    );
    assert!(
        err.contains("unused parameter \"bool visualizestrategies\"") && !err.contains("\"integer maxdepth\""),
        "{err}"
    );
    // pbrt-v3 reads any maxdepth: the shared Cornell box sets 65.
    for integrator in ["path", "directlighting"] {
        let line = format!("Integrator \"{integrator}\" \"integer maxdepth\" [65]");
        let (code, err, _) = render(&dir, &common::lit_plane(&line), &["--spp", "1"]);
        assert_eq!(code, 0, "{integrator}: {err}");
    }
}

#[test]
fn placement_names_in_any_case_and_a_did_you_mean() {
    let dir = TempDir::new("first-hour-placement");
    let text = common::lit_plane("");
    let cache = ["--integrator", "cacheao", "--caches", "8", "--spp", "1"];
    let (code, err, written) = render(&dir, &text, &[&cache[..], &["--placement", "VGC+DGS"]].concat());
    assert!(code == 0 && written, "{err}");
    let (code, err, written) = render(&dir, &text, &[&cache[..], &["--placement", "vgc+dsg"]].concat());
    assert!(code == 2 && !written, "{err}");
    assert!(err.contains("did you mean \"vgc+dgs\"?"), "{err}");
    // In a scene file the error is located.
    let located =
        common::lit_plane("Integrator \"cacheao\" \"integer caches\" [8]\n  \"string placement\" \"vgc+dsg\"");
    let (code, err, written) = render(&dir, &located, &["--spp", "1"]);
    assert!(code == 2 && !written, "{err}");
    assert!(err.contains("scene.pbrt:2:3:") && err.contains("did you mean \"vgc+dgs\"?"), "{err}");
}

#[test]
fn a_negative_cache_budget_is_a_clear_error() {
    let dir = TempDir::new("first-hour-caches");
    let (code, err, written) = render(&dir, &common::lit_plane(""), &["--integrator", "cacheao", "--caches", "-5"]);
    assert!(code == 2 && !written, "{err}");
    assert!(err.contains("at least 1, got -5") && !err.contains("-- -5"), "{err}");
}

#[test]
fn a_bad_output_is_found_before_the_scene_is_read() {
    let dir = TempDir::new("first-hour-outputs");
    // The scene does not exist: the output's error comes first, so nothing was read or rendered.
    let missing_scene = dir.path("no-such-scene.pbrt");
    let run = |args: &[&str]| {
        let o =
            Command::new(env!("CARGO_BIN_EXE_cachert")).arg("render").arg(&missing_scene).args(args).output().unwrap();
        (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let nowhere = dir.path("no-such-folder/out.exr");
    let (code, err) = run(&["--outfile", nowhere.to_str().unwrap()]);
    assert!(code == 2 && err.contains("--outfile") && err.contains("does not exist"), "{err}");
    let (code, err) = run(&["--outfile", dir.path("out.jpg").to_str().unwrap()]);
    assert!(code == 2 && err.contains("--outfile") && err.contains("extension"), "{err}");
    let (code, err) = run(&["--outfile", dir.path("out.exr").to_str().unwrap(), "--stats", nowhere.to_str().unwrap()]);
    assert!(code == 2 && err.contains("--stats"), "{err}");
    // A good output name gets as far as the scene.
    let (code, err) = run(&["--outfile", dir.path("out.exr").to_str().unwrap()]);
    assert!(code == 2 && err.contains("no-such-scene.pbrt"), "{err}");
    assert_eq!(dir.entries(), Vec::<String>::new(), "nothing written, no probe left");
}

#[test]
fn a_resolution_too_large_for_this_machine_blames_the_flag() {
    let dir = TempDir::new("first-hour-resolution");
    let (code, err, written) = render(&dir, &common::lit_plane(""), &["--resolution", "3000000x3000000"]);
    assert!(code == 2 && !written, "{err}");
    assert!(err.contains("--resolution 3000000x3000000: film resolution") && err.contains("is available"), "{err}");
    assert!(!err.contains("scene.pbrt:"), "the Film line is not at fault: {err}");
    // A scene whose own Film is too large renders at a --resolution that fits.
    let huge =
        common::lit_plane("").replace("[8] \"integer yresolution\" [8]", "[3000000] \"integer yresolution\" [3000000]");
    let (code, err, written) = render(&dir, &huge, &["--resolution", "8x8", "--spp", "1"]);
    assert!(code == 0 && written, "{err}");
}

#[test]
fn a_misspelt_parameter_is_named_with_its_nearest_before_the_render() {
    let dir = TempDir::new("first-hour-typo");
    let text = common::lit_plane("Integrator \"directlighting\" \"integer maxdeth\" [3]")
        .replace("Material \"matte\"", "Material \"matte\"\nShape \"sphere\" \"float radus\" [0.5]");
    let (code, err, written) = render(&dir, &text, &["--spp", "1"]);
    assert!(code == 0 && written, "{err}");
    assert!(err.contains("warning: Shape: unused parameter \"float radus\" (did you mean \"radius\"?)"), "{err}");
    assert!(
        err.contains("warning: Integrator: unused parameter \"integer maxdeth\" (did you mean \"maxdepth\"?)"),
        "{err}"
    );
    // The scene's warnings come out before a failure later on: here the Film's own file name, checked once
    // the scene is read, names a folder that does not exist.
    let text = text.replace("Film \"image\"", "Film \"image\" \"string filename\" \"no-such-folder/a.exr\"");
    let file = dir.write("film.pbrt", text);
    let o = Command::new(env!("CARGO_BIN_EXE_cachert")).arg("render").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let (warning, error) = (err.find("did you mean \"radius\""), err.find("error:"));
    assert!(o.status.code() == Some(2) && warning.is_some() && warning < error, "{err}");
}

#[test]
fn routine_facts_are_notes_and_image_changes_are_warnings() {
    let dir = TempDir::new("first-hour-notes");
    let text = common::lit_plane("Sampler \"halton\"\nIntegrator \"path\" \"integer maxdepth\" [3]")
        .replace("WorldBegin", "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"");
    let (code, err, _) = render(&dir, &text, &["--integrator", "cacheao", "--caches", "8", "--set", "gather=4"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = err.lines().collect();
    let kind = |what: &str| lines.iter().find(|l| l.contains(what)).map(|l| l.contains(": note: "));
    assert_eq!(kind("Sampler \"halton\" is not used"), Some(true), "{err}");
    assert_eq!(kind("is replaced by --integrator cacheao"), Some(true), "{err}");
    assert_eq!(kind("participating media"), Some(false), "a warning: {err}");
}

#[test]
fn irradiance_caching_renders_the_whole_image_by_default() {
    // A lit plane has no indirect light (it cannot see itself), so the default image, `output full`, is the
    // directlighting image of the same seed, bit for bit; `output indirect` is black.
    let dir = TempDir::new("first-hour-irradiance");
    let image = |integrator: &str, args: &[&str]| {
        let (code, err, written) = render(&dir, &common::lit_plane(integrator), args);
        assert!(code == 0 && written, "{integrator}: {err}");
        cachert::image::read(&dir.path("out.pfm")).unwrap()
    };
    let default = image("Integrator \"irradiancecache\" \"integer caches\" [8] \"integer gather\" [4]", &[]);
    let direct = image("Integrator \"directlighting\"", &[]);
    assert!(common::mean(&direct) > 0.0);
    assert_eq!(default.pixels, direct.pixels);
    let indirect = image(
        "Integrator \"irradiancecache\" \"integer caches\" [8] \"integer gather\" [4]",
        &["--set", "output=indirect"],
    );
    assert!(indirect.pixels.iter().all(|p| *p == [0.0; 3]));
}

#[test]
fn a_crop_renders_the_same_pixels_as_that_part_of_the_whole_image() {
    // pbrt-v3's --cropwindow: x0,x1,y0,y1 as fractions, rounded up to pixels (here 2..6 × 0..4 of 8×8). Each
    // pixel's samples do not depend on the others, so the crop is that part of the whole render, bit for bit.
    let dir = TempDir::new("first-hour-crop");
    let text = common::lit_plane("Integrator \"directlighting\"");
    let (code, err, _) = render(&dir, &text, &["--spp", "2"]);
    assert_eq!(code, 0, "{err}");
    let whole = cachert::image::read(&dir.path("out.pfm")).unwrap();
    let (code, err, _) = render(&dir, &text, &["--spp", "2", "--crop", "0.25,0.75,0,0.5"]);
    assert_eq!(code, 0, "{err}");
    let crop = cachert::image::read(&dir.path("out.pfm")).unwrap();
    assert_eq!((crop.width, crop.height), (4, 4));
    assert_eq!(Some(crop.clone()), whole.crop(2, 0, 4, 4));
    // pbrt-v3's spelling of the flag; bad windows are the flag's errors and write nothing.
    let (code, err, _) = render(&dir, &text, &["--spp", "2", "--cropwindow", "0.25,0.75,0,0.5"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(cachert::image::read(&dir.path("out.pfm")).unwrap(), crop);
    for (bad, why) in [
        ("0.5,0.25,0,1", "x0 < x1"),
        ("0,1,0", "four numbers"),
        ("0,1.5,0,1", "between 0 and 1"),
        ("0.1,0.11,0,1", "covers no pixel of the 8x8 film"),
    ] {
        let (code, err, written) = render(&dir, &text, &["--crop", bad]);
        assert!(code == 2 && !written && err.contains("--crop") && err.contains(why), "{bad}: {err}");
    }
}

#[test]
fn one_render_writes_every_outfile_it_is_given() {
    let dir = TempDir::new("first-hour-outfiles");
    let file = dir.write("scene.pbrt", common::lit_plane("Integrator \"directlighting\""));
    let (exr, png) = (dir.path("a.exr"), dir.path("a.png"));
    let o = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .arg("render")
        .arg(&file)
        .args(["--spp", "1", "--outfile", exr.to_str().unwrap(), "--outfile", png.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (cachert::image::read(&exr).unwrap(), cachert::image::read(&png).unwrap());
    assert_eq!((a.width, a.height, b.width, b.height), (8, 8, 8, 8));
    // A bad second name stops the run before anything is written.
    std::fs::remove_file(&exr).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .arg("render")
        .arg(&file)
        .args(["--outfile", exr.to_str().unwrap(), "--outfile", dir.path("a.jpg").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(!exr.exists());
}

#[test]
fn an_exr_records_its_crop_and_how_it_was_made() {
    let dir = TempDir::new("first-hour-exr-header");
    let file = dir.write("scene.pbrt", common::lit_plane("Integrator \"directlighting\""));
    let exr = dir.path("a.exr");
    let render = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_cachert"))
            .arg("render")
            .arg(&file)
            .args(["--outfile", exr.to_str().unwrap(), "--seed", "3"])
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        cachert::image::read_metadata(&exr).unwrap()
    };
    // pbrt-v3's crop: the display window is the whole 8×8 film, the data window the crop (2..6 × 2..8).
    let meta = render(&["--crop", "0.25,0.75,0.25,1"]);
    assert_eq!(meta.window, Some(cachert::image::Window { full: [8, 8], origin: [2, 2] }));
    let attr =
        |m: &cachert::image::Metadata, k: &str| m.attributes.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
    assert_eq!(attr(&meta, "integrator").as_deref(), Some("directlighting"));
    assert_eq!(attr(&meta, "seed").as_deref(), Some("3"));
    assert!(attr(&meta, "renderTimeSeconds").is_some() && attr(&meta, "cachertCommit").is_some(), "{meta:?}");
    // A cache render adds its placement and cache count; `cachert info` prints them.
    let meta = render(&["--integrator", "cacheao", "--placement", "im", "--caches", "6", "--set", "gather=4"]);
    assert_eq!(meta.window, None);
    assert_eq!((attr(&meta, "placement").as_deref(), attr(&meta, "caches").as_deref()), (Some("im"), Some("6")));
    let info = Command::new(env!("CARGO_BIN_EXE_cachert")).arg("info").arg(&exr).output().unwrap();
    let info = String::from_utf8_lossy(&info.stdout);
    assert!(info.contains("placement  im") && info.contains("integrator  cacheao"), "{info}");
}

#[test]
fn a_crop_is_the_window_and_the_pixels_pbrt_v3_writes() {
    // tests/data/pbrt-v3/crop: pbrt-v3's own EXR of --cropwindow 0.25 0.75 0.25 1 (make.sh; half floats).
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/crop");
    let dir = TempDir::new("first-hour-pbrt-crop");
    let ours = dir.path("ours.exr");
    let o = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .arg("render")
        .arg(data.join("plane.pbrt"))
        .args(["--crop", "0.25,0.75,0.25,1", "--outfile", ours.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let theirs = data.join("crop.exr");
    let window = |p: &Path| cachert::image::read_metadata(p).unwrap().window;
    assert_eq!(window(&ours), window(&theirs));
    assert_eq!(window(&theirs), Some(cachert::image::Window { full: [8, 8], origin: [2, 2] }));
    let (a, b) = (cachert::image::read(&ours).unwrap(), cachert::image::read(&theirs).unwrap());
    let rmse = cachert::metrics::rmse(&a, &b).unwrap();
    let rel = rmse / common::mean(&b);
    // Measured 0.3 % (64 samples per pixel on both sides, pbrt-v3's half floats).
    assert!(rel < 0.01, "relative RMSE {rel}");
}
