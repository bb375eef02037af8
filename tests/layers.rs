//! The layers of `src/` (ARCHITECTURE.md): each top-level module has a layer, and a module may import only
//! from modules of lower layers — never from its own layer's other modules, never up. So circles can only
//! form inside one folder. The check reads every `crate::…` path (and a top-level file's `super::…`) in the
//! non-test code of `src/`, so a new import up a layer, or a new top-level module without a layer, fails
//! here with the file and line.

use std::path::{Path, PathBuf};

/// Every top-level module of `src/` and its layer, lowest first (ARCHITECTURE.md explains each).
const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("os", 0),
    ("provenance", 0),
    ("test_support", 0),
    ("parse", 1),
    ("image", 1),
    ("sampling", 1),
    ("cache", 1),
    ("metrics", 2),
    ("scene", 2),
    ("gbuffer", 3),
    ("shading", 3),
    ("placement", 4),
    ("render", 4),
    ("application", 4),
    ("integrator", 5),
    ("job", 6),
    ("golden", 7),
    ("experiment", 7),
    ("cli", 8),
];

/// What the crate root re-exports from `error` (`crate::Result`, …).
const ROOT_REEXPORTS: &[&str] = &["Error", "Result", "SourceLoc", "Warning", "Warnings"];

fn layer(module: &str) -> Option<u32> {
    if ROOT_REEXPORTS.contains(&module) {
        return Some(0);
    }
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, l)| l)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without its test module (from a `#[cfg(test)]` line followed by `mod`) and without
/// comments.
fn code_lines(text: &str) -> Vec<(usize, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        if t.starts_with("#[cfg(test)]") && lines.get(i + 1).is_some_and(|n| n.trim_start().starts_with("mod ")) {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        out.push((i + 1, l.split(" // ").next().unwrap_or("").to_string()));
    }
    out
}

/// The modules named right after each `prefix` in `line` (`crate::scene::…` gives `scene`).
fn named_after(line: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find(prefix) {
        let before = rest[..at].chars().last();
        rest = &rest[at + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        if !name.is_empty() {
            out.push(name);
        }
    }
    out
}

/// Every import of `src/` that crosses top-level modules: (file, line, from, to).
fn imports() -> Vec<(String, usize, String, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut out = Vec::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap().to_string_lossy().into_owned();
        if rel == "lib.rs" || rel == "main.rs" {
            continue;
        }
        let from = rel.split('/').next().unwrap().trim_end_matches(".rs").to_string();
        let top_level_file = !rel.contains('/');
        for (n, line) in code_lines(&std::fs::read_to_string(&f).unwrap()) {
            let mut to = named_after(&line, "crate::");
            if top_level_file {
                to.extend(named_after(&line, "super::"));
            }
            for t in to {
                if t != from {
                    out.push((rel.clone(), n, from.clone(), t));
                }
            }
        }
    }
    out
}

#[test]
fn every_top_level_module_has_a_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut missing = Vec::new();
    for e in std::fs::read_dir(&src).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        if name != "lib" && name != "main" && layer(&name).is_none() {
            missing.push(name);
        }
    }
    assert!(missing.is_empty(), "give these modules a layer in tests/layers.rs and ARCHITECTURE.md: {missing:?}");
}

#[test]
fn no_import_runs_up_a_layer_or_across_one() {
    let all = imports();
    assert!(all.len() > 200, "{} imports found: is the reader broken?", all.len());
    let bad: Vec<String> = all
        .iter()
        .filter_map(|(file, line, from, to)| {
            let (lf, lt) = (layer(from)?, layer(to));
            match lt {
                Some(lt) if lt < lf => None,
                Some(lt) => Some(format!("src/{file}:{line}: {from} (layer {lf}) imports {to} (layer {lt})")),
                None => Some(format!("src/{file}:{line}: {from} imports {to}, which has no layer")),
            }
        })
        .collect();
    assert!(bad.is_empty(), "imports up or across a layer:\n{}", bad.join("\n"));
}

#[test]
fn the_reader_sees_imports_and_skips_comments_and_tests() {
    let text = "use crate::scene::Scene;\n// crate::cli::x\nfn f() { crate::render::g(); } // crate::job\n\
                #[cfg(test)]\nmod tests {\n    use crate::cli::Cli;\n}\n";
    let names: Vec<String> = code_lines(text).iter().flat_map(|(_, l)| named_after(l, "crate::")).collect();
    assert_eq!(names, ["scene", "render"]);
    assert!(named_after("cachert::scene", "crate::").is_empty() && named_after("mycrate::x", "crate::").is_empty());
}
