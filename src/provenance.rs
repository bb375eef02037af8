//! LAYER 0 (system probe): where this binary's code came from: the commit of the source tree it was built
//! from, and whether that tree has uncommitted changes to the code (`src/`, `Cargo.toml`, `Cargo.lock`).
//! `golden update` and `golden add` refuse to record from a tree with such changes unless asked
//! (`--allow-dirty`), and then the recorded commit says `-dirty`: a golden must name code someone can check
//! out. A rendered EXR records the same commit in its header.
//!
//! Depends on `git` being on the PATH; without it, or without the source tree (an installed binary), the
//! provenance is unknown and nothing is refused.

use std::path::Path;
use std::process::Command;

/// The paths of the source tree whose changes change an image.
pub const CODE_PATHS: [&str; 3] = ["src", "Cargo.toml", "Cargo.lock"];

/// The state of a source tree.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Provenance {
    /// A git checkout whose code paths match the commit (`git describe --always`, 12 hex digits).
    Clean(String),
    /// A git checkout with uncommitted changes to its code paths: the commit and the changed paths as
    /// `git status --porcelain` lists them.
    Dirty(String, Vec<String>),
    /// Not a git checkout, or git is missing.
    Unknown,
}

impl Provenance {
    /// What to record as a golden's commit: the commit, with `-dirty` when the code had changes.
    pub fn commit(&self) -> String {
        match self {
            Provenance::Clean(c) => c.clone(),
            Provenance::Dirty(c, _) => format!("{c}-dirty"),
            Provenance::Unknown => "unknown".to_string(),
        }
    }
}

/// Runs git in `repo` and returns its standard output, or `None` when it fails.
fn git(repo: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git").arg("-C").arg(repo).args(args).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The provenance of the source tree at `repo` (its top folder).
pub fn of(repo: &Path) -> Provenance {
    let Some(commit) = git(repo, &["describe", "--always", "--abbrev=12"]).map(|s| s.trim().to_string()) else {
        return Provenance::Unknown;
    };
    let mut args = vec!["status", "--porcelain", "--untracked-files=all", "--"];
    args.extend(CODE_PATHS);
    match git(repo, &args) {
        Some(s) if s.trim().is_empty() => Provenance::Clean(commit),
        Some(s) => Provenance::Dirty(commit, s.lines().map(str::to_string).collect()),
        None => Provenance::Unknown,
    }
}

/// The provenance of the tree this binary was built from.
pub fn of_this_build() -> Provenance {
    of(Path::new(env!("CARGO_MANIFEST_DIR")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(repo: &Path, args: &[&str]) {
        let ok = Command::new("git").arg("-C").arg(repo).args(args).output().unwrap().status.success();
        assert!(ok, "git {args:?}");
    }

    #[test]
    fn changes_to_the_code_make_a_tree_dirty_and_other_changes_do_not() {
        if Command::new("git").arg("--version").output().is_err() {
            panic!("git is needed by this test (and by golden update's provenance)");
        }
        let repo = std::env::temp_dir().join(format!("cachert-provenance-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&repo);
        std::fs::create_dir_all(repo.join("src")).unwrap();
        assert_eq!(of(&repo), Provenance::Unknown);
        run(&repo, &["init", "-q"]);
        std::fs::write(repo.join("src/lib.rs"), "// one\n").unwrap();
        std::fs::write(repo.join("README.md"), "one\n").unwrap();
        run(&repo, &["add", "."]);
        run(&repo, &["-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "one"]);
        let Provenance::Clean(commit) = of(&repo) else { panic!("{:?}", of(&repo)) };
        assert_eq!(commit.len(), 12);
        // A document or a golden changing leaves the code clean.
        std::fs::write(repo.join("README.md"), "two\n").unwrap();
        assert_eq!(of(&repo), Provenance::Clean(commit.clone()));
        // A changed or a new source file makes it dirty, and the recorded commit says so.
        std::fs::write(repo.join("src/lib.rs"), "// two\n").unwrap();
        std::fs::write(repo.join("src/new.rs"), "\n").unwrap();
        let p = of(&repo);
        assert!(matches!(&p, Provenance::Dirty(c, files) if *c == commit && files.len() == 2), "{p:?}");
        assert_eq!(p.commit(), format!("{commit}-dirty"));
        std::fs::remove_dir_all(&repo).unwrap();
    }
}
