//! Merge-conflict markers left in the repository's text files: a rebase resolved by hand
//! that kept a `<<<<<<<` … `>>>>>>>` block (it happened once, in docs/quality.md).
//! `cargo xtask layout` fails on them. A file is flagged when it has a line opening a
//! conflict and a line closing one (`=======` alone is a Markdown heading underline).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Folders never searched: build output, installed packages, git's own store.
const SKIPPED_DIRS: [&str; 3] = ["target", "node_modules", ".git"];
/// Files larger than this are data, not text someone edits by hand.
const MAX_TEXT_BYTES: u64 = 4 << 20;

/// One line per file under `root` that holds a conflict block: `path:line: …`.
pub fn marker_problems(root: &Path) -> Result<Vec<String>> {
    let mut files = Vec::new();
    text_candidates(root, &mut files)?;
    files.sort();
    let mut problems = Vec::new();
    for path in files {
        let Ok(bytes) = fs::read(&path) else { continue };
        let Ok(text) = String::from_utf8(bytes) else {
            continue;
        };
        if let Some(line) = conflict_line(&text) {
            let rel = path.strip_prefix(root).unwrap_or(&path);
            problems.push(format!(
                "{}:{line}: merge-conflict markers (<<<<<<< … >>>>>>>) left in the file",
                rel.display()
            ));
        }
    }
    Ok(problems)
}

fn text_candidates(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for entry in fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let entry = entry.with_context(|| format!("reading {}", dir.display()))?;
        let path = entry.path();
        let kind = entry.file_type()?;
        if kind.is_dir() {
            let name = entry.file_name();
            if !SKIPPED_DIRS.iter().any(|s| name == *s) {
                text_candidates(&path, out)?;
            }
        } else if kind.is_file() && entry.metadata()?.len() <= MAX_TEXT_BYTES {
            out.push(path);
        }
    }
    Ok(())
}

/// The 1-based line of the first opening marker, when a closing marker follows it.
fn conflict_line(text: &str) -> Option<usize> {
    let is = |line: &str, marker: &str| line == marker || line.starts_with(&format!("{marker} "));
    let open = text.lines().position(|l| is(l, "<<<<<<<"))?;
    text.lines()
        .skip(open + 1)
        .any(|l| is(l, ">>>>>>>"))
        .then_some(open + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_conflict_block_is_found_and_lookalikes_are_not() {
        let block = "intro\n<<<<<<< HEAD\nours\n=======\ntheirs\n>>>>>>> 022d6c4 (docs)\nend\n";
        assert_eq!(conflict_line(block), Some(2));
        assert_eq!(conflict_line("<<<<<<<\na\n>>>>>>>\n"), Some(1));
        // A Markdown heading underline, an opening without a close, quoted markers.
        assert_eq!(conflict_line("Title\n=======\ntext\n"), None);
        assert_eq!(conflict_line("<<<<<<< HEAD\nnothing closes\n"), None);
        assert_eq!(conflict_line("  \"<<<<<<< x\"\n  \">>>>>>> y\"\n"), None);
        assert_eq!(conflict_line(">>>>>>> before\n<<<<<<< after\n"), None);
    }

    #[test]
    fn files_with_markers_are_named_and_build_output_is_skipped() {
        let root = tempfile::tempdir().expect("temporary folder");
        let docs = root.path().join("docs");
        let target = root.path().join("target");
        fs::create_dir_all(&docs).expect("docs folder");
        fs::create_dir_all(&target).expect("target folder");
        let block = "a\n<<<<<<< HEAD\nb\n=======\nc\n>>>>>>> other\n";
        fs::write(docs.join("quality.md"), block).expect("write");
        fs::write(docs.join("clean.md"), "Title\n=======\n").expect("write");
        fs::write(target.join("log.txt"), block).expect("write");
        fs::write(docs.join("mesh.bin"), [0xffu8, 0xfe, 0x00, 0x3c]).expect("write");
        let problems = marker_problems(root.path()).expect("scan");
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(
            problems[0].starts_with("docs/quality.md:2:"),
            "{problems:?}"
        );
    }
}
