//! Edge antialiasing of solids (seed 003 eq. 8): exact against the f64
//! model of the same rule at any tiling, the coverage it writes, the error
//! it removes against a 16x16 supersampled ideal, and which mesh edges get it.

use proptest::prelude::*;
use tilerast::line::{EdgeCmd, Side};
use tilerast::prelude::*;
use tilerast_sim::{mesh::silhouette_edges, metrics, reference, render, FormatKind};
use tilerast_tests::{config, tri, vsub, Rng};

/// A triangle with its three antialiased edges (drawn last by the caller).
fn edges_of(v: [Vertex; 3]) -> [Command; 3] {
    [0, 1, 2].map(|i| Command::Edge {
        edge: EdgeCmd::of_triangle(&v, i),
        state: State::default(),
    })
}

/// White triangle over black, RGB888: the red channel of row `y`.
fn row(v: [Vertex; 3], y: usize) -> Vec<u32> {
    let mut cmds = vec![tri(v, 0)];
    cmds.extend(edges_of(v));
    let r = render(&config(32, 24, FormatKind::Rgb888), &cmds).unwrap();
    r.raw[y * 32..(y + 1) * 32]
        .iter()
        .map(|p| p >> 16)
        .collect()
}

#[test]
fn the_outside_pixel_gets_the_covered_part() {
    let w = [255; 3];
    // A wide triangle whose top edge is horizontal at y = 9.75: row 9's
    // centre (9.5) is outside, a quarter of its cell is inside.
    let t = [
        vsub(-160, 156, 0, w),
        vsub(1000, 156, 0, w),
        vsub(400, 380, 0, w),
    ];
    assert!(
        row(t, 9)[10..20].iter().all(|&v| v == 64),
        "{:?}",
        row(t, 9)
    );
    assert!(row(t, 10)[10..20].iter().all(|&v| v == 255));
    // At y = 10.25 the edge crosses row 10's cell, whose centre is inside:
    // the seed leaves inside pixels alone, so nothing is blended.
    let t = t.map(|v| Vertex {
        y: v.y + Coord::from_num(0.5),
        ..v
    });
    assert!(row(t, 9).iter().all(|&v| v == 0));
    // The same edge with the solid above it: row 10 (centre 10.5 outside)
    // gets a quarter.
    let t = [
        vsub(-160, 164, 0, w),
        vsub(1000, 164, 0, w),
        vsub(400, -60, 0, w),
    ];
    assert!(
        row(t, 10)[10..20].iter().all(|&v| v == 64),
        "{:?}",
        row(t, 10)
    );
}

#[test]
fn interior_side_follows_the_triangle() {
    let v = |x: i64, y: i64| vsub(x * 16, y * 16, 0, [0; 3]);
    let t = [v(0, 0), v(10, 0), v(0, 10)];
    assert_eq!(EdgeCmd::of_triangle(&t, 0).interior, Side::Right);
    assert_eq!(EdgeCmd::of_triangle(&t, 1).interior, Side::Right);
    let flipped = [t[0], t[2], t[1]];
    assert!((0..3).all(|i| EdgeCmd::of_triangle(&flipped, i).interior == Side::Left));
}

/// Random solids behind, one solid with its edges, sometimes a nearer
/// occluder: ours and the f64 model of the same rule, red channel.
fn scene(seed: u64) -> Vec<Command> {
    let mut rng = Rng::new(seed);
    let mut cmds = Vec::new();
    // Flat, distinct depths: no two solids meet where their quantized and
    // exact depths could order them differently.
    for k in 0..3 {
        let mut v = rng.triangle((-200, 1200), (-200, 900));
        v.iter_mut().for_each(|v| v.z = 20000 + 10000 * k);
        cmds.push(tri(v, 0));
    }
    let mut fg = rng.triangle((0, 1024), (0, 768));
    fg.iter_mut().for_each(|v| v.z = 10000 + v.z / 8);
    cmds.push(tri(fg, 0));
    if rng.range(0, 2) == 0 {
        let mut occ = rng.triangle((0, 1024), (0, 768));
        occ.iter_mut().for_each(|v| v.z = 1000);
        cmds.push(tri(occ, 0));
    }
    cmds.extend(edges_of(fg));
    cmds
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(200)))]
    /// Every pixel within 3 LSB of the f64 model: the weight is floored to
    /// 1/256 twice (distance, then times the column cover: 2/256 of 255 =
    /// 2 LSB), the pixel rounds (0.5) and the background the blend starts
    /// from is itself the pipeline's rounded Gouraud value (0.5).
    #[test]
    fn edges_match_the_reference_at_any_tiling(seed in any::<u64>(), tw in 1u16..64, th in 1u16..48) {
        let cmds = scene(seed);
        let mut c = config(64, 48, FormatKind::Rgb888);
        c.depth = true;
        c.tile = (tw, th);
        let ours = render(&c, &cmds).unwrap();
        let exact = reference::render(&c, &cmds);
        for (i, (p, e)) in ours.raw.iter().zip(&exact.color).enumerate() {
            for (ch, e) in e.iter().enumerate() {
                let v = (p >> (16 - 8 * ch)) & 255;
                prop_assert!((v as f64 - e).abs() <= 3.0, "pixel {} ch {}: {} vs {}", i, ch, v, e);
            }
        }
    }
}

/// Eq. 8 colour error against the 16x16 supersampled ideal, with and
/// without the edges.
fn errors(cmds: &[Command], n_solid: usize) -> (u64, u64) {
    let mut c = config(64, 48, FormatKind::Rgb888);
    c.depth = true;
    let ideal = reference::supersample(&c, cmds, 16).to_image();
    let sse = |cmds: &[Command]| {
        let img = render(&c, cmds).unwrap().image;
        metrics::compare(&img, &ideal).unwrap().sse
    };
    (sse(&cmds[..n_solid]), sse(cmds))
}

#[test]
fn edge_aa_removes_about_half_the_edge_error() {
    // Seed 003 blends only the outside pixel: of the two pixels a column of
    // an edge crosses, only the one whose centre is outside is corrected,
    // so for edges at random positions the expected squared error halves
    // (measured: 0.59 here, the rest is at vertices and overlaps).
    let (mut aliased, mut aa) = (0, 0);
    for seed in 0..12 {
        let mut rng = Rng::new(seed);
        let mut cmds = Vec::new();
        let mut tris = Vec::new();
        for k in 0..4u16 {
            let mut v = rng.triangle((0, 1024), (0, 768));
            v.iter_mut().for_each(|v| v.z = 1000 + 10000 * k);
            cmds.push(tri(v, 0));
            tris.push(v);
        }
        let n = cmds.len();
        for v in tris {
            cmds.extend(edges_of(v));
        }
        let (a, b) = errors(&cmds, n);
        aliased += a;
        aa += b;
    }
    let ratio = aa as f64 / aliased as f64;
    assert!(
        (0.4..0.7).contains(&ratio),
        "edge AA / aliased error = {ratio:.3} ({aa} / {aliased})"
    );
}

#[test]
fn only_silhouette_and_boundary_edges_are_antialiased() {
    let v = |x: i64, y: i64| vsub(x * 16, y * 16, 0, [9; 3]);
    // A quad of two triangles: four boundary edges, not the shared diagonal.
    let quad = [
        [v(0, 0), v(10, 0), v(10, 10)],
        [v(0, 0), v(10, 10), v(0, 10)],
    ];
    let e = silhouette_edges(&quad);
    assert_eq!(e.len(), 4);
    let diagonal = |e: &EdgeCmd| {
        let k = e.v.map(|v| (v.x.to_num::<i32>(), v.y.to_num::<i32>()));
        k == [(0, 0), (10, 10)] || k == [(10, 10), (0, 0)]
    };
    assert!(!e.iter().any(diagonal));
    // Folded: the second triangle lies on the same side of the shared edge
    // (a silhouette seen edge-on), so the shared edge is antialiased too.
    let fold = [[v(0, 0), v(10, 0), v(5, 8)], [v(0, 0), v(10, 0), v(5, 4)]];
    assert_eq!(silhouette_edges(&fold).len(), 5);
    // A fan around a centre: only the rim.
    let c = v(20, 20);
    let rim = [v(30, 20), v(20, 30), v(10, 20), v(20, 10)];
    let fan: Vec<_> = (0..4).map(|i| [c, rim[i], rim[(i + 1) % 4]]).collect();
    assert_eq!(silhouette_edges(&fan).len(), 4);
    // Degenerate triangles take no part.
    assert!(silhouette_edges(&[[v(0, 0), v(5, 5), v(10, 10)]]).is_empty());
}

#[test]
fn one_sample_supersampling_is_the_pixel_centre_reference() {
    // The ideal (N x N samples) and the pixel-centre f64 reference share no
    // code; at N = 1 the sample is the pixel centre and they must agree on
    // every command kind but the antialiased ones (lines here are Bresenham
    // in one, rectangles in the other, so the demo without lines is used).
    for name in ["demo.toml", "edges.toml"] {
        let mut s = tilerast_sim::Scene::load(tilerast_tests::scene(name)).unwrap();
        s.set_edge_aa(false);
        let a = reference::supersample(&s.config, &s.commands, 1).to_image();
        let b = reference::render(&s.config, &s.commands).to_image();
        assert_eq!(metrics::compare(&a, &b).unwrap().differing, 0, "{name}");
    }
}

#[test]
fn antialiasing_brings_renders_closer_to_the_ideal() {
    // The report's measurements (`tilerast-lab aa-report`), as properties:
    // against the 16x16 supersampled ideal, two-point lines beat Bresenham
    // by far, Bresenham with sub-pixel end points beats integer end points,
    // and edge antialiasing lowers the error of solids.
    let groups = tilerast_lab::aa::measure(&[]);
    let err = |g: usize, mode: &str| {
        let m = groups[g].1.iter().find(|m| m.mode.contains(mode)).unwrap();
        m.diff.mse_per_pixel
    };
    assert!(err(0, "Wu") < err(0, "Bresenham") / 4.0);
    assert!(err(0, "Bresenham") < err(0, "embedded-graphics"));
    assert!(err(1, "edge AA") < err(1, "aliased") * 0.7);
}
