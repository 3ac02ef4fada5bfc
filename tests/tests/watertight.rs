//! Watertightness: triangles that share edges cover every pixel exactly
//! once (top-left rule), with random sub-pixel vertex positions — and the
//! core's coverage equals the independent f64 reference's.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_sim::{reference, FormatKind};
use tilerast_tests::{config, tri, vsub, Rng};

const W: u16 = 64;
const H: u16 = 48;

/// Coverage count per pixel, each triangle drawn alone into a fresh tile.
fn coverage(tris: &[[Vertex; 3]]) -> Vec<u32> {
    let mut count = vec![0u32; W as usize * H as usize];
    let mut tile: Box<Tile<512, Rgb888Format>> = Box::default();
    let c = config(W, H, FormatKind::Rgb888);
    for v in tris {
        tile.begin(Rect::new(0, 0, W as u32, H as u32), &Clear::default())
            .unwrap();
        let white = v.map(|v| Vertex {
            color: Rgb::new(255, 255, 255),
            ..v
        });
        tile.draw(&tri(white, 0)).unwrap();
        let exact = reference::render(&c, &[tri(white, 0)]);
        for y in 0..H as i32 {
            for x in 0..W as i32 {
                let i = (y * W as i32 + x) as usize;
                let hit = tile.raw(x, y).unwrap() != 0;
                assert_eq!(
                    hit,
                    exact.color[i][0] > 0.0,
                    "core and reference disagree at ({x}, {y})"
                );
                count[i] += hit as u32;
            }
        }
    }
    count
}

/// Twice the signed area (sub-pixel units) of `a, b, c`.
fn area2(t: &[Vertex; 3]) -> i64 {
    let p = t.map(|v| (v.x.to_bits() as i64, v.y.to_bits() as i64));
    (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0)
}

/// A jittered grid whose outer vertices lie beyond the screen. Jitter can
/// make a quad concave, and splitting it along the wrong diagonal folds
/// one triangle over its neighbour: such a mesh overlaps by construction,
/// so callers reject it (`folded`).
fn grid(seed: u64, n: i64) -> Vec<[Vertex; 3]> {
    let mut rng = Rng::new(seed);
    let (cw, ch) = ((W as i64 * 16 + 64) / n, (H as i64 * 16 + 64) / n);
    let mut pts = vec![];
    for j in 0..=n {
        for i in 0..=n {
            let jitter = |rng: &mut Rng, c: i64, k: i64| {
                if k == 0 || k == n {
                    0
                } else {
                    rng.range(-c / 3, c / 3)
                }
            };
            let x = -32 + i * cw + jitter(&mut rng, cw, i);
            let y = -32 + j * ch + jitter(&mut rng, ch, j);
            pts.push(vsub(x, y, 0, [0; 3]));
        }
    }
    let at = |i: i64, j: i64| pts[(j * (n + 1) + i) as usize];
    let mut tris = vec![];
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            let pair = if rng.range(0, 2) == 0 {
                [[a, b, d], [a, d, c]]
            } else {
                [[a, b, c], [b, d, c]]
            };
            for mut t in pair {
                // Either winding is drawn: reverse some.
                if rng.range(0, 2) == 0 {
                    t.swap(1, 2);
                }
                tris.push(t);
            }
        }
    }
    tris
}

/// Whether a grid from [`grid`] folded: its pairs come from quads `a, b,
/// c, d` in the unjittered orientation (positive area), possibly reversed,
/// so a fold is a triangle whose area sign disagrees with its reversal flag.
/// Since the reversal is random, check the unsigned form instead: in an
/// unfolded grid the areas sum to the grid's area exactly.
fn folded(tris: &[[Vertex; 3]]) -> bool {
    let sum: i64 = tris.iter().map(|t| area2(t).abs()).sum();
    let (w, h) = (W as i64 * 16 + 64, H as i64 * 16 + 64);
    let n = ((tris.len() / 2) as f64).sqrt() as i64;
    let (cw, ch) = (w / n, h / n);
    sum != 2 * (cw * n) * (ch * n)
}

/// A fan around a random centre with rim vertices far off screen.
fn fan(seed: u64, k: usize) -> Vec<[Vertex; 3]> {
    let mut rng = Rng::new(seed);
    let centre = vsub(
        rng.range(0, W as i64 * 16),
        rng.range(0, H as i64 * 16),
        0,
        [0; 3],
    );
    let rim: Vec<Vertex> = (0..k)
        .map(|i| {
            let a = i as f64 / k as f64 * std::f64::consts::TAU + rng.range(0, 100) as f64 * 1e-4;
            vsub(
                (centre.x.to_bits() as f64 + 4000.0 * a.cos()) as i64,
                (centre.y.to_bits() as f64 + 4000.0 * a.sin()) as i64,
                0,
                [0; 3],
            )
        })
        .collect();
    (0..k).map(|i| [centre, rim[i], rim[(i + 1) % k]]).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(12)))]
    #[test]
    fn jittered_grid_covers_every_pixel_once(seed in any::<u64>(), n in 2i64..12) {
        let tris = grid(seed, n);
        // Windings are mixed; a fold shows as triangles whose orientation,
        // corrected for the winding, is opposite to the others'. Reject those meshes.
        prop_assume!(!folded(&tris));
        let c = coverage(&tris);
        prop_assert!(c.iter().all(|&k| k == 1), "counts: {:?}", c.iter().filter(|&&k| k != 1).count());
    }

    #[test]
    fn fan_covers_every_pixel_once(seed in any::<u64>(), k in 3usize..40) {
        let c = coverage(&fan(seed, k));
        prop_assert!(c.iter().all(|&k| k == 1));
    }
}

#[test]
fn axis_aligned_shared_edges_through_pixel_centres() {
    // Edges exactly through pixel centres: the top-left rule must decide.
    let p = |x: i64, y: i64| vsub(x * 16 + 8, y * 16 + 8, 0, [0; 3]);
    let (x0, y0, x1, y1) = (-4, -4, W as i64 + 4, H as i64 + 4);
    let (xm, ym) = (20, 17);
    let quads = [
        (x0, y0, xm, ym),
        (xm, y0, x1, ym),
        (x0, ym, xm, y1),
        (xm, ym, x1, y1),
    ];
    let mut tris = vec![];
    for (a, b, c, d) in quads {
        tris.push([p(a, b), p(c, b), p(c, d)]);
        tris.push([p(a, b), p(c, d), p(a, d)]);
    }
    assert!(coverage(&tris).iter().all(|&k| k == 1));
}
