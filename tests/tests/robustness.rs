//! Regression tests for what fuzzing and real-world OBJ files found
//! (issue 12): each test is named after its finding.

use std::path::{Path, PathBuf};
use tilerast::numeric::COORD_LIMIT;
use tilerast::prelude::*;
use tilerast_sim::{render, Limits, Scene};

/// A fresh directory under the target's temporary folder.
fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("robustness")
        .join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(d: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const HEAD: &str = "[screen]\nwidth = 16\nheight = 16\nformat = \"rgb565\"\n";

/// A scene drawing one OBJ with the defaults (camera on +z).
fn mesh_scene(d: &Path, obj: &str, extra: &str) -> PathBuf {
    write(
        d,
        "scene.toml",
        format!("[screen]\nwidth = 64\nheight = 64\nformat = \"rgb888\"\ndepth = true\n\n[[command]]\nkind = \"mesh\"\nobj = \"{obj}\"\nambient = 1.0\ncolor = [255, 255, 255]\n{extra}"),
    )
}

// 1. Plane mask ignored with coverage antialiasing.
#[test]
fn plane_mask_holds_with_coverage_aa() {
    for aa in ["none", "ruf8", "ss4", "ruf4", "grid4"] {
        let src = format!(
            "{HEAD}aa = \"{aa}\"\n\n[[command]]\nkind = \"fill\"\nrect = [0, 0, 16, 16]\nrgb = [255, 255, 255]\nplane_mask = 0x001F\n\n\
             [[command]]\nkind = \"triangle\"\nv = [[0, 0, 0, 255, 255, 255], [16, 0, 0, 255, 255, 255], [0, 16, 0, 255, 255, 255]]\nplane_mask = 0x07E0\n"
        );
        let s = Scene::parse(&src, Path::new(".")).unwrap();
        let r = render(&s.config, &s.commands).unwrap();
        // Blue everywhere; green added inside the triangle (pixel centres).
        assert_eq!(r.raw[15 * 16 + 15], 0x001F, "aa = {aa}: masked fill");
        assert_eq!(r.raw[0], 0x07FF, "aa = {aa}: masked triangle");
        assert!(
            r.raw.iter().all(|&p| p == 0x001F || p == 0x07FF),
            "aa = {aa}"
        );
    }
}

// 2. Tile rectangles near i32::MAX.
#[test]
fn tile_rect_near_i32_max_is_refused_and_the_band_edge_draws() {
    use tilerast::coverage::Ruf8;
    let mut t: Tile<8, Planes<Rgb565Format, Depth16, Wid8, NoDither, Ruf8>> = Tile::new();
    for r in [
        Rect::new(i32::MAX - 3, 0, 8, 1),
        Rect::new(0, i32::MAX - 1, 8, 1),
        Rect::new(i32::MIN, 0, 8, 1),
        Rect::new(COORD_LIMIT - 4, 0, 8, 1),
    ] {
        assert_eq!(
            t.begin(r, &Clear::default()),
            Err(Error::CoordOutOfRange),
            "{r:?}"
        );
    }
    // A tile ending exactly at the guard band's last row is fine, and every
    // fill reaches it.
    let edge = Rect::new(COORD_LIMIT - 8, COORD_LIMIT - 1, 8, 1);
    let mut t: Tile<8, Planes<Rgb565Format, Depth16, Wid8>> = Tile::new();
    t.begin(edge, &Clear::default()).unwrap();
    let white = Rgb::new(255, 255, 255);
    t.draw(&Command::WidFill { rect: edge, wid: 3 }).unwrap();
    t.draw(&Command::ZFill {
        rect: edge,
        z: 7,
        state: State::new(3),
    })
    .unwrap();
    t.draw(&Command::Fill {
        rect: edge,
        color: white,
        state: State::new(3),
        alpha: 255,
    })
    .unwrap();
    for x in edge.x..edge.x1() as i32 {
        assert_eq!(t.wid(x, edge.y), Some(3));
        assert_eq!(t.depth(x, edge.y), Some(7));
        assert_eq!(t.raw(x, edge.y), Some(0xFFFF));
    }
    let mut t: Tile<8, Planes<Rgb565Format, Depth16, Wid8, NoDither, Ruf8>> = Tile::new();
    t.begin(edge, &Clear::default()).unwrap();
    t.draw(&Command::Fill {
        rect: edge,
        color: white,
        state: State::default(),
        alpha: 255,
    })
    .unwrap();
    assert!(t.finish());
    assert_eq!(t.raw(edge.x, edge.y), Some(0xFFFF));
}

// 3. Scene parsing was quadratic (20,000 fills: 3.3 s; 200,000 triangles:
// over 60 s). A complexity check with a bound ten times what linear needs.
#[test]
fn scene_parsing_is_linear() {
    let mut src = String::from(HEAD);
    for i in 0..100_000 {
        src += &format!(
            "\n[[command]]\nkind = \"fill\"\nrect = [{}, 0, 1, 1]\nrgb = [1, 2, 3]\n",
            i % 16
        );
    }
    // The error of the last command names its own key's line.
    src += "\n[[command]]\nkind = \"fill\"\nrgb = [1, 2, 3]\nrect = [0, 0, -1, 1]\n";
    let lines = src.lines().count();
    let t = std::time::Instant::now();
    let e = Scene::parse(&src, Path::new(".")).unwrap_err().to_string();
    let took = t.elapsed();
    assert!(e.starts_with(&format!("{lines}: ")), "{e}");
    assert!(took.as_secs_f64() < 20.0, "100,000 commands took {took:?}");
}

// 4. Unbounded memory from the OBJ path.
#[test]
fn obj_path_to_dev_zero_is_bounded() {
    let d = dir("devzero");
    let limits = Limits {
        max_bytes: 1 << 20,
        max_line: 4096,
    };
    let e = Scene::load_with(mesh_scene(&d, "/dev/zero", ""), &limits)
        .unwrap_err()
        .to_string();
    assert!(e.contains("larger than the limit of 1048576 bytes"), "{e}");
    write(
        &d,
        "m.obj",
        "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = Scene::load_with(mesh_scene(&d, "m.obj", ""), &limits)
        .unwrap_err()
        .to_string();
    assert!(e.contains("/dev/zero: larger than the limit"), "{e}");
    // A large file without newlines stops at the line limit.
    write(&d, "long.obj", vec![b'v'; 8192]);
    let e = Scene::load_with(mesh_scene(&d, "long.obj", ""), &limits)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("long.obj:1: line longer than the limit of 4096 bytes"),
        "{e}"
    );
    // The scene file itself is bounded the same way.
    let e = Scene::load_with("/dev/zero", &limits)
        .unwrap_err()
        .to_string();
    assert!(e.contains("larger than the limit"), "{e}");
}

// 6. Export of a mesh group with more than 65,535 triangles.
#[test]
fn export_splits_mesh_groups_over_65535_triangles() {
    let d = dir("bigmesh");
    let n = 200; // 200 x 200 vertices: 79,202 triangles in one group
    let mut obj = String::new();
    for j in 0..n {
        for i in 0..n {
            obj += &format!("v {i} {j} 0\n");
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            obj += &format!(
                "f {a} {} {}\nf {a} {} {}\n",
                a + 1,
                a + n + 1,
                a + n + 1,
                a + n
            );
        }
    }
    write(&d, "grid.obj", obj);
    let s = Scene::load(mesh_scene(&d, "grid.obj", "")).unwrap();
    assert!(s.commands.len() > 65_535, "{}", s.commands.len());
    let bytes = s.encode().unwrap();
    let decoded: Vec<Command> = tilerast::wire::Encoded(&bytes[tilerast::wire::HEADER_LEN..])
        .iter()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(decoded, s.commands);
}

// 7. A coordinate of 1e308 was reported as "NaN or infinite input".
#[test]
fn huge_coordinate_is_out_of_range_not_infinite() {
    let e = Scene::parse(
        &format!("{HEAD}\n[[command]]\nkind = \"triangle\"\nv = [[1e308, 0, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0]]\n"),
        Path::new("."),
    )
    .unwrap_err().to_string();
    assert!(e.contains("outside the documented range"), "{e}");
    let e = Scene::parse(
        &format!("{HEAD}\n[[command]]\nkind = \"line\"\nfrom = [1e308, 0]\nto = [1, 1]\nrgb = [1, 1, 1]\n"),
        Path::new("."),
    )
    .unwrap_err().to_string();
    assert!(e.contains("out of range"), "{e}");
}

/// The pixels a one-face OBJ covers, as a 64x64 mask.
fn coverage(d: &Path, obj: &str) -> (Scene, Vec<bool>) {
    let s = Scene::load(mesh_scene(d, obj, "eye = [0, 0, 4]")).unwrap();
    let r = render(&s.config, &s.commands).unwrap();
    let m = (0..64 * 64)
        .map(|i| r.image.get(i % 64, i / 64) != [0, 0, 0])
        .collect();
    (s, m)
}

// 8. Concave polygons were fanned from the first vertex.
#[test]
fn concave_faces_fill_only_the_polygon() {
    let d = dir("concave");
    // A C: a 3x3 square with the notch x in 1..3, y in 1..2 cut out.
    let c = "v 0 0 0\nv 3 0 0\nv 3 1 0\nv 1 1 0\nv 1 2 0\nv 3 2 0\nv 3 3 0\nv 0 3 0\nf 1 2 3 4 5 6 7 8\n";
    write(&d, "c.obj", c);
    let (s, m) = coverage(&d, "c.obj");
    assert_eq!(s.mesh.triangles, 6);
    // The same shape as three convex quads.
    write(
        &d,
        "parts.obj",
        format!(
            "{}f 1 2 3 4\nf 4 5 8 1\nf 5 6 7 8\n",
            &c[..c.find('f').unwrap()]
        ),
    );
    let (_, parts) = coverage(&d, "parts.obj");
    let notch = m.iter().zip(&parts).filter(|(a, b)| a != b).count();
    assert!(parts.iter().filter(|&&p| p).count() > 500);
    // Shared interior edges may differ by a pixel or two of rounding.
    assert!(
        notch <= 4,
        "{notch} pixels differ from the convex decomposition"
    );
}

// 9. `l` elements were filled as triangles; `f` with two vertices made a
// degenerate triangle.
#[test]
fn obj_lines_become_line_commands() {
    let d = dir("lines");
    write(
        &d,
        "l.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nl 1 2 3\nf 3 4\n",
    );
    let s = Scene::load(mesh_scene(&d, "l.obj", "")).unwrap();
    let lines = s
        .commands
        .iter()
        .filter(|c| matches!(c, Command::Line { .. }))
        .count();
    assert_eq!(lines, 3);
    assert!(!s
        .commands
        .iter()
        .any(|c| matches!(c, Command::Triangle { .. })));
    assert!(
        s.notes
            .iter()
            .any(|n| n.contains("l.obj:6:1: face with two vertices drawn as a line")),
        "{:?}",
        s.notes
    );
}

// 10. One NaN vertex made unrelated triangles vanish.
#[test]
fn nan_vertex_is_named_and_does_not_poison_the_rest() {
    let d = dir("nan");
    let good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    write(&d, "good.obj", good);
    write(
        &d,
        "bad.obj",
        format!("{good}v nan 0 0\nv 1 inf 1\nf 1 5 2\nf 4 2 3\n"),
    );
    let g = Scene::load(mesh_scene(&d, "good.obj", "")).unwrap();
    let b = Scene::load(mesh_scene(&d, "bad.obj", "")).unwrap();
    assert_eq!(
        b.commands, g.commands,
        "the good triangle is drawn as before"
    );
    let warns = b.notes.join("\n");
    assert!(
        warns.contains("bad.obj:5:1: vertex 4 is not finite"),
        "{warns}"
    );
    assert!(
        warns.contains("bad.obj:6:1: vertex 5 is not finite"),
        "{warns}"
    );
    assert!(warns.contains("2 faces or lines dropped"), "{warns}");
}

// 11. A Latin-1 byte in a comment refused a valid OBJ.
#[test]
fn latin1_comment_is_read() {
    let d = dir("latin1");
    write(
        &d,
        "l1.obj",
        b"# mod\xe8le de caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 # \xa9\n",
    );
    let s = Scene::load(mesh_scene(&d, "l1.obj", "")).unwrap();
    assert_eq!(s.mesh.triangles, 1);
}

// 12. A missing `.mtl` or an undefined `usemtl` silently rendered grey.
#[test]
fn missing_mtl_and_undefined_material_warn() {
    let d = dir("mtl");
    write(
        &d,
        "m.obj",
        "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl gold\nf 1 2 3\n",
    );
    let s = Scene::load(mesh_scene(&d, "m.obj", "")).unwrap();
    let w = s.notes.join("\n");
    assert!(w.contains("m.obj:1:1: mtllib nowhere.mtl:"), "{w}");
    assert!(
        w.contains("m.obj:5:1: material `gold` is not defined"),
        "{w}"
    );
}

// 13. Errors named the `[[command]]` header, not the key's line, and never
// the OBJ's own line.
#[test]
fn errors_name_the_key_line_and_the_obj_line() {
    let d = dir("errlines");
    write(&d, "bad.obj", "v 0 0 0\nv 1 0 0\nv 1 x 0\n");
    let e = Scene::load(mesh_scene(&d, "bad.obj", ""))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("scene.toml:9: ") && e.contains("bad.obj:3:5: `x` is not a number"),
        "{e}"
    );
    write(&d, "idx.obj", "v 0 0 0\nf 1 2 3\n");
    let e = Scene::load(mesh_scene(&d, "idx.obj", ""))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("idx.obj:2:5: vertex 2 does not exist (1 defined so far)"),
        "{e}"
    );
    let e = Scene::parse(
        "[screen]\nformat = \"rgb565\"\nheight = 8\nwidth = 99999\n",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("4: "), "{e}");
    let e = Scene::parse(
        "[screen]\nwidth = 8\nheight = 8\nformat = \"rgb565\"\n\ndither = 3\n",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("6: "), "{e}");
}

// 14. `--edge-aa off` still said "silhouette edges (antialiased)"; PNGs
// written in the repository were not ignored.
#[test]
fn edge_aa_note_follows_the_switch_and_pngs_are_ignored() {
    let d = dir("edgenote");
    write(&d, "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let mut s = Scene::load(mesh_scene(&d, "t.obj", "edge_aa = true")).unwrap();
    assert!(s.notes[0].ends_with("(antialiased)"), "{:?}", s.notes);
    s.set_edge_aa(false);
    assert!(!s.notes[0].contains("antialiased"), "{:?}", s.notes);
    s.set_edge_aa(true);
    assert!(s.notes[0].ends_with("(antialiased)"), "{:?}", s.notes);
    let ignore = std::fs::read_to_string(tilerast_tests::repo().join(".gitignore")).unwrap();
    assert!(ignore.lines().any(|l| l.trim() == "/*.png"), "{ignore}");
}
