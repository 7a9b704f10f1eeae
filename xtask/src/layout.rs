//! `cargo xtask layout`: keeps the code layout of issue 15 true. Fails when
//! a file under `crates/*/src` or `xtask/src` has more than
//! [`MAX_FILE_LINES`] lines, a function outside test code has more than
//! [`MAX_FN_LINES`] lines, or files of one crate import each other (a cycle
//! in the graph of `use crate::…` / `super::…` / `self::…` paths and
//! relative `use child::…`, each path resolved to the file of the deepest
//! module it names), or a text file anywhere in the repository still holds
//! merge-conflict markers ([`crate::markers`]). A re-export (`pub use child::X` in a `mod.rs` façade)
//! is the module's surface, not an import, unless the file itself uses `X`.
//!
//! A small tokenizer (comments, strings, chars and lifetimes told apart)
//! is enough: items under `#[cfg(test)]` or `#[test]` are skipped, a
//! function runs from its `fn` line to its closing brace.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// Longest file allowed, in lines.
pub const MAX_FILE_LINES: usize = 800;
/// Longest non-test function allowed, in lines (`fn` to closing brace).
pub const MAX_FN_LINES: usize = 120;

pub fn run(args: &[String]) -> Result<()> {
    if let Some(a) = args.first() {
        bail!("layout takes no arguments (got {a:?})");
    }
    let root = crate::workspace_root();
    let problems = check_workspace(&root)?;
    if problems.is_empty() {
        println!(
            "layout: ok (files ≤ {MAX_FILE_LINES} lines, functions ≤ {MAX_FN_LINES} lines, \
             no module cycles, no merge-conflict markers)"
        );
        return Ok(());
    }
    for p in &problems {
        println!("layout: {p}");
    }
    bail!("{} layout problem(s)", problems.len())
}

/// Every problem of every crate under `root`, as one line each.
pub fn check_workspace(root: &Path) -> Result<Vec<String>> {
    let mut src_dirs = vec![root.join("xtask/src")];
    let crates = root.join("crates");
    let mut entries: Vec<PathBuf> = fs::read_dir(&crates)
        .with_context(|| format!("reading {}", crates.display()))?
        .filter_map(|e| e.ok().map(|e| e.path().join("src")))
        .filter(|p| p.is_dir())
        .collect();
    entries.sort();
    src_dirs.extend(entries);
    let mut problems = Vec::new();
    for dir in src_dirs {
        let mut files = Vec::new();
        rust_files(&dir, &mut files)?;
        files.sort();
        let mut parsed = Vec::with_capacity(files.len());
        for path in files {
            let text =
                fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
            let rel = path.strip_prefix(root).unwrap_or(&path).to_path_buf();
            let module = module_of(path.strip_prefix(&dir).unwrap_or(&path));
            parsed.push(scan(&rel, module, &text));
        }
        problems.extend(size_problems(&parsed));
        problems.extend(cycle_problems(&parsed));
    }
    problems.extend(crate::markers::marker_problems(root)?);
    Ok(problems)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for entry in fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        if path.is_dir() {
            rust_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

/// The module path of a file relative to its crate's `src/`: `lib.rs` and
/// `main.rs` are the root, `a/mod.rs` and `a.rs` are `a`, `a/b.rs` is `a::b`.
/// Other binaries (`src/bin/x.rs`) count as modules of their own.
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if let Some(last) = parts.pop() {
        let stem = last.strip_suffix(".rs").unwrap_or(&last).to_string();
        let root_file = parts.is_empty() && (stem == "lib" || stem == "main");
        if stem != "mod" && !root_file {
            parts.push(stem);
        }
    }
    parts
}

/// What the checks need of one file.
#[derive(Debug)]
pub struct Scanned {
    path: PathBuf,
    module: Vec<String>,
    lines: usize,
    /// Non-test functions: (name, first line, length in lines).
    functions: Vec<(String, usize, usize)>,
    /// Absolute module paths this file refers to (not yet resolved to files).
    imports: Vec<Vec<String>>,
}

fn size_problems(files: &[Scanned]) -> Vec<String> {
    let mut out = Vec::new();
    for f in files {
        if f.lines > MAX_FILE_LINES {
            out.push(format!(
                "{}: {} lines (at most {MAX_FILE_LINES})",
                f.path.display(),
                f.lines
            ));
        }
        for (name, line, len) in &f.functions {
            if *len > MAX_FN_LINES {
                out.push(format!(
                    "{}:{line}: fn {name} has {len} lines (at most {MAX_FN_LINES})",
                    f.path.display()
                ));
            }
        }
    }
    out
}

/// Import cycles between the files of one crate, one problem per cycle
/// (strongly connected component of more than one file).
fn cycle_problems(files: &[Scanned]) -> Vec<String> {
    let by_module: BTreeMap<&[String], usize> = files
        .iter()
        .enumerate()
        .map(|(i, f)| (f.module.as_slice(), i))
        .collect();
    let edges: Vec<Vec<usize>> = files
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut to: Vec<usize> = f
                .imports
                .iter()
                .filter_map(|path| {
                    (0..=path.len())
                        .rev()
                        .find_map(|n| by_module.get(&path[..n]).copied())
                })
                .filter(|&j| j != i)
                .collect();
            to.sort_unstable();
            to.dedup();
            to
        })
        .collect();
    strongly_connected(&edges)
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| {
            let names: Vec<String> = c
                .iter()
                .map(|&i| files[i].path.display().to_string())
                .collect();
            let why: Vec<String> = c
                .iter()
                .flat_map(|&i| {
                    edges[i].iter().filter(|j| c.contains(j)).map(move |&j| {
                        format!("{} → {}", files[i].path.display(), files[j].path.display())
                    })
                })
                .collect();
            format!(
                "module cycle between {} ({})",
                names.join(", "),
                why.join("; ")
            )
        })
        .collect()
}

/// Tarjan's algorithm, iterative; components in discovery order, each sorted.
fn strongly_connected(edges: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let n = edges.len();
    let (mut index, mut low) = (vec![usize::MAX; n], vec![0; n]);
    let mut on_stack = vec![false; n];
    let (mut stack, mut out, mut next) = (Vec::new(), Vec::new(), 0);
    for start in 0..n {
        if index[start] != usize::MAX {
            continue;
        }
        let mut call = vec![(start, 0usize)];
        index[start] = next;
        low[start] = next;
        next += 1;
        stack.push(start);
        on_stack[start] = true;
        while let Some(&mut (v, ref mut e)) = call.last_mut() {
            if let Some(&w) = edges[v].get(*e) {
                *e += 1;
                if index[w] == usize::MAX {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    call.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            call.pop();
            if let Some(&(parent, _)) = call.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut comp = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w] = false;
                    comp.push(w);
                    if w == v {
                        break;
                    }
                }
                comp.sort_unstable();
                out.push(comp);
            }
        }
    }
    out
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    Punct(char),
}

/// Tokens with their line numbers; comments, string and char literals and
/// lifetimes dropped (a lifetime's name is never a path).
fn tokenize(text: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = text.chars().collect();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    let skip_to = |i: &mut usize, line: &mut usize, end: usize| {
        *line += c[*i..end.min(c.len())]
            .iter()
            .filter(|&&x| x == '\n')
            .count();
        *i = end;
    };
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied();
        if ch == '/' && next == Some('/') {
            let end = (i..c.len()).find(|&k| c[k] == '\n').unwrap_or(c.len());
            skip_to(&mut i, &mut line, end);
        } else if ch == '/' && next == Some('*') {
            let end = block_comment_end(&c, i);
            skip_to(&mut i, &mut line, end);
        } else if ch == '"' {
            let end = string_end(&c, i + 1, 0);
            skip_to(&mut i, &mut line, end);
        } else if (ch == 'r' || ch == 'b') && raw_string_start(&c, i).is_some() {
            let (open, hashes) = raw_string_start(&c, i).unwrap_or((i, 0));
            let end = string_end(&c, open + 1, hashes);
            skip_to(&mut i, &mut line, end);
        } else if ch == 'b' && next == Some('\'') {
            let end = char_end(&c, i + 1);
            skip_to(&mut i, &mut line, end);
        } else if ch == '\'' {
            let lifetime =
                next.is_some_and(|n| n.is_alphabetic() || n == '_') && c.get(i + 2) != Some(&'\'');
            if lifetime {
                i += 1;
                while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                    i += 1;
                }
            } else {
                let end = char_end(&c, i);
                skip_to(&mut i, &mut line, end);
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push((Tok::Ident(c[start..i].iter().collect()), line));
        } else if ch.is_ascii_digit() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_' || c[i] == '.') {
                i += 1;
            }
        } else {
            if ch == '\n' {
                line += 1;
            } else if !ch.is_whitespace() {
                out.push((Tok::Punct(ch), line));
            }
            i += 1;
        }
    }
    out
}

fn block_comment_end(c: &[char], start: usize) -> usize {
    let (mut depth, mut i) = (0usize, start);
    while i + 1 < c.len() {
        if c[i] == '/' && c[i + 1] == '*' {
            depth += 1;
            i += 2;
        } else if c[i] == '*' && c[i + 1] == '/' {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            i += 1;
        }
    }
    c.len()
}

/// `r"`, `r#"`, `br"`, `br#"`: the index of the opening quote and the
/// number of `#`.
fn raw_string_start(c: &[char], i: usize) -> Option<(usize, usize)> {
    let mut k = i;
    if c.get(k) == Some(&'b') {
        k += 1;
        if c.get(k) == Some(&'"') {
            return Some((k, 0)); // b"…": an ordinary string with escapes
        }
    }
    if c.get(k) != Some(&'r') {
        return None;
    }
    if i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_') {
        return None;
    }
    k += 1;
    let hashes = c[k..].iter().take_while(|&&x| x == '#').count();
    (c.get(k + hashes) == Some(&'"')).then_some((k + hashes, hashes))
}

/// The index after the string whose contents start at `i` (escapes apply
/// when `hashes == 0`; raw strings end at `"` followed by `hashes` `#`).
fn string_end(c: &[char], mut i: usize, hashes: usize) -> usize {
    while i < c.len() {
        if c[i] == '\\' && hashes == 0 {
            i += 2;
        } else if c[i] == '"'
            && c[i + 1..]
                .iter()
                .take(hashes)
                .filter(|&&x| x == '#')
                .count()
                == hashes
        {
            return i + 1 + hashes;
        } else {
            i += 1;
        }
    }
    c.len()
}

/// The index after the char literal whose opening quote is at `i`.
fn char_end(c: &[char], i: usize) -> usize {
    let mut k = i + 1;
    if c.get(k) == Some(&'\\') {
        k += 2;
    } else {
        k += 1;
    }
    while k < c.len() && c[k] != '\'' {
        k += 1;
    }
    (k + 1).min(c.len())
}

/// The index after the item starting at token `i`: through its matching
/// `}` or its `;`, whichever comes first at nesting depth 0.
fn item_end(toks: &[(Tok, usize)], i: usize) -> usize {
    let mut depth = 0i64;
    for (k, (t, _)) in toks.iter().enumerate().skip(i) {
        match t {
            Tok::Punct('{') | Tok::Punct('(') | Tok::Punct('[') => depth += 1,
            Tok::Punct('}') | Tok::Punct(')') | Tok::Punct(']') => {
                depth -= 1;
                if depth == 0 && *t == Tok::Punct('}') {
                    return k + 1;
                }
            }
            Tok::Punct(';') if depth == 0 => return k + 1,
            _ => {}
        }
    }
    toks.len()
}

fn ident(toks: &[(Tok, usize)], i: usize) -> Option<&str> {
    match toks.get(i) {
        Some((Tok::Ident(s), _)) => Some(s),
        _ => None,
    }
}

fn punct(toks: &[(Tok, usize)], i: usize, ch: char) -> bool {
    matches!(toks.get(i), Some((Tok::Punct(p), _)) if *p == ch)
}

fn path_sep(toks: &[(Tok, usize)], i: usize) -> bool {
    punct(toks, i, ':') && punct(toks, i + 1, ':')
}

/// Scans one file: its length, its non-test functions and the modules its
/// paths name.
pub fn scan(path: &Path, module: Vec<String>, text: &str) -> Scanned {
    let toks = tokenize(text);
    let mut s = Scanned {
        path: path.to_path_buf(),
        lines: text.lines().count(),
        module,
        functions: Vec::new(),
        imports: Vec::new(),
    };
    // Inline modules: (module path, token index where it ends).
    let mut inline: Vec<(Vec<String>, usize)> = Vec::new();
    // `pub use` paths with the name they bind, and the token ranges of
    // `use` statements.
    let mut reexports: Vec<(Vec<String>, Option<String>)> = Vec::new();
    let mut in_use: Vec<std::ops::Range<usize>> = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        while inline.last().is_some_and(|(_, end)| i >= *end) {
            inline.pop();
        }
        let here = inline.last().map_or(&s.module, |(m, _)| m).clone();
        if punct(&toks, i, '#') && punct(&toks, i + 1, '[') {
            let close = item_end(&toks, i + 1);
            let attr: Vec<&str> = (i + 2..close).filter_map(|k| ident(&toks, k)).collect();
            let test = attr == ["test"]
                || (attr.first() == Some(&"cfg")
                    && attr.contains(&"test")
                    && !attr.contains(&"not"));
            i = if test { item_end(&toks, close) } else { close };
            continue;
        }
        match ident(&toks, i) {
            Some("fn") if ident(&toks, i + 1).is_some() => {
                let end = item_end(&toks, i);
                let last = toks[end.saturating_sub(1).max(i)].1;
                if punct(&toks, end.saturating_sub(1), '}') {
                    let name = ident(&toks, i + 1).unwrap_or_default().to_string();
                    s.functions.push((name, toks[i].1, last - toks[i].1 + 1));
                }
                i += 2;
            }
            Some("mod") if ident(&toks, i + 1).is_some() && punct(&toks, i + 2, '{') => {
                let mut m = here.clone();
                m.push(ident(&toks, i + 1).unwrap_or_default().to_string());
                inline.push((m, item_end(&toks, i)));
                i += 3;
            }
            Some("use") => {
                let end = item_end(&toks, i);
                let mut paths = Vec::new();
                use_tree(&toks[i + 1..end], &here, &mut paths);
                if is_pub(&toks, i) {
                    reexports.extend(paths);
                } else {
                    s.imports.extend(paths.into_iter().map(|(p, _)| p));
                }
                in_use.push(i..end);
                i = end;
            }
            Some("crate" | "super" | "self") if path_sep(&toks, i + 1) => {
                let (segments, next) = path_at(&toks, i);
                if let Some(abs) = absolute(&segments, &here) {
                    s.imports.push(abs);
                }
                i = next;
            }
            _ => i += 1,
        }
    }
    // A re-export is the module's surface, not a dependency, unless the
    // file itself uses the name it binds (globs: never).
    let mut used = std::collections::BTreeSet::new();
    let mut ranges = in_use.iter().peekable();
    for (k, (t, _)) in toks.iter().enumerate() {
        while ranges.peek().is_some_and(|r| r.end <= k) {
            ranges.next();
        }
        if let (Tok::Ident(name), false) = (t, ranges.peek().is_some_and(|r| r.contains(&k))) {
            used.insert(name.as_str());
        }
    }
    for (path, name) in reexports {
        if name.is_some_and(|n| used.contains(n.as_str())) {
            s.imports.push(path);
        }
    }
    s
}

/// Whether the `use` at token `i` is `pub`, `pub(crate)`, `pub(super)` or
/// `pub(in …)`.
fn is_pub(toks: &[(Tok, usize)], i: usize) -> bool {
    if i >= 1 && ident(toks, i - 1) == Some("pub") {
        return true;
    }
    if i == 0 || !punct(toks, i - 1, ')') {
        return false;
    }
    (i.saturating_sub(8)..i - 1)
        .rev()
        .find(|&k| punct(toks, k, '('))
        .is_some_and(|k| k >= 1 && ident(toks, k - 1) == Some("pub"))
}

/// The path `a::b::c` starting at token `i`, and the index after it.
fn path_at(toks: &[(Tok, usize)], mut i: usize) -> (Vec<String>, usize) {
    let mut segments = Vec::new();
    while let Some(name) = ident(toks, i) {
        segments.push(name.to_string());
        if !path_sep(toks, i + 1) {
            return (segments, i + 1);
        }
        i += 3;
    }
    (segments, i)
}

/// `segments` made absolute from module `here`: `crate::…`, `super::…`,
/// `self::…`; `None` for paths into other crates.
fn absolute(segments: &[String], here: &[String]) -> Option<Vec<String>> {
    let mut base: Vec<String> = here.to_vec();
    let mut rest = segments;
    match rest.first().map(String::as_str) {
        Some("crate") => {
            base.clear();
            rest = &rest[1..];
        }
        Some("super") | Some("self") => {
            while let Some(first) = rest.first() {
                match first.as_str() {
                    "super" => {
                        base.pop()?;
                    }
                    "self" => {}
                    _ => break,
                }
                rest = &rest[1..];
            }
        }
        _ => return None,
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// Paths of a `use` tree with the name each binds (`None` for a glob).
type UsePaths = Vec<(Vec<String>, Option<String>)>;

/// The paths of a `use` tree (tokens after `use`, up to and including `;`):
/// `crate` / `super` / `self` ones, and relative ones (`use child::X`,
/// resolved against `here`; external crates resolve to no file).
fn use_tree(toks: &[(Tok, usize)], here: &[String], out: &mut UsePaths) {
    fn walk(
        toks: &[(Tok, usize)],
        i: &mut usize,
        prefix: Vec<String>,
        here: &[String],
        out: &mut UsePaths,
    ) {
        let mut path = prefix;
        let mut alias = None;
        let mut glob = false;
        loop {
            if punct(toks, *i, ':') && punct(toks, *i + 1, ':') {
                *i += 2;
                continue;
            }
            if punct(toks, *i, '{') {
                *i += 1;
                while *i < toks.len() && !punct(toks, *i, '}') {
                    walk(toks, i, path.clone(), here, out);
                    if punct(toks, *i, ',') {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            match ident(toks, *i) {
                Some("as") => {
                    alias = ident(toks, *i + 1).map(String::from);
                    *i += 2;
                }
                Some(name) => {
                    path.push(name.to_string());
                    *i += 1;
                    continue;
                }
                None if punct(toks, *i, '*') => {
                    glob = true;
                    *i += 1;
                }
                None => {}
            }
            break;
        }
        let binding = match (glob, alias) {
            (true, _) => None,
            (false, Some(a)) => Some(a),
            (false, None) => path.iter().rev().find(|s| *s != "self").cloned(),
        };
        let full = match path.first().map(String::as_str) {
            Some("crate" | "super" | "self") => absolute(&path, here),
            Some(_) => {
                let mut p = here.to_vec();
                p.extend(path);
                Some(p)
            }
            None => None,
        };
        out.extend(full.map(|p| (p, binding)));
    }
    let mut i = 0;
    if punct(toks, 0, ':') {
        return; // `use ::extern_crate::…`
    }
    walk(toks, &mut i, Vec::new(), here, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scanned(module: &[&str], text: &str) -> Scanned {
        scan(
            Path::new("x.rs"),
            module.iter().map(|s| s.to_string()).collect(),
            text,
        )
    }

    #[test]
    fn function_lengths_skip_tests_strings_and_comments() {
        let long_body = "    let x = 1;\n".repeat(130);
        let text = format!(
            "fn short() {{\n    let s = \"}} {{ fn fake() {{\";\n    // }} fn no() {{\n}}\n\
             fn long<'a>(c: char) -> &'a str {{\n    let _ = '}}';\n{long_body}    \"\"\n}}\n\
             #[cfg(test)]\nmod tests {{\n    fn also_long() {{\n{long_body}    }}\n}}\n\
             #[test]\nfn a_test() {{\n{long_body}}}\n"
        );
        let s = scanned(&[], &text);
        let fns: Vec<(&str, usize)> = s.functions.iter().map(|f| (f.0.as_str(), f.2)).collect();
        assert_eq!(fns, vec![("short", 4), ("long", 134)]);
        assert_eq!(size_problems(&[s]).len(), 1);
    }

    #[test]
    fn imports_resolve_use_trees_and_inline_paths() {
        let text = "use crate::a::{b::C, d};\nuse super::e::*;\nuse child::F as G;\n\
                    use std::fmt;\nfn f() { self::g::h(); crate::k::l(); }\n";
        let s = scanned(&["m", "n"], text);
        let text =
            "pub use a::Used;\npub use b::Unused;\npub(crate) use c::*;\nfn f() -> Used {}\n";
        let r = scanned(&[], text);
        assert_eq!(r.imports, vec![vec!["a".to_string(), "Used".to_string()]]);
        let want: Vec<Vec<&str>> = vec![
            vec!["a", "b", "C"],
            vec!["a", "d"],
            vec!["m", "e"],
            vec!["m", "n", "child", "F"],
            vec!["m", "n", "std", "fmt"],
            vec!["m", "n", "g", "h"],
            vec!["k", "l"],
        ];
        assert_eq!(s.imports, want);
    }

    #[test]
    fn cycles_are_found_and_trees_pass() {
        let files = [
            scanned(&[], "mod a;\nmod b;\nuse a::X;\n"),
            scanned(&["a"], "use super::b::Y;\n"),
            scanned(&["b"], "pub struct Y;\n"),
        ];
        assert!(cycle_problems(&files).is_empty());
        let files = [
            scanned(&[], "mod a;\nmod b;\n"),
            scanned(&["a"], "use crate::b::Y;\npub struct X;\n"),
            scanned(&["b"], "pub struct Y;\nfn f() -> super::a::X { todo!() }\n"),
        ];
        let problems = cycle_problems(&files);
        assert_eq!(problems.len(), 1, "{problems:?}");
        // a parent that only re-exports a child that uses the parent: no
        // cycle; once the parent uses what it re-exports: a cycle
        let mut files = [
            scanned(&["p"], "mod c;\npub use c::Z;\npub struct W;\n"),
            scanned(&["p", "c"], "use super::W;\npub struct Z;\n"),
        ];
        assert!(cycle_problems(&files).is_empty());
        files[0] = scanned(&["p"], "mod c;\npub use c::Z;\npub struct W(Z);\n");
        assert_eq!(cycle_problems(&files).len(), 1);
    }

    #[test]
    fn module_paths_of_files() {
        assert!(module_of(Path::new("lib.rs")).is_empty());
        assert!(module_of(Path::new("main.rs")).is_empty());
        assert_eq!(module_of(Path::new("a/mod.rs")), ["a"]);
        assert_eq!(module_of(Path::new("a/b.rs")), ["a", "b"]);
    }
}
