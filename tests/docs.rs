//! The documentation keeps its promises (issue 42): every `cachert` command shown in `README.md`,
//! `docs/`, `tests/README.md` and the experiments' notes names a subcommand that exists and only flags that subcommand accepts
//! (read from the binary's own clap definition, `cachert::cli::Cli`), and one without placeholders parses
//! as the binary would parse it; the README's quick start runs (at 16×16 pixels); `.ci/run` runs the
//! README's test command; every relative link, picture and cited repository path exists; and every
//! decimal number in a README line that cites a committed file occurs in that file.
//!
//! The checkers are plain functions over text, so the unit tests at the bottom feed them bad snippets and
//! require each to fail: a made-up flag, a made-up subcommand, a broken link, a missing file, a number the
//! cited file does not hold.

use std::path::{Path, PathBuf};
use std::process::Command;

use cachert::cli::Cli;
use clap::{CommandFactory, Parser};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The documents checked: the README, `tests/README.md`, every Markdown file under `docs/`, and the
/// experiments' and the fuzzer's notes.
fn documents() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "md") {
                out.push(p);
            }
        }
    }
    let mut docs = vec![root().join("README.md"), root().join("tests/README.md")];
    walk(&root().join("docs"), &mut docs);
    docs.push(root().join("experiments/README.md"));
    docs.push(root().join("examples/fuzz/README.md"));
    walk(&root().join("experiments/notes"), &mut docs);
    docs
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// One command shown in a document: where it is, and its words after the program's name.
#[derive(Debug)]
struct Shown {
    at: String,
    words: Vec<String>,
    /// Shown in a fenced block as a command to copy (not inline in prose, not a `$ ` transcript of an error).
    to_copy: bool,
}

/// The ways a document starts a `cachert` command.
const PROGRAMS: [&str; 3] = ["cachert ", "target/release/cachert ", "cargo run --release -- "];

fn command_words(line: &str) -> Option<Vec<String>> {
    let line = line.trim().trim_start_matches("$ ");
    let rest = PROGRAMS.iter().find_map(|p| line.strip_prefix(p))?;
    let rest = rest.split(" #").next().unwrap_or(rest);
    Some(rest.split_whitespace().map(str::to_string).collect())
}

/// The fenced blocks of a document: (info string, first line number, lines).
fn fenced_blocks(text: &str) -> Vec<(String, usize, Vec<&str>)> {
    let mut blocks = Vec::new();
    let mut open: Option<(String, usize, Vec<&str>)> = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if let Some(info) = t.strip_prefix("```") {
            match open.take() {
                Some(b) => blocks.push(b),
                None => open = Some((info.trim().to_string(), i + 2, Vec::new())),
            }
        } else if let Some(b) = open.as_mut() {
            b.2.push(line);
        }
    }
    blocks
}

/// The document's text outside fenced blocks (a fence's lines become empty, so line numbers hold).
fn prose(text: &str) -> String {
    let mut inside = false;
    let mut out = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            inside = !inside;
        } else if !inside {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

/// The inline code spans of prose, each with its line number (a span may continue over a line break).
fn code_spans(prose: &str) -> Vec<(usize, String)> {
    let mut spans = Vec::new();
    let mut line = 1;
    for (i, part) in prose.split('`').enumerate() {
        if i % 2 == 1 {
            spans.push((line, part.replace('\n', " ")));
        }
        line += part.matches('\n').count();
    }
    spans
}

/// Every `cachert` command of a document: each line of a shell block (an indented line that follows one
/// and starts with `[` or `-` continues it) and each inline code span.
fn commands(text: &str, file: &str) -> Vec<Shown> {
    let mut shown = Vec::new();
    for (info, first, lines) in fenced_blocks(text) {
        if !matches!(info.as_str(), "" | "sh" | "bash" | "shell" | "console" | "text") {
            continue;
        }
        let mut last: Option<usize> = None;
        for (k, line) in lines.iter().enumerate() {
            let continues = line.starts_with(' ') && matches!(line.trim_start().chars().next(), Some('[' | '-'));
            if let (true, Some(j)) = (continues, last) {
                let more = line.split(" #").next().unwrap_or(line).split_whitespace().map(str::to_string);
                let s: &mut Shown = &mut shown[j];
                s.words.extend(more);
                continue;
            }
            last = None;
            if let Some(words) = command_words(line) {
                last = Some(shown.len());
                let to_copy = !line.trim_start().starts_with("$ ");
                shown.push(Shown { at: format!("{file}:{}", first + k), words, to_copy });
            }
        }
    }
    for (line, span) in code_spans(&prose(text)) {
        if let Some(words) = command_words(&span) {
            shown.push(Shown { at: format!("{file}:{line}"), words, to_copy: false });
        }
    }
    shown
}

/// A word that stands for something the reader fills in: `SCENE.pbrt`, `DIR`, `N`, `KEY=VALUE`, `WxH`.
fn placeholder(word: &str) -> bool {
    let stem = word.split(['.', '=', ',']).next().unwrap_or(word);
    let upper = stem.chars().any(|c| c.is_ascii_uppercase());
    (upper && !stem.chars().any(|c| c.is_ascii_lowercase())) || word.contains("WxH")
}

/// What is wrong with one shown command: an unknown subcommand, a flag its subcommand does not accept, or (for
/// a command to copy with no placeholders) anything clap refuses.
fn check_command(s: &Shown) -> Vec<String> {
    let mut problems = Vec::new();
    let mut cmd = Cli::command();
    cmd.build();
    let Some(first) = s.words.first() else {
        return vec![format!("{}: a `cachert` command without a subcommand", s.at)];
    };
    let Some(mut sub) = cmd.find_subcommand(first).cloned() else {
        let names: Vec<_> = cmd.get_subcommands().map(|c| c.get_name().to_string()).collect();
        return vec![format!("{}: `{first}` is not a subcommand (cachert has {})", s.at, names.join(", "))];
    };
    let mut path = vec![first.clone()];
    for w in &s.words[1..] {
        match sub.find_subcommand(w).cloned() {
            Some(next) if !w.starts_with('-') => {
                path.push(w.clone());
                sub = next;
            }
            _ => break,
        }
    }
    let accepts = |name: &str| {
        name == "help"
            || sub
                .get_arguments()
                .any(|a| a.get_long() == Some(name) || a.get_all_aliases().is_some_and(|al| al.contains(&name)))
    };
    for w in &s.words {
        let w = w.trim_matches(|c| matches!(c, '[' | ']' | '(' | ')' | ','));
        if let Some(long) = w.strip_prefix("--") {
            let long = long.split('=').next().unwrap_or(long);
            if !long.is_empty() && !accepts(long) {
                problems.push(format!("{}: `cachert {}` has no flag --{long}", s.at, path.join(" ")));
            }
        } else if let Some(short) = w.strip_prefix('-').filter(|f| f.len() == 1 && f.chars().all(char::is_alphabetic)) {
            let c = short.chars().next().unwrap_or('?');
            if c != 'h' && !sub.get_arguments().any(|a| a.get_short() == Some(c)) {
                problems.push(format!("{}: `cachert {}` has no flag -{c}", s.at, path.join(" ")));
            }
        }
    }
    let concrete = !s
        .words
        .iter()
        .any(|w| placeholder(w) || w.contains(['[', ']', '|', '…']) || w.contains("...") || w == "--help");
    if problems.is_empty() && concrete && s.to_copy {
        let argv = std::iter::once("cachert".to_string()).chain(s.words.iter().cloned());
        if let Err(e) = Cli::try_parse_from(argv) {
            problems.push(format!("{}: `cachert {}` does not parse: {}", s.at, s.words.join(" "), e.render()));
        }
    }
    problems
}

fn check_commands(text: &str, file: &str) -> Vec<String> {
    commands(text, file).iter().flat_map(check_command).collect()
}

/// GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

fn anchors(text: &str) -> Vec<String> {
    prose(text).lines().filter_map(|l| l.strip_prefix('#')).map(|h| slug(h.trim_start_matches('#'))).collect()
}

/// The link targets of a document's prose: Markdown links and pictures, and HTML `src`/`href`, with line numbers.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in prose(text).lines().enumerate() {
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let tail = &rest[at + 2..];
            let end = tail.find(')').unwrap_or(tail.len());
            out.push((i + 1, tail[..end].to_string()));
            rest = &tail[end..];
        }
        for attr in ["src=\"", "href=\""] {
            let mut rest = line;
            while let Some(at) = rest.find(attr) {
                let tail = &rest[at + attr.len()..];
                let end = tail.find('"').unwrap_or(tail.len());
                out.push((i + 1, tail[..end].to_string()));
                rest = &tail[end..];
            }
        }
    }
    out
}

/// Broken relative links of a document at `path` (inside the repository at `repo`): a missing file, or an
/// anchor that no heading of the target makes.
fn check_links(text: &str, path: &Path, repo: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    let file = path.strip_prefix(repo).unwrap_or(path).display().to_string();
    for (line, target) in links(text) {
        if target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        let (file_part, anchor) = target.split_once('#').map_or((target.as_str(), None), |(f, a)| (f, Some(a)));
        let resolved = if file_part.is_empty() { path.to_path_buf() } else { path.parent().unwrap().join(file_part) };
        if !resolved.exists() {
            problems.push(format!("{file}:{line}: link to {target}: no such file"));
            continue;
        }
        if let Some(a) = anchor
            && resolved.extension().is_some_and(|e| e == "md")
            && !anchors(&read(&resolved)).iter().any(|h| h == a)
        {
            problems.push(format!("{file}:{line}: link to {target}: no heading makes #{a}"));
        }
    }
    problems
}

/// The top-level entries a cited path may start with.
const TOP: [&str; 9] = ["src", "tests", "docs", "experiments", "scenes", "golden", "examples", "scripts", ".ci"];

/// A code span that cites a repository path (`src/cli/render.rs:92` cites `src/cli/render.rs`), if it is one.
fn cited_path(span: &str) -> Option<&str> {
    let span = span.trim();
    let first = span.split('/').next()?;
    if span.contains(char::is_whitespace) || !span.contains('/') || !TOP.contains(&first) {
        return None;
    }
    if span.contains(['*', '<', '>', '{', '…']) || placeholder(span.rsplit('/').next().unwrap_or("")) {
        return None;
    }
    Some(span.split(':').next().unwrap_or(span))
}

/// Cited paths of a document in folder `dir` that exist neither from the repository's root nor from `dir`.
fn check_cited_paths(text: &str, file: &str, repo: &Path, dir: &Path) -> Vec<String> {
    code_spans(&prose(text))
        .into_iter()
        .filter_map(|(line, span)| cited_path(&span).map(|p| (line, p.to_string())))
        .filter(|(_, p)| !repo.join(p).exists() && !dir.join(p).exists())
        .map(|(line, p)| format!("{file}:{line}: cites {p}, which does not exist"))
        .collect()
}

/// The decimal numbers of a text (`0.79`, `1.07`), as written.
fn decimals(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if chars[i].is_ascii_digit() && (i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '.')) {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            let n: String = chars[start..i].iter().collect::<String>().trim_end_matches('.').to_string();
            // One point: a measurement; more: a version or a section number.
            if n.matches('.').count() == 1 {
                out.push(n);
            }
        } else {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '.') {
                i += 1; // the rest of a word such as v1.2 or x86_64
            }
            i += 1;
        }
    }
    out
}

/// Whether `text` holds the number `n` as a whole number (not `0.79` inside `0.7913` or `10.79`).
fn holds_number(text: &str, n: &str) -> bool {
    text.match_indices(n).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let after = text[at + n.len()..].chars().next();
        !before.is_some_and(|c| c.is_ascii_digit() || c == '.') && !after.is_some_and(|c| c.is_ascii_digit())
    })
}

/// In each paragraph or table row that cites a committed file under `experiments/` (a code span or a link),
/// every decimal number must occur in one of the files it cites.
/// Returns the problems and how many numbers were traced.
fn check_numbers(text: &str, path: &Path, repo: &Path) -> (Vec<String>, usize) {
    let file = path.strip_prefix(repo).unwrap_or(path).display().to_string();
    let mut problems = Vec::new();
    let mut traced = 0;
    let prose = prose(text);
    let lines: Vec<&str> = prose.lines().collect();
    // Blocks: each table row alone, else runs of non-empty lines.
    let mut blocks: Vec<(usize, String)> = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, l) in lines.iter().enumerate() {
        if l.trim().is_empty() || l.starts_with('|') {
            blocks.extend(current.take());
            if l.starts_with('|') {
                blocks.push((i + 1, l.to_string()));
            }
        } else {
            let c = current.get_or_insert((i + 1, String::new()));
            c.1.push_str(l);
            c.1.push('\n');
        }
    }
    blocks.extend(current);
    for (line, block) in blocks {
        let mut cited: Vec<PathBuf> =
            code_spans(&block).into_iter().filter_map(|(_, s)| cited_path(&s).map(|p| repo.join(p))).collect();
        cited.extend(
            links(&block).into_iter().map(|(_, t)| path.parent().unwrap().join(t.split('#').next().unwrap_or(""))),
        );
        let text_file = |p: &Path| p.extension().is_some_and(|e| ["md", "csv", "json", "toml"].iter().any(|x| e == *x));
        cited.retain(|p| p.is_file() && text_file(p) && p.starts_with(repo.join("experiments")));
        if cited.is_empty() {
            continue;
        }
        let sources: Vec<String> = cited.iter().map(|p| read(p)).collect();
        for n in decimals(&block) {
            traced += 1;
            if !sources.iter().any(|s| holds_number(s, &n)) {
                let names: Vec<_> =
                    cited.iter().map(|p| p.strip_prefix(repo).unwrap_or(p).display().to_string()).collect();
                problems.push(format!("{file}:{line}: {n} is in none of the files it cites ({})", names.join(", ")));
            }
        }
    }
    (problems, traced)
}

fn report(problems: Vec<String>) {
    assert!(problems.is_empty(), "{} problem(s):\n{}", problems.len(), problems.join("\n"));
}

#[test]
fn every_shown_command_names_a_subcommand_and_its_flags() {
    let mut problems = Vec::new();
    let mut count = 0;
    for d in documents() {
        let rel = d.strip_prefix(root()).unwrap().display().to_string();
        let text = read(&d);
        count += commands(&text, &rel).len();
        problems.extend(check_commands(&text, &rel));
    }
    assert!(count >= 40, "only {count} commands found: is the extraction broken?");
    report(problems);
}

#[test]
fn every_relative_link_and_cited_path_exists() {
    let mut problems = Vec::new();
    let (mut nlinks, mut npaths) = (0, 0);
    for d in documents() {
        let rel = d.strip_prefix(root()).unwrap().display().to_string();
        let text = read(&d);
        nlinks += links(&text).len();
        npaths += code_spans(&prose(&text)).iter().filter(|(_, s)| cited_path(s).is_some()).count();
        problems.extend(check_links(&text, &d, root()));
        problems.extend(check_cited_paths(&text, &rel, root(), d.parent().unwrap()));
    }
    assert!(nlinks >= 50 && npaths >= 50, "only {nlinks} links and {npaths} cited paths found");
    report(problems);
}

#[test]
fn every_number_the_readme_cites_a_file_for_is_in_that_file() {
    let path = root().join("README.md");
    let (problems, traced) = check_numbers(&read(&path), &path, root());
    assert!(traced >= 20, "only {traced} numbers traced: is the README's placement table still citing its files?");
    report(problems);
}

#[test]
fn the_readme_opens_with_the_two_commands_and_ci_runs_the_second() {
    let readme = read(&root().join("README.md"));
    let (_, _, first) = fenced_blocks(&readme).into_iter().next().expect("the README has a fenced block");
    assert_eq!(
        first,
        ["cargo run --release -- render scenes/spheres.pbrt --outfile spheres.exr", "cargo test --release"]
    );
    let ci = read(&root().join(".ci/run"));
    let last = ci.lines().rev().find(|l| !l.trim().is_empty() && !l.starts_with('#')).unwrap();
    assert_eq!(last.trim(), first[1], ".ci/run must end by running the README's test command");
}

/// The README's fenced commands that render or compare, run as shown at 16×16 pixels in a scratch folder.
#[test]
fn the_readme_quick_start_runs() {
    let readme = read(&root().join("README.md"));
    let dir = std::env::temp_dir().join(format!("cachert-docs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut ran = 0;
    for s in commands(&readme, "README.md").into_iter().filter(|s| s.to_copy) {
        if !matches!(s.words[0].as_str(), "render" | "compare") {
            continue;
        }
        let mut args: Vec<String> = Vec::new();
        let mut words = s.words.iter();
        while let Some(w) = words.next() {
            if w == "--resolution" {
                words.next();
                continue;
            }
            args.push(if w.starts_with("scenes/") { root().join(w).display().to_string() } else { w.clone() });
        }
        if s.words[0] == "render" {
            args.extend(["--resolution", "16x16", "--quiet"].map(String::from));
        }
        let out = Command::new(env!("CARGO_BIN_EXE_cachert")).args(&args).current_dir(&dir).output().unwrap();
        assert!(out.status.success(), "{}: cachert {}\n{}", s.at, args.join(" "), String::from_utf8_lossy(&out.stderr));
        ran += 1;
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(ran >= 11, "only {ran} quick-start commands ran");
}

#[cfg(test)]
mod checker {
    use super::*;

    fn problems(snippet: &str) -> Vec<String> {
        check_commands(snippet, "bad.md")
    }

    #[test]
    fn a_made_up_flag_fails() {
        let p = problems("```\ncachert render scenes/room.pbrt --made-up-flag 3\n```\n");
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].contains("bad.md:2") && p[0].contains("--made-up-flag"), "{p:?}");
        // Inline, with placeholders, after a nested subcommand, and on a continuation line.
        assert_eq!(problems("Run `cachert info SCENE.pbrt --verbose`.\n").len(), 1);
        assert_eq!(problems("```\ncachert golden check --dir D --made-up\n```\n").len(), 1);
        assert_eq!(problems("```\ncachert golden add SCENE\n    [--made-up N]\n```\n").len(), 1);
        assert_eq!(problems("```\ntarget/release/cachert render x.pbrt --cropwndow 0,1,0,1\n```\n").len(), 1);
        // A flag of another subcommand is not accepted.
        assert_eq!(problems("```\ncargo run --release -- compare a.exr b.exr --placement im\n```\n").len(), 1);
    }

    #[test]
    fn a_made_up_subcommand_or_a_bad_value_fails() {
        assert_eq!(problems("```\ncachert rendr scenes/room.pbrt\n```\n").len(), 1);
        assert_eq!(problems("```\ncachert render scenes/room.pbrt --placement vgcdgs\n```\n").len(), 1);
        assert_eq!(problems("```\ncachert render scenes/room.pbrt --resolution 10\n```\n").len(), 1);
    }

    #[test]
    fn good_commands_pass() {
        let good = "```\ncachert render SCENE.pbrt --integrator cacheao --placement sd+as --caches N --set KEY=VALUE\n\
                    cachert golden add --dir my [--name NAME] SCENE\n    [--resolution WxH] [--set KEY=VALUE …]\n\
                    cargo run --release -- bench micro flip\n```\n\
                    and `cachert experiment --replot DIR` or `cachert render --help`; not a command: `cachert`.\n";
        assert_eq!(commands(good, "good.md").len(), 5);
        assert!(problems(good).is_empty(), "{:?}", problems(good));
        assert!(problems("```toml\ncachert render x --made-up\n```\n").is_empty(), "a TOML block is not shell");
    }

    #[test]
    fn broken_links_missing_files_and_untraced_numbers_fail() {
        let repo = root();
        let doc = repo.join("docs/bad.md");
        assert_eq!(check_links("[x](nope.md) [ok](placements.md)\n", &doc, repo).len(), 1);
        assert_eq!(check_links("[x](placements.md#no-such-heading)\n", &doc, repo).len(), 1);
        assert!(check_links("[x](placements.md#placements) <img src=\"report.png\">\n", &doc, repo).is_empty());
        assert_eq!(check_links("<img src=\"nope.png\">\n", &doc, repo).len(), 1);
        assert_eq!(
            check_cited_paths("see `src/nope.rs:12` and `src/lib.rs`\n", "bad.md", repo, &repo.join("docs")).len(),
            1
        );
        let readme = repo.join("README.md");
        let table = "| x | 0.79 / 0.92 | `experiments/results/ao/tables.md` |\n";
        assert_eq!(check_numbers(table, &readme, repo), (vec![], 2));
        let made_up = "| x | 0.7913 / 0.92 | `experiments/results/ao/tables.md` |\n";
        assert_eq!(check_numbers(made_up, &readme, repo).0.len(), 1);
        let linked = "Ratios 0.79 and 0.7913 ([tables](experiments/results/ao/tables.md)).\n";
        assert_eq!(check_numbers(linked, &readme, repo).0.len(), 1);
        assert_eq!(decimals("0.79+ / 1.01-, 13333 caches, v1.2 and 1.2.3, 0.5."), ["0.79", "1.01", "0.5"]);
        assert!(
            holds_number("a 0.79+ b", "0.79") && !holds_number("a 0.7913 b", "0.79") && !holds_number("10.79", "0.79")
        );
    }
}
