//! Integrator parameters (issue 40): every integrator, per-pixel or cache-based, reads exactly the
//! parameters of its table; its documentation page (`docs/integrators/`) shows each table as the code declares
//! it; and no value given by
//! `--set` — NaN, ±∞, negative, zero, huge, not a number — panics: each renders or is a usage error that
//! names the parameter.

use std::path::Path;

use cachert::application::registry::APPLICATIONS;
use cachert::integrator::{RenderSettings, render};
use cachert::parse::integrator::{Parameter, markdown_table};
use cachert::scene::{LoadOptions, LoadedScene, load_str};
use cachert::{Warnings, integrator, render as per_pixel};

/// A lit 8×6 corner: a floor, a wall, a sphere and an area light.
const SCENE: &str = "LookAt 0 1 -4  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
     Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 6\nWorldBegin\n\
     AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nTranslate 0 2.5 0\nShape \"sphere\" \"float radius\" 0.3\nAttributeEnd\n\
     Material \"matte\"\n\
     Shape \"trianglemesh\" \"point P\" [-3 0 -3  3 0 -3  3 0 3  -3 0 3] \"integer indices\" [0 1 2 0 2 3]\n\
     Shape \"trianglemesh\" \"point P\" [-3 0 2  3 0 2  3 3 2  -3 3 2] \"integer indices\" [0 1 2 0 2 3]\n\
     Translate 0.5 0.4 0.5\nShape \"sphere\" \"float radius\" 0.4\nWorldEnd\n";

fn loaded() -> LoadedScene {
    load_str(SCENE, Path::new("params.pbrt"), LoadOptions::default()).unwrap()
}

fn run(l: &LoadedScene, integrator: &str, set: &[(String, String)]) -> cachert::Result<()> {
    let settings = RenderSettings {
        integrator: Some(integrator.into()),
        set: set.to_vec(),
        spp: Some(1),
        threads: Some(1),
        ..Default::default()
    };
    render(&l.scene, l.integrator.as_ref(), &settings, &mut Warnings::default()).map(drop)
}

/// An integrator by name, its parameter table and the settings that keep its renders small.
type Integrator = (&'static str, Vec<Parameter>, Vec<(String, String)>);

/// Every integrator.
fn integrators() -> Vec<Integrator> {
    let mut all: Vec<_> = per_pixel::PARAMETERS.iter().map(|&(n, t)| (n, t.to_vec(), Vec::new())).collect();
    for e in APPLICATIONS {
        let own = integrator::cache::PARAMETERS.iter().chain(e.parameters).copied().collect();
        let quick = e.quick.iter().chain(&[("caches", "8")]).map(|(k, v)| (k.to_string(), v.to_string()));
        all.push((e.name, own, quick.collect()));
    }
    all
}

#[test]
fn every_integrator_reads_exactly_its_table() {
    let names: Vec<&str> = per_pixel::PARAMETERS.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, per_pixel::INTEGRATORS);
    let l = loaded();
    for (name, table, _) in integrators() {
        let e = run(&l, name, &[("zzz".into(), "1".into())]).unwrap_err().to_string();
        let (_, list) = e.split_once("it reads: ").unwrap_or_else(|| panic!("{name}: {e}"));
        let mut read: Vec<&str> = list.trim_end_matches(')').split(", ").collect();
        let mut documented: Vec<&str> = table.iter().map(|p| p.name).collect();
        read.sort_unstable();
        documented.sort_unstable();
        assert_eq!(read, documented, "{name}");
    }
}

/// The documentation page of an integrator.
fn page(name: &str) -> (String, String) {
    let rel = format!("docs/integrators/{name}.md");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(&rel))
        .unwrap_or_else(|e| panic!("{rel}: {e}"));
    (rel, text)
}

#[test]
fn each_integrator_page_has_its_table_as_the_code_declares_it() {
    // `ambientocclusion` is pbrt-v3's integrator, documented by pbrt-v3; the page tables the other two.
    let (rel, text) = page("per-pixel");
    for (name, table) in &per_pixel::PARAMETERS[1..] {
        let t = markdown_table(table);
        assert!(text.contains(&t), "{rel} lacks the table of {name} as the code declares it; paste:\n{t}");
    }
    // Each cache application's own table on its page; the parameters every cache integrator shares are in
    // docs/placements.md.
    let placements = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/placements.md")).unwrap();
    let t = markdown_table(integrator::cache::PARAMETERS);
    assert!(placements.contains(&t), "docs/placements.md lacks the generic table as the code declares it; paste:\n{t}");
    for e in APPLICATIONS {
        let (rel, text) = page(e.name);
        let t = markdown_table(e.parameters);
        assert!(text.contains(&t), "{rel} lacks the table of {} as the code declares it; paste:\n{t}", e.name);
    }
}

#[test]
fn no_set_value_panics_and_every_refusal_names_its_parameter() {
    let l = loaded();
    let mut panics = Vec::new();
    let (mut rendered, mut refused) = (0, 0);
    for (name, table, base) in integrators() {
        for p in &table {
            let values: &[&str] = match p.ty {
                "integer" => &["-1", "0", "1", "2147483647", "1.5", "x"],
                "float" => &["nan", "inf", "-inf", "-1", "0", "1e-300", "1e30", "x"],
                "bool" => &["maybe"],
                _ => &["", "zzz"],
            };
            for v in values {
                let mut set = base.clone();
                set.push((p.name.to_string(), v.to_string()));
                let what = format!("{name} --set {}={v}", p.name);
                match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(&l, name, &set))) {
                    Ok(Ok(())) => rendered += 1,
                    Ok(Err(e)) => {
                        let e = e.to_string();
                        assert!(e.contains(p.name), "{what}: the error does not name the parameter: {e}");
                        refused += 1;
                    }
                    Err(_) => panics.push(what),
                }
            }
        }
    }
    eprintln!("{rendered} rendered, {refused} refused");
    assert!(panics.is_empty(), "panics:\n{}", panics.join("\n"));
}
