//! House rules the code keeps (issue 11): the core's pipeline stages —
//! its top-level modules and folders — import each other without a cycle,
//! so each can be read, tested and replaced in pipeline order.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// `crate::NAME` references on lines that are code (not comments or docs).
fn references(src: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in src.lines() {
        let code = line.trim_start();
        if code.starts_with("//") {
            continue;
        }
        let code = code.split("//").next().unwrap_or("");
        for (i, _) in code.match_indices("crate::") {
            let name: String = code[i + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// Every `.rs` file under `dir`, with the top-level module it belongs to.
fn files(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(root, &p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            let rel = p.strip_prefix(root).unwrap();
            let top = rel
                .components()
                .next()
                .unwrap()
                .as_os_str()
                .to_string_lossy();
            let module = top.trim_end_matches(".rs").to_string();
            out.push((module, std::fs::read_to_string(&p).unwrap()));
        }
    }
}

/// The module graph of `core/src` (edges between distinct top-level
/// modules; `lib.rs` only declares and re-exports).
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let root = tilerast_tests::repo().join("core/src");
    let mut all = Vec::new();
    files(&root, &root, &mut all);
    let modules: BTreeSet<String> = all.iter().map(|(m, _)| m.clone()).collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, src) in &all {
        if m == "lib" {
            continue;
        }
        let deps = g.entry(m.clone()).or_default();
        for r in references(src) {
            if r != *m && modules.contains(&r) && r != "lib" {
                deps.insert(r);
            }
        }
    }
    g
}

/// A cycle of `g`, if any (depth-first search).
fn cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(n) {
            Some(2) => return None,
            Some(1) => {
                let start = path.iter().position(|p| p == n).unwrap();
                let mut c = path[start..].to_vec();
                c.push(n.to_string());
                return Some(c);
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for d in g.get(n).into_iter().flatten() {
            if let Some(c) = visit(d, g, state, path) {
                return Some(c);
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    g.keys()
        .find_map(|n| visit(n, g, &mut state, &mut Vec::new()))
}

#[test]
fn core_stages_import_without_a_cycle() {
    let g = graph();
    assert!(g.len() >= 12, "{g:?}");
    assert_eq!(
        cycle(&g),
        None,
        "import cycle between core stages; graph {g:#?}"
    );
    // The pipeline's order where it matters most: the tile planes draw,
    // the frame bins and flushes — never the other way round.
    assert!(g["frame"].contains("tile") && !g["tile"].contains("frame"));
    assert!(g["tile"].contains("raster") && !g["raster"].contains("tile"));
    assert!(!g["raster"].contains("fragment") && !g["fragment"].contains("raster"));
}

#[test]
fn the_cycle_finder_finds_cycles() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default();
    assert_eq!(cycle(&g), None);
    g.get_mut("c").unwrap().insert("a".into());
    assert_eq!(
        cycle(&g),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    assert_eq!(
        references("use crate::tile::Tile; // crate::frame\n/// crate::wire"),
        BTreeSet::from(["tile".to_string()])
    );
}

/// The README is what a newcomer reads first: it stays a readable page (a
/// scripted edit once interleaved a paragraph between its every character,
/// 22 MB), and it keeps the two commands.
#[test]
fn readme_stays_a_readable_page() {
    let text = std::fs::read_to_string(tilerast_tests::repo().join("README.md")).unwrap();
    assert!(text.len() < 200_000, "README.md is {} bytes", text.len());
    assert!(
        text.starts_with("# tilerast\n"),
        "README.md starts with its title"
    );
    assert!(text.contains("cargo xtask test"));
    assert!(text.contains("tilerast-sim -- render scenes/demo.toml"));
    // No paragraph repeated: every line of 60+ characters appears once.
    let mut seen = BTreeSet::new();
    for line in text
        .lines()
        .filter(|l| l.len() >= 60 && !l.starts_with('|'))
    {
        assert!(seen.insert(line), "README.md repeats: {line}");
    }
}
