//! Where a frame's instructions go, function by function: the firmware runs
//! under QEMU with the `segprof` plugin (`tests/qemu-prof/segprof.c`),
//! which counts every executed instruction per address and starts a new
//! segment after each line of the firmware's report (the firmware calls
//! `tilerast_report_line` there). Each segment is one line's work; its
//! addresses are charged to functions through the ELF's debug info, inlined
//! frames included, so the span loop inlined into the frame loop still
//! counts as the span loop. The fused mesh path's per-pair routine is also
//! broken down by its source lines ([`STATEMENTS`]).
//!
//! The firmware also calls `tilerast_lap` as it reads SysTick, so the
//! instructions between a line's first and last reading are those its
//! ticks count: the test asserts they agree, to a tick a reading. With
//! `TILERAST_PROFILE=path` it writes the profiles of the workloads issue
//! 13's targets name (`reports/profile.md`, by `cargo xtask report`).
//!
//! Needs `qemu-system-arm`, the thumb targets and a C compiler for the
//! plugin, so it is `#[ignore]`d in a plain `cargo test`; `cargo xtask test`
//! runs it.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::Command as Process;
use tilerast_fw::workloads::{self, LARGE_TRIANGLE_CMDS, TRIANGLE_CMDS};

mod qemu;
use qemu::{build_with, export_scenes, run_with};

/// One report line's work: the line and its instructions per address,
/// those SysTick timed (from its first lap to its last) and all.
struct Segment {
    line: String,
    /// Every instruction since the previous line.
    total: u64,
    /// The timed ones (all of them when the line read SysTick less than
    /// twice).
    timed: u64,
    /// SysTick readings.
    laps: u64,
    /// Per address: the timed instructions.
    counts: BTreeMap<u64, u64>,
}

/// Builds the plugin with the system's C compiler.
fn plugin() -> PathBuf {
    let src = tilerast_tests::repo().join("tests/qemu-prof/segprof.c");
    let lib = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("libsegprof.so");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let st = Process::new(&cc)
        .args(["-shared", "-fPIC", "-O2", "-o"])
        .arg(&lib)
        .arg(&src)
        .status()
        .unwrap_or_else(|e| panic!("{cc} (a C compiler builds the QEMU plugin): {e}"));
    assert!(st.success(), "building {}", src.display());
    lib
}

/// The address of a function of the firmware.
fn address(elf: &Path, name: &str) -> u64 {
    use object::{Object, ObjectSymbol};
    let data = std::fs::read(elf).unwrap();
    let file = object::File::parse(&*data).unwrap();
    let sym = file
        .symbols()
        .find(|s| s.name() == Ok(name))
        .unwrap_or_else(|| panic!("the firmware defines {name}"));
    // Thumb: bit 0 of a function's address says so; the code is at the even one.
    sym.address() & !1
}

/// What the plugin writes per segment: its instructions, what ended it
/// (`lap`, `line`, `exit`) and its counts per address.
type Piece = (u64, String, Vec<(u64, u64)>);

/// Runs `elf` under the profiler: each report line with its segment, and
/// the instructions the plugin counted in all.
fn profile(board: &str, elf: &Path, lib: &Path) -> (Vec<Segment>, u64) {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("prof-{board}.txt"));
    let (line, lap) = (
        address(elf, "tilerast_report_line"),
        address(elf, "tilerast_lap"),
    );
    assert_ne!(line, lap, "two marks");
    let arg = format!(
        "{},line={line:#x},lap={lap:#x},out={}",
        lib.display(),
        out.display()
    );
    let text = run_with(board, elf, &["-plugin", &arg]);
    let mut lines = text.lines();
    let prof = std::fs::read_to_string(&out).unwrap();
    // The plugin's pieces, each ended by a lap, a line or the exit.
    let mut pieces: Vec<Piece> = vec![];
    let mut total = 0;
    for l in prof.lines() {
        let w: Vec<&str> = l.split_whitespace().collect();
        match w[..] {
            ["segment", k, n, end] => {
                assert_eq!(k.parse::<usize>().unwrap(), pieces.len());
                pieces.push((n.parse().unwrap(), end.to_string(), vec![]));
            }
            ["total", n] => total = n.parse().unwrap(),
            [a, n] => pieces
                .last_mut()
                .unwrap()
                .2
                .push((u64::from_str_radix(a, 16).unwrap(), n.parse().unwrap())),
            _ => panic!("{l}"),
        }
    }
    assert_eq!(pieces.last().map(|p| p.1.as_str()), Some("exit"));
    let mut segs = vec![];
    let mut group: Vec<&Piece> = vec![];
    for p in &pieces {
        group.push(p);
        if p.1 == "lap" {
            continue;
        }
        let laps = group.len() as u64 - 1;
        let timed = if laps >= 2 {
            &group[1..group.len() - 1]
        } else {
            &group[..]
        };
        let mut counts = BTreeMap::new();
        for (_, _, c) in timed {
            for &(a, n) in c {
                *counts.entry(a).or_default() += n;
            }
        }
        segs.push(Segment {
            line: match p.1.as_str() {
                "line" => lines.next().expect("a line per mark").to_string(),
                _ => "(exit)".into(),
            },
            total: group.iter().map(|g| g.0).sum(),
            timed: timed.iter().map(|g| g.0).sum(),
            laps,
            counts,
        });
        group.clear();
    }
    assert_eq!(lines.next(), None, "{board}: a mark per report line");
    (segs, total)
}

/// A function's name as the report prints it: the core's paths without
/// the crate's name (the demangler has already dropped the hash).
fn short(name: &str) -> String {
    name.replace("tilerast::", "")
}

/// An address's inline chain, innermost first: each frame's function, and
/// the file and line in it where the address lies.
type Frames = (Vec<String>, Vec<Option<(String, u32)>>);

/// The inline chain at each address, innermost first: each frame's
/// function and where in its source the address lies (the innermost
/// frame's own line; an outer frame's call of the next one).
struct Symbols {
    loader: addr2line::Loader,
    cache: HashMap<u64, Frames>,
    /// [`core_modules`].
    modules: Vec<(String, bool)>,
}

impl Symbols {
    fn new(elf: &Path) -> Self {
        Symbols {
            loader: addr2line::Loader::new(elf).unwrap(),
            cache: HashMap::new(),
            modules: core_modules(),
        }
    }

    fn frames(&mut self, addr: u64) -> &Frames {
        let loader = &self.loader;
        self.cache.entry(addr).or_insert_with(|| {
            let (mut chain, mut at) = (vec![], vec![]);
            if let Ok(mut frames) = loader.find_frames(addr) {
                while let Ok(Some(f)) = frames.next() {
                    if let Some(name) = f.function.as_ref().and_then(|n| n.demangle().ok()) {
                        chain.push(short(&name));
                        at.push(
                            f.location
                                .and_then(|l| Some((l.file?.to_string(), l.line.unwrap_or(0)))),
                        );
                    }
                }
            }
            if chain.is_empty() {
                chain.push(
                    loader
                        .find_symbol(addr)
                        .map(|s| short(&addr2line::demangle_auto(s.into(), None)))
                        .unwrap_or_else(|| format!("{addr:#x}")),
                );
                at.push(None);
            }
            (chain, at)
        })
    }

    fn chain(&mut self, addr: u64) -> &[String] {
        &self.frames(addr).0
    }

    /// Where in function `f` (a name ending in `::f`) the address lies, if
    /// `f` is on its chain: the file and line of `f`'s statement that
    /// reaches it (line 0: code the compiler gave no line, such as
    /// register moves and spills).
    fn statement(&mut self, addr: u64, f: &str) -> Option<(String, u32)> {
        let (chain, at) = self.frames(addr);
        let tail = format!("::{f}");
        let i = chain.iter().position(|n| n.ends_with(&tail))?;
        at[i].clone()
    }
}

/// The core's modules (`core/src`'s files and folders) and whether each
/// has submodules of its own (a folder).
fn core_modules() -> Vec<(String, bool)> {
    let dir = tilerast_tests::repo().join("core/src");
    let mut m: Vec<(String, bool)> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| {
            let e = e.ok()?;
            let name = e.file_name().into_string().ok()?;
            let nested = e.file_type().ok()?.is_dir();
            let name = if nested {
                name
            } else {
                name.strip_suffix(".rs")?.to_string()
            };
            (name != "lib").then_some((name, nested))
        })
        .collect();
    m.sort();
    m
}

/// The core module an instruction is written in: that of the innermost
/// frame of its chain that belongs to the core (`raster::traverse`,
/// `setup`, ...), or `outside the core`.
fn module(chain: &[String], modules: &[(String, bool)]) -> String {
    for f in chain {
        let path = f.trim_start_matches('<').trim_start_matches("impl ");
        let mut seg = path.split("::");
        let first = seg.next().unwrap_or("");
        let Some((_, nested)) = modules.iter().find(|(m, _)| m == first) else {
            continue;
        };
        return match seg.next() {
            Some(sub) if *nested && sub.chars().all(|c| c.is_ascii_lowercase() || c == '_') => {
                format!("{first}::{sub}")
            }
            _ => first.to_string(),
        };
    }
    "outside the core".into()
}

/// Whether a frame is the standard library's (`core::cmp::min`, `<i32>::
/// wrapping_add`, ...): inlined helpers that *self* looks through.
fn is_std(f: &str) -> bool {
    let f = f.trim_start_matches('<');
    f.starts_with("core::")
        || [
            "i8", "u8", "i16", "u16", "i32", "u32", "i64", "u64", "isize", "usize", "[", "&",
        ]
        .iter()
        .any(|t| f.starts_with(t))
}

/// The function an instruction is charged to in *self*: the innermost one
/// that is not the standard library's (the whole chain is, when none).
fn own(chain: &[String]) -> &String {
    chain.iter().find(|f| !is_std(f)).unwrap_or(&chain[0])
}

/// The rows of one segment's table: instructions per name, most first.
fn top(counts: &BTreeMap<String, u64>, n: usize) -> Vec<(&String, u64)> {
    let mut v: Vec<_> = counts.iter().map(|(k, &c)| (k, c)).collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    v.truncate(n);
    v
}

/// The firmware's instructions for a `scene`, `spin` or `bench` line: its ticks
/// times the board's instructions per tick.
fn ticked(line: &str, per_tick: f64) -> Option<f64> {
    let w: Vec<&str> = line.split_whitespace().collect();
    let num = |k: &str| -> Option<f64> {
        let i = w.iter().position(|&x| x == k)?;
        w.get(i + 1)?.parse().ok()
    };
    match *w.first()? {
        "scene" => Some((num("raster_ticks")? + num("flush_ticks")?) * per_tick),
        // A rotating-mesh frame: its vertex stage, then binning, drawing
        // and the CRC flush.
        "spin" => {
            Some((num("vertex_ticks")? + num("raster_ticks")? + num("flush_ticks")?) * per_tick)
        }
        "bench" => Some(num("ticks")? * per_tick),
        _ => None,
    }
}

/// What a line's work is counted in: `(unit, how many)`.
fn unit(line: &str) -> Option<(&'static str, u64)> {
    let w: Vec<&str> = line.split_whitespace().collect();
    match (w.first()?, w.get(1)?) {
        (&"scene" | &"spin", _) => {
            let i = w.iter().position(|&x| x == "replayed")?;
            Some(("(tile, command) pair", w[i + 1].parse().ok()?))
        }
        (&"bench", name) if name.starts_with("large_") => Some((
            "pixel",
            workloads::covered_pixels(&LARGE_TRIANGLE_CMDS, workloads::SIDE).ok()?,
        )),
        (&"bench", _) => Some((
            "pixel",
            workloads::covered_pixels(&TRIANGLE_CMDS, workloads::SIDE).ok()?,
        )),
        _ => None,
    }
}

/// One workload's section of the report.
fn section(board: &str, seg: &Segment, syms: &mut Symbols, per_tick: f64) -> String {
    let (mut selfs, mut incl, mut modules) = (
        BTreeMap::<String, u64>::new(),
        BTreeMap::<String, u64>::new(),
        BTreeMap::<String, u64>::new(),
    );
    for (&a, &n) in &seg.counts {
        let chain = syms.chain(a).to_vec();
        *selfs.entry(own(&chain).clone()).or_default() += n;
        let mut seen: Vec<&String> = vec![];
        for f in &chain {
            if !seen.contains(&f) {
                *incl.entry(f.clone()).or_default() += n;
                seen.push(f);
            }
        }
        *modules.entry(module(&chain, &syms.modules)).or_default() += n;
    }
    let w: Vec<&str> = seg.line.split_whitespace().collect();
    let (u, units) = unit(&seg.line).unwrap_or(("", 0));
    let mut md = format!(
        "### {board}: {} {}\n\n{} instructions timed ({} SysTick ticks of {per_tick}), {} {u}s; \
         {} more load the workload and print its line.\n\n",
        w[0],
        w[1],
        fmt_n(seg.timed),
        fmt_n(ticked(&seg.line, 1.0).unwrap_or(0.0) as u64),
        fmt_n(units),
        fmt_n(seg.total - seg.timed),
    );
    let per = |n: u64| {
        if units > 0 {
            format!("{:.1}", n as f64 / units as f64)
        } else {
            "—".into()
        }
    };
    let pct = |n: u64| format!("{:.1}%", 100.0 * n as f64 / seg.timed.max(1) as f64);
    md += &format!(
        "| module of the core | instructions | share | per {u} |\n| --- | ---: | ---: | ---: |\n"
    );
    for (s, n) in top(&modules, modules.len()) {
        md += &format!("| {s} | {} | {} | {} |\n", fmt_n(n), pct(n), per(n));
    }
    md += &format!(
        "\n| function (self: where the instruction is, inlined or not) | instructions | share | per {u} |\n| --- | ---: | ---: | ---: |\n"
    );
    for (f, n) in top(&selfs, 14) {
        md += &format!("| `{f}` | {} | {} | {} |\n", fmt_n(n), pct(n), per(n));
    }
    md += &format!(
        "\n| function (inclusive: with what is inlined into it) | instructions | share | per {u} |\n| --- | ---: | ---: | ---: |\n"
    );
    for (f, n) in top(&incl, 14) {
        md += &format!("| `{f}` | {} | {} | {} |\n", fmt_n(n), pct(n), per(n));
    }
    for f in STATEMENTS {
        md += &statements(f, seg, syms, &pct, &per, u);
    }
    md + "\n"
}

/// The functions whose statements a section breaks down, when the
/// workload runs them: the fused mesh path's per-pair routine and its row
/// loop (issue 46: where a pair's instructions go, statement by
/// statement).
const STATEMENTS: [&str; 2] = ["near_triangle", "plane_rows"];

/// Function `f`'s statements in `seg`: each instruction charged to the
/// line of `f` that reaches it (what that line inlines included), the
/// most costly first, with the line's source text; empty when the
/// workload does not run `f`.
fn statements(
    f: &str,
    seg: &Segment,
    syms: &mut Symbols,
    pct: &dyn Fn(u64) -> String,
    per: &dyn Fn(u64) -> String,
    u: &str,
) -> String {
    let mut lines = BTreeMap::<(String, u32), u64>::new();
    for (&a, &n) in &seg.counts {
        if let Some(at) = syms.statement(a, f) {
            *lines.entry(at).or_default() += n;
        }
    }
    let all: u64 = lines.values().sum();
    if all == 0 {
        return String::new();
    }
    let mut rows: Vec<_> = lines.into_iter().collect();
    rows.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut md = format!(
        "\n`{f}`, statement by statement ({} instructions, {} of the workload's, {} a {u}): \
         each instruction charged to the line of `{f}` that reaches it, what it inlines \
         included.\n\n| line | source | instructions | share | per {u} |\n| --- | --- | ---: | ---: | ---: |\n",
        fmt_n(all),
        pct(all),
        per(all),
    );
    let shown = 16;
    for ((file, line), n) in rows.iter().take(shown) {
        let name = file
            .rsplit_once("core/src/")
            .map_or(file.as_str(), |(_, r)| r);
        let text = if *line == 0 {
            "(no line: register moves, spills, branches the compiler made)".to_string()
        } else {
            source_line(file, *line)
        };
        md += &format!(
            "| {name}:{line} | `{text}` | {} | {} | {} |\n",
            fmt_n(*n),
            pct(*n),
            per(*n)
        );
    }
    let rest: u64 = rows.iter().skip(shown).map(|r| r.1).sum();
    if rest > 0 {
        md += &format!(
            "| {} more lines | | {} | {} | {} |\n",
            rows.len() - shown,
            fmt_n(rest),
            pct(rest),
            per(rest)
        );
    }
    md
}

/// Line `line` of source file `file`, trimmed and shortened for a table
/// cell (`?` when the file is not on this machine).
fn source_line(file: &str, line: u32) -> String {
    let text = std::fs::read_to_string(file)
        .ok()
        .and_then(|s| {
            s.lines()
                .nth(line as usize - 1)
                .map(str::trim)
                .map(String::from)
        })
        .unwrap_or_else(|| "?".into());
    let mut t: String = text.chars().take(72).collect();
    if text.chars().count() > 72 {
        t.push('…');
    }
    t.replace('|', "\\|").replace('`', "'")
}

/// `n` with thousands separated by commas.
fn fmt_n(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The builds profiled and the report lines each section shows.
const RUNS: [(&str, Option<&str>, &[&str]); 3] = [
    (
        "mps2-an386",
        None,
        &[
            "scene teapot",
            "scene teapot_cull",
            "spin teapot backend f32 frame 0",
            "scene demo",
            "bench gouraud_z_wid_dither8_rgb565",
            "bench gouraud_z_wid_dither8_plane_rgb565",
            "bench large_gouraud_rgb565",
            "bench large_gouraud_z_rgb565",
            "bench large_gouraud_z_wid_dither8_rgb565",
        ],
    ),
    ("microbit", None, &["scene demo"]),
    ("microbit", Some("bench"), &["bench large_gouraud_z_rgb565"]),
];

#[test]
#[ignore = "needs qemu-system-arm, the thumb targets and cc: run `cargo xtask test`"]
fn instruction_profile_agrees_with_systick() {
    let scenes = export_scenes();
    let lib = plugin();
    let mut md = String::from(
        "# Where the instructions go, function by function\n\n\
         Generated by `cargo xtask report` (`tests/tests/profile.rs` with `TILERAST_PROFILE`). \
         Each firmware is built with its feature `profile` (the marks below) and runs \
         under QEMU with `tests/qemu-prof/segprof.c`, a plugin that counts \
         every executed instruction per address and starts a new segment after each line of \
         the firmware's report: a segment is the work of one line (its workload, timed by \
         SysTick for `reports/targets.md`, plus loading it and printing the line). Addresses \
         are charged to functions through the ELF's debug info, inlined frames included: \
         *self* charges an instruction to the innermost function it was written in, looking \
         through the standard library's inlined helpers (`min`, `wrapping_add`: the span loop \
         inlined into the frame loop counts as the span loop), *inclusive* to every function \
         on its inline chain, and *module* to the core module that function is in: where the \
         code is written, which is not the frame's phase (`reports/targets.md` times the \
         phases: binning reads the commands through `wire` too, and the phase *setup* runs \
         the traversal's set-up and first row). Each workload's profile holds the instructions between its \
         first and last reading of SysTick (the firmware calls `tilerast_lap` there, another \
         mark): the test asserts they are the instructions its ticks count, to a tick a \
         reading. The marks' calls change how the code around them compiles, so these \
         counts differ a little (under 1%) from `reports/targets.md`'s, which come from \
         builds without them. Where a workload runs the fused mesh path, its per-pair \
         routine (`near_triangle`) and its row loop (`plane_rows`) are broken down \
         statement by statement, each instruction charged to the source line that reaches it.\n\n",
    );
    for (board, features, wanted) in RUNS {
        let elf = build_with(board, &scenes, features, true);
        let (segs, total) = profile(board, &elf, &lib);
        let sum: u64 = segs.iter().map(|s| s.total).sum();
        assert_eq!(sum, total, "{board}: every instruction is in a segment");
        let per_tick: f64 = segs
            .iter()
            .find_map(|s| {
                let w: Vec<&str> = s.line.split_whitespace().collect();
                let i = w.iter().position(|&x| x == "instr_per_tick")?;
                w[i + 1].parse().ok()
            })
            .expect("board line");
        let mut checked = 0;
        for s in &segs {
            let Some(t) = ticked(&s.line, per_tick) else {
                continue;
            };
            // Each lap rounds to a tick and its mark lies a few
            // instructions before SysTick is read.
            let slack = s.laps as f64 * (per_tick + 16.0);
            assert!(
                s.laps >= 2 && (s.timed as f64 - t).abs() <= slack,
                "{board} `{}`: {} instructions between its {} laps, {t} timed",
                s.line,
                s.timed,
                s.laps
            );
            checked += 1;
        }
        assert!(checked >= wanted.len(), "{board}: {checked} timed lines");
        let mut syms = Symbols::new(&elf);
        for w in wanted {
            let seg = segs
                .iter()
                .find(|s| s.line.starts_with(&format!("{w} ")))
                .unwrap_or_else(|| panic!("{board}: no line `{w}`"));
            let sec = section(board, seg, &mut syms, per_tick);
            println!("{sec}");
            md += &sec;
        }
    }
    if let Some(path) = std::env::var_os("TILERAST_PROFILE") {
        std::fs::write(&path, md).unwrap();
        println!("wrote {}", Path::new(&path).display());
    }
}
