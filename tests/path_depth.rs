//! A cache integrator that replaces a scene's path-like `Integrator` line takes its light-path depth from
//! that line's `maxdepth` (issue 41): importance caching's `vpldepth` and irradiance caching's `maxdepth`
//! are `maxdepth` − 1, so the image has the light paths of the scene's own integrator; `--set` wins, and the
//! warning about the replaced line says what was carried over.

mod common;

use std::path::Path;

use cachert::Warnings;
use cachert::integrator::{RenderSettings, render};
use cachert::scene::{LoadOptions, load_str};

/// Renders `text` with cache integrator `name` and `set`; returns the resolved value of `key` and the
/// warnings' text.
fn depth(text: &str, name: &str, key: &str, set: &[(&str, &str)]) -> (serde_json::Value, String) {
    let loaded = load_str(text, Path::new("depth.pbrt"), LoadOptions::default()).unwrap();
    let mut set: Vec<(String, String)> = set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    set.extend([("caches", "4"), ("vpls", "64"), ("gather", "4")].map(|(k, v)| (k.to_string(), v.to_string())));
    let set = set.into_iter().filter(|(k, _)| name == "importancecache" || k != "vpls").collect::<Vec<_>>();
    let set = set.into_iter().filter(|(k, _)| name == "irradiancecache" || k != "gather").collect();
    let settings = RenderSettings { integrator: Some(name.into()), set, ..Default::default() };
    let mut warnings = Warnings::default();
    let out = render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut warnings).unwrap();
    let text = warnings.iter().map(|w| w.to_string()).collect::<Vec<_>>().join("\n");
    (out.cache.unwrap().settings[key].clone(), text)
}

#[test]
fn a_replaced_path_lines_maxdepth_sets_the_light_path_depth() {
    for (name, key, default) in [("importancecache", "vpldepth", 4), ("irradiancecache", "maxdepth", 3)] {
        for line in ["Integrator \"path\" \"integer maxdepth\" [3]", "Integrator \"volpath\" \"integer maxdepth\" [3]"]
        {
            let (v, w) = depth(&common::lit_plane(line), name, key, &[]);
            assert_eq!(v, 2, "{name} under {line}");
            assert!(w.contains(&format!("its \"maxdepth\" gives {name}'s \"{key}\" 2")), "{w}");
            assert!(!w.contains("are not used"), "maxdepth is used: {w}");
        }
        // pbrt-v3's default maxdepth 5 when the line has none; 65 is clamped to the parameter's 64.
        assert_eq!(depth(&common::lit_plane("Integrator \"path\""), name, key, &[]).0, 4, "{name}");
        assert_eq!(
            depth(&common::lit_plane("Integrator \"path\" \"integer maxdepth\" [65]"), name, key, &[]).0,
            64,
            "{name}"
        );
        // --set wins, and other parameters of the replaced line are still named unused.
        let line = "Integrator \"path\" \"integer maxdepth\" [3] \"float rrthreshold\" [0.5]";
        let (v, w) = depth(&common::lit_plane(line), name, key, &[(key, "1")]);
        assert_eq!(v, 1, "{name}");
        assert!(w.contains("its parameters (maxdepth, rrthreshold) are not used"), "{w}");
        // Lines that are not path-like, and no line at all, leave the default.
        let ao = "Integrator \"ambientocclusion\" \"integer nsamples\" [4]";
        assert_eq!(depth(&common::lit_plane(ao), name, key, &[]).0, default, "{name}");
        assert_eq!(depth(&common::lit_plane(""), name, key, &[]).0, default, "{name}");
    }
}
