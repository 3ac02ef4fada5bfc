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

/// The module graph of crate source folder `src` (edges between distinct
/// top-level modules; `lib.rs` only declares and re-exports, `main.rs` is
/// the binary on top).
fn graph(src: &str) -> BTreeMap<String, BTreeSet<String>> {
    let root = tilerast_tests::repo().join(src);
    let mut all = Vec::new();
    files(&root, &root, &mut all);
    let modules: BTreeSet<String> = all.iter().map(|(m, _)| m.clone()).collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, src) in &all {
        if m == "lib" || m == "main" {
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
    let g = graph("core/src");
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

/// The simulator's modules too: scenes read files and build commands,
/// the renderers draw them, the reports sit on top — no module imports
/// one that imports it back.
#[test]
fn simulator_modules_import_without_a_cycle() {
    let g = graph("host-sim/src");
    assert!(g.len() >= 10, "{g:?}");
    assert_eq!(
        cycle(&g),
        None,
        "import cycle in the simulator; graph {g:#?}"
    );
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
    // A front page: what it is, two commands, getting started, what is
    // proven, links. Long material lives in docs/ and reports/.
    let lines = text.lines().count();
    assert!(
        lines <= 300,
        "README.md is {lines} lines: move material to docs/"
    );
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

/// Every Markdown file of the repository (README, CHANGELOG, docs/,
/// reports/, the crates' pages): relative links point at files that exist,
/// and `#anchors` at headings of the file they name.
#[test]
fn every_markdown_link_resolves() {
    let root = tilerast_tests::repo();
    let mut pages = vec![];
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                // Build output, fuzz inputs and installed packages are
                // not the repository's pages.
                let skip = ["target", "corpus", "seeds", "node_modules"];
                if !name.starts_with('.') && !skip.contains(&name.as_str()) {
                    walk(&p, out);
                }
            } else if name.ends_with(".md") {
                out.push(p);
            }
        }
    }
    walk(&root, &mut pages);
    assert!(pages.len() > 10, "found {} pages", pages.len());
    let anchors = |text: &str| -> BTreeSet<String> {
        text.lines()
            .filter(|l| l.starts_with('#'))
            .map(|l| {
                l.trim_start_matches('#')
                    .trim()
                    .to_lowercase()
                    .chars()
                    .filter_map(|c| match c {
                        ' ' => Some('-'),
                        c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                        _ => None,
                    })
                    .collect()
            })
            .collect()
    };
    let mut broken = vec![];
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        let mut in_code = false;
        for line in text.lines() {
            if line.trim_start().starts_with("```") {
                in_code = !in_code;
                continue;
            }
            if in_code {
                continue;
            }
            let mut rest = line;
            while let Some(i) = rest.find("](") {
                rest = &rest[i + 2..];
                let Some(end) = rest.find(')') else { break };
                let target = rest[..end].trim_matches(['<', '>']);
                rest = &rest[end..];
                // Web links, and rustdoc's intra-doc paths (`tile::Tile`) in
                // pages a crate includes as its documentation, which
                // `cargo doc -D warnings` checks.
                if target.is_empty()
                    || target.contains("://")
                    || target.starts_with("mailto:")
                    || target.contains(' ')
                    || target.contains("::")
                {
                    continue;
                }
                let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
                let dest = if file.is_empty() {
                    page.clone()
                } else {
                    page.parent().unwrap().join(file)
                };
                if !dest.exists() {
                    broken.push(format!("{}: {target} (no such file)", page.display()));
                } else if !anchor.is_empty() && dest.extension().is_some_and(|e| e == "md") {
                    let t = std::fs::read_to_string(&dest).unwrap();
                    if !anchors(&t).contains(anchor) {
                        broken.push(format!("{}: {target} (no such heading)", page.display()));
                    }
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}
