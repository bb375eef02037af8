//! `MANIFEST.json` of a golden folder: for each golden image, the inputs that render it ([`Spec`]) and what
//! was recorded when it was made ([`Recorded`]: commit, platform, machine, mean, every resolved setting).
//!
//! Paths in the manifest are relative to its folder, so the folder can move with the scenes it names.
//!
//! Depends on `serde` and `image` (atomic writes) only.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The manifest's file name inside a golden folder.
pub const MANIFEST: &str = "MANIFEST.json";

/// Version of the manifest format this build writes. Format 1 had no [`Recorded::platform`]; this build
/// reads it too, taking the platform from the front of the machine string (`x86_64-linux, AMD EPYC`).
pub const FORMAT: u32 = 2;

/// How to render one golden: what `cachert render` would be given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// The scene file, relative to the manifest's folder (or absolute).
    pub scene: String,
    /// The integrator (`--integrator`).
    pub integrator: String,
    /// The placement of a cache-based integrator (`--placement`); absent for per-pixel integrators.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placement: Option<String>,
    /// The cache budget (`--caches`); absent: the integrator's default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caches: Option<usize>,
    /// Film resolution (`--resolution`); absent: the scene's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<[u32; 2]>,
    /// Samples per pixel (`--spp`); absent: the scene's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
    /// Seed of every random stream (`--seed`).
    pub seed: u64,
    /// Integrator parameters (`--set KEY=VALUE`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub set: BTreeMap<String, String>,
}

/// What was recorded when a golden was rendered.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recorded {
    /// The commit of the code that rendered it (`git describe --always --dirty`, or `unknown`).
    pub commit: String,
    /// The platform it was rendered on ([`super::platform`]: architecture and system, `x86_64-linux`):
    /// what decides whether a re-render must be bit-identical. Empty in a format-1 manifest until read.
    #[serde(default)]
    pub platform: String,
    /// The machine it was rendered on ([`super::machine_kind`]: platform and CPU model), for the record
    /// only: the CPU model does not change an image.
    pub machine: String,
    /// Mean of each channel.
    pub mean: [f64; 3],
    /// Seconds the render took.
    pub secs: f64,
    /// Every resolved setting: for a cache-based integrator the `--stats` parameters (generic and the
    /// application's, defaults filled in); for a per-pixel one its samples per pixel.
    pub settings: serde_json::Map<String, serde_json::Value>,
}

/// One golden image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// Unique name (what `--filter` matches).
    pub name: String,
    /// The image, relative to the manifest's folder (EXR, float RGB).
    pub file: String,
    /// How to render it.
    pub spec: Spec,
    /// What was recorded when it was made.
    pub recorded: Recorded,
}

/// A golden folder's manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: u32,
    /// The goldens, in the order they are checked.
    pub entries: Vec<Entry>,
}

impl Default for Manifest {
    fn default() -> Self {
        Manifest { format: FORMAT, entries: Vec::new() }
    }
}

impl Manifest {
    /// Reads `dir/MANIFEST.json`; a missing file is an error unless `allow_missing` (then it is empty).
    pub fn read(dir: &Path, allow_missing: bool) -> Result<Manifest> {
        let path = dir.join(MANIFEST);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if allow_missing && e.kind() == std::io::ErrorKind::NotFound => return Ok(Manifest::default()),
            Err(e) => return Err(Error::file(&path, format!("cannot read the golden manifest: {e}"))),
        };
        let mut m: Manifest = serde_json::from_str(&text).map_err(|e| {
            Error::file(&path, format!("line {}, column {}: not a golden manifest: {e}", e.line(), e.column()))
        })?;
        if m.format != FORMAT && m.format != 1 {
            return Err(Error::file(&path, format!("manifest format {} (this build reads 1 and {FORMAT})", m.format)));
        }
        for e in &mut m.entries {
            if e.recorded.platform.is_empty() {
                e.recorded.platform = platform_of_machine(&e.recorded.machine);
            }
        }
        m.format = FORMAT;
        m.validate().map_err(|msg| Error::file(&path, msg))?;
        Ok(m)
    }

    /// Writes `dir/MANIFEST.json` all-or-nothing.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join(MANIFEST);
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::file(&path, format!("cannot encode the manifest: {e}")))?;
        crate::image::write_bytes(&path, format!("{text}\n").as_bytes())
    }

    /// Names are unique and non-empty, and files are distinct relative `.exr` paths.
    fn validate(&self) -> std::result::Result<(), String> {
        let mut names = std::collections::HashSet::new();
        let mut files = std::collections::HashSet::new();
        for e in &self.entries {
            if e.name.is_empty() || !names.insert(e.name.as_str()) {
                return Err(format!("golden name \"{}\" is empty or not unique", e.name));
            }
            if !e.file.ends_with(".exr") || Path::new(&e.file).is_absolute() || !files.insert(e.file.as_str()) {
                return Err(format!(
                    "golden \"{}\": file \"{}\" must be a distinct relative .exr path",
                    e.name, e.file
                ));
            }
        }
        Ok(())
    }

    /// The entry named `name`.
    pub fn get(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.name == name)
    }
}

/// The platform part of a [`super::machine_kind`] string: what comes before its first `, `.
fn platform_of_machine(machine: &str) -> String {
    machine.split(", ").next().unwrap_or_default().to_string()
}

/// `path` relative to the manifest folder `dir` (absolute paths stay as they are).
pub fn resolve(dir: &Path, path: &str) -> PathBuf {
    let p = Path::new(path);
    if p.is_absolute() { p.to_path_buf() } else { dir.join(p) }
}

/// A file name for the golden named `name`: characters other than letters, digits, `.`, `-`, `+` and `_`
/// become `_`, then `.exr`.
pub fn file_name(name: &str) -> String {
    let stem: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || ".-+_".contains(c) { c } else { '_' }).collect();
    format!("{stem}.exr")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(name: &str, file: &str) -> Entry {
        Entry {
            name: name.into(),
            file: file.into(),
            spec: Spec {
                scene: "s.pbrt".into(),
                integrator: "someapp".into(),
                placement: Some("im".into()),
                caches: None,
                resolution: Some([8, 6]),
                spp: None,
                seed: 3,
                set: BTreeMap::from([("gather".into(), "8".into())]),
            },
            recorded: Recorded {
                commit: "abc".into(),
                platform: "p".into(),
                machine: "m".into(),
                mean: [1.0, 2.0, 3.0],
                secs: 0.5,
                settings: serde_json::Map::new(),
            },
        }
    }

    #[test]
    fn a_manifest_round_trips_and_duplicates_are_refused() {
        let dir = std::env::temp_dir().join(format!("cachert-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = Manifest { format: FORMAT, entries: vec![entry("a", "a.exr"), entry("b", "b.exr")] };
        m.write(&dir).unwrap();
        assert_eq!(Manifest::read(&dir, false).unwrap(), m);
        let dup = Manifest { format: FORMAT, entries: vec![entry("a", "a.exr"), entry("a", "b.exr")] };
        dup.write(&dir).unwrap();
        let e = Manifest::read(&dir, false).unwrap_err().to_string();
        assert!(e.contains("MANIFEST.json") && e.contains("not unique"), "{e}");
        std::fs::write(dir.join(MANIFEST), "{\"format\": 1, \"entries\": [{]}").unwrap();
        let e = Manifest::read(&dir, false).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("not a golden manifest"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(Manifest::read(&dir, true).unwrap().entries.is_empty());
        assert!(Manifest::read(&dir, false).unwrap_err().to_string().contains("cannot read"));
    }

    #[test]
    fn a_format_1_manifest_takes_its_platform_from_the_machine_string() {
        let dir = std::env::temp_dir().join(format!("cachert-manifest-v1-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut e = entry("a", "a.exr");
        e.recorded.machine = "x86_64-linux, Intel(R) Xeon(R) Platinum, 2 cores".into();
        let mut v = serde_json::to_value(Manifest { format: 1, entries: vec![e] }).unwrap();
        v["entries"][0]["recorded"].as_object_mut().unwrap().remove("platform");
        std::fs::write(dir.join(MANIFEST), v.to_string()).unwrap();
        let m = Manifest::read(&dir, false).unwrap();
        assert_eq!((m.format, m.entries[0].recorded.platform.as_str()), (FORMAT, "x86_64-linux"));
        std::fs::write(dir.join(MANIFEST), "{\"format\": 7, \"entries\": []}").unwrap();
        assert!(Manifest::read(&dir, false).unwrap_err().to_string().contains("manifest format 7"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn file_names_are_safe() {
        assert_eq!(file_name("spheres.someapp.vgc+dgs:diff"), "spheres.someapp.vgc+dgs_diff.exr");
        assert_eq!(file_name("a/b c"), "a_b_c.exr");
    }
}
