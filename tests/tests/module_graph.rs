//! The modules of `dsp` and `xtask` import each other without cycles.
//!
//! Within every module directory (a crate's `src/`, or a directory of submodules), each sibling
//! module is a node, and module `a` depends on its sibling `b` when code in `a` (comments aside)
//! names `b` through the directory's path: `crate::…::b`, or `super::b` from `a`'s own file
//! (`super::super::b` one directory down). A parent's items reached with `super::` are not an
//! edge: the parent is the namespace its children live in. The graph of every directory must be
//! acyclic.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The crates whose source trees are checked, relative to the workspace root.
const CRATES: [&str; 2] = ["dsp/src", "xtask/src"];

/// One module of a directory: its name and its files, each with its depth below the directory
/// (0 for `name.rs` and `name/mod.rs`, 1 for `name/x.rs`, and so on).
struct Module {
    name: String,
    files: Vec<(PathBuf, usize)>,
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ lies in the workspace").to_owned()
}

/// Every `.rs` file under `dir`, with its depth below `dir` as a module (see [`Module`]).
fn files_under(dir: &Path, depth: usize, out: &mut Vec<(PathBuf, usize)>) {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files_under(&path, depth + 1, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let own = path.file_name().is_some_and(|n| n == "mod.rs");
            out.push((path, if own { depth.saturating_sub(1) } else { depth }));
        }
    }
}

/// The sibling modules of directory `dir`.
fn modules(dir: &Path) -> Vec<Module> {
    let mut by_name: BTreeMap<String, Vec<(PathBuf, usize)>> = BTreeMap::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            // `name/mod.rs` sits at depth 0, `name/x.rs` at depth 1.
            files_under(&path, 1, by_name.entry(stem).or_default());
        } else if path.extension().is_some_and(|e| e == "rs") && !["mod", "lib", "main"].contains(&stem.as_str()) {
            by_name.entry(stem).or_default().push((path, 0));
        }
    }
    by_name.into_iter().map(|(name, files)| Module { name, files }).collect()
}

/// Every directory of `src` that holds modules, with its module path (`crate`, `crate::scene`, …).
fn module_dirs(src: &Path, path: &str, out: &mut Vec<(PathBuf, String)>) {
    out.push((src.to_owned(), path.to_owned()));
    let mut dirs: Vec<PathBuf> = fs::read_dir(src).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()).collect();
    dirs.sort();
    for dir in dirs {
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        module_dirs(&dir, &format!("{path}::{name}"), out);
    }
}

/// The code of a file: every line outside comments (line comments and doc comments dropped).
fn code(text: &str) -> String {
    text.lines()
        .map(|line| match line.find("//") {
            // A `//` inside a string literal (a URL, say) keeps its line.
            Some(i) if line[..i].matches('"').count() % 2 == 0 => &line[..i],
            _ => line,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The names `code` reaches right after `prefix::`: `prefix::name` and each top-level entry of
/// `prefix::{a, b::c, …}`.
fn names_after(code: &str, prefix: &str) -> Vec<String> {
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    let needle = format!("{prefix}::");
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = code[from..].find(&needle) {
        let at = from + i;
        from = at + needle.len();
        // Only whole path segments: `crate::x` but not `my_crate::x`, `super::x` but not `super::super::x`
        // when the prefix is `super`.
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let rest = &code[from..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0usize;
            let mut entry_start = true;
            for (j, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => entry_start = true,
                    c if c.is_whitespace() => {}
                    _ if entry_start && depth == 0 => {
                        out.push(ident(&group[j..]));
                        entry_start = false;
                    }
                    _ => {}
                }
            }
        } else {
            out.push(ident(rest));
        }
    }
    out
}

/// A cycle of the dependency graph `edges` (node indices), if there is one.
fn find_cycle(edges: &[Vec<usize>]) -> Option<Vec<usize>> {
    // 0: unvisited, 1: on the current path, 2: done.
    fn visit(n: usize, edges: &[Vec<usize>], state: &mut [u8], path: &mut Vec<usize>) -> Option<Vec<usize>> {
        state[n] = 1;
        path.push(n);
        for &m in &edges[n] {
            if state[m] == 1 {
                let start = path.iter().position(|&p| p == m).unwrap();
                let mut cycle = path[start..].to_vec();
                cycle.push(m);
                return Some(cycle);
            }
            if state[m] == 0
                && let Some(cycle) = visit(m, edges, state, path)
            {
                return Some(cycle);
            }
        }
        path.pop();
        state[n] = 2;
        None
    }
    let mut state = vec![0u8; edges.len()];
    (0..edges.len()).find_map(|n| if state[n] == 0 { visit(n, edges, &mut state, &mut Vec::new()) } else { None })
}

/// The dependency graph of the sibling modules of `dir` (module path `path`).
fn graph(dir: &Path, path: &str) -> (Vec<String>, Vec<Vec<usize>>) {
    let mods = modules(dir);
    let index: BTreeMap<&str, usize> = mods.iter().enumerate().map(|(i, m)| (m.name.as_str(), i)).collect();
    let mut edges = vec![Vec::new(); mods.len()];
    for (a, module) in mods.iter().enumerate() {
        for (file, depth) in &module.files {
            let text = code(&fs::read_to_string(file).unwrap());
            let supers = vec!["super"; depth + 1].join("::");
            for prefix in [path, supers.as_str()] {
                for name in names_after(&text, prefix) {
                    if let Some(&b) = index.get(name.as_str())
                        && b != a
                        && !edges[a].contains(&b)
                    {
                        edges[a].push(b);
                    }
                }
            }
        }
    }
    (mods.into_iter().map(|m| m.name).collect(), edges)
}

#[test]
fn module_imports_have_no_cycles() {
    let root = workspace_root();
    let mut cycles = Vec::new();
    let mut checked = 0;
    for krate in CRATES {
        let mut dirs = Vec::new();
        module_dirs(&root.join(krate), "crate", &mut dirs);
        for (dir, path) in dirs {
            let (names, edges) = graph(&dir, &path);
            checked += names.len();
            if let Some(cycle) = find_cycle(&edges) {
                let cycle: Vec<&str> = cycle.iter().map(|&i| names[i].as_str()).collect();
                cycles.push(format!("{}: {}", dir.strip_prefix(&root).unwrap().display(), cycle.join(" -> ")));
            }
        }
    }
    assert!(checked > 20, "the scan found only {checked} modules");
    assert!(cycles.is_empty(), "module import cycles:\n{}", cycles.join("\n"));
}

#[test]
fn the_scan_finds_a_cycle_and_grouped_imports() {
    let code = code("use super::{alpha, beta::Thing};\n// use super::gamma;\nfn f() { crate::x::delta::g(); }");
    assert_eq!(names_after(&code, "super"), ["alpha", "beta"]);
    assert_eq!(names_after(&code, "crate::x"), ["delta"]);
    assert_eq!(find_cycle(&[vec![1], vec![2], vec![0]]), Some(vec![0, 1, 2, 0]));
    assert_eq!(find_cycle(&[vec![1, 2], vec![2], vec![]]), None);
}
