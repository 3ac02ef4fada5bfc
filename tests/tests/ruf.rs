//! The RUF buffer (seed 000): the paper's worked example (Fig. 5, eqs. 4
//! and 5), complementary coverage on shared edges, and the bounds of the
//! fixed-point colour accumulator under adversarial fragment orders.

use proptest::prelude::*;
use tilerast::coverage::*;
use tilerast::prelude::*;
use tilerast_tests::{vsub, Rng};

fn frag(mask: Mask, z: u16, c: [u8; 3], tag: u16) -> Fragment<8> {
    Fragment {
        mask,
        z: [z; 8],
        color: Rgb::new(c[0], c[1], c[2]),
        tag,
    }
}

/// The accumulator in levels (8.8 to f64).
fn acc(p: &RufPixel<8>) -> [f64; 3] {
    p.c_ff.map(|v| v as f64 / 256.0)
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

const A: [u8; 3] = [200, 40, 0];
const B: [u8; 3] = [0, 160, 80];
const C: [u8; 3] = [40, 40, 240];

fn col(c: [u8; 3]) -> [f64; 3] {
    c.map(|v| v as f64)
}

fn lin(terms: &[(f64, [f64; 3])]) -> [f64; 3] {
    std::array::from_fn(|i| terms.iter().map(|(w, c)| w * c[i]).sum())
}

#[test]
fn worked_example_eq4_and_eq5_case_a() {
    // Fig. 5: A covers 2 of 8 samples; B (nearer) covers 4 and hides one of
    // A's; C (nearest) covers 4 and hides one of B's. C_∅ = 0.
    let mut p = RufPixel::<8>::new(u16::MAX);
    p.update(&frag(0b0000_0011, 300, A, 1));
    assert!(close(acc(&p), lin(&[(2.0 / 8.0, col(A))]), 0.01)); // eq. 4, C_A
    p.update(&frag(0b0001_1110, 200, B, 2));
    let c_ab = lin(&[
        (2.0 / 8.0, col(A)),
        (4.0 / 8.0, col(B)),
        (-1.0 / 8.0, col(A)),
    ]);
    assert!(close(acc(&p), c_ab, 0.01)); // eq. 4, C_AB
    assert_eq!((p.tag, p.m_ruf), (2, 0b0001_1110));
    p.update(&frag(0b1111_0000, 100, C, 3));
    // Eq. 5: the sample C hides is in the RUF buffer (B): exact.
    let c_abc = lin(&[(1.0, c_ab), (4.0 / 8.0, col(C)), (-1.0 / 8.0, col(B))]);
    assert!(close(acc(&p), c_abc, 0.01), "{:?} vs {c_abc:?}", acc(&p));
    // And equal to 8-sample supersampling of the same fragments.
    let mut ss = SsPixel::<8>::new(Rgb::new(0, 0, 0), u16::MAX);
    for f in [
        frag(0b0000_0011, 300, A, 1),
        frag(0b0001_1110, 200, B, 2),
        frag(0b1111_0000, 100, C, 3),
    ] {
        ss.update(&f);
    }
    assert_eq!(p.resolve(Rgb::new(0, 0, 0)), ss.resolve());
}

#[test]
fn worked_example_case_b_uses_the_estimate() {
    // C hides one of A's samples instead: the RUF buffer holds B, so that
    // sample's colour is estimated (eq. 3's fourth term) by the mean of the
    // covered samples the RUF entry does not explain — here A's remaining
    // sample, so the estimate is exact. (The paper's literal term, the
    // pixel's whole colour C_AB, would be off by (C_AB - A) / 8.)
    let mut p = RufPixel::<8>::new(u16::MAX);
    p.update(&frag(0b0000_0011, 300, A, 1));
    p.update(&frag(0b0001_1110, 200, B, 2));
    let c_ab = acc(&p);
    p.update(&frag(0b1110_0001, 100, C, 3));
    let exact = lin(&[(1.0, c_ab), (4.0 / 8.0, col(C)), (-1.0 / 8.0, col(A))]);
    assert!(close(acc(&p), exact, 0.02), "{:?} vs {exact:?}", acc(&p));
    // Two objects outside the RUF entry: their mean stands in.
    let mut p = RufPixel::<8>::new(u16::MAX);
    p.update(&frag(0b0000_0001, 300, A, 1));
    p.update(&frag(0b0000_0010, 300, C, 3));
    p.update(&frag(0b0001_1100, 200, B, 2));
    let before = acc(&p);
    p.update(&frag(0b0000_0001, 100, B, 4)); // hides A, RUF holds B
    let mean = lin(&[(0.5, col(A)), (0.5, col(C))]);
    let want = lin(&[(1.0, before), (1.0 / 8.0, col(B)), (-1.0 / 8.0, mean)]);
    assert!(close(acc(&p), want, 0.02), "{:?} vs {want:?}", acc(&p));
}

#[test]
fn fragments_of_one_object_merge() {
    // Eqs. 6 and 7: two fragments with one tag leave one RUF fragment with
    // the union mask and the area-weighted colour.
    let mut p = RufPixel::<8>::new(u16::MAX);
    p.update(&frag(0b0000_0111, 50, [240, 0, 0], 7));
    p.update(&frag(0b0001_1000, 50, [0, 0, 160], 7));
    assert_eq!((p.tag, p.m_ruf), (7, 0b0001_1111));
    assert_eq!(p.c_ruf, Rgb::new(144, 0, 64)); // (3 x 240) / 5, (2 x 160) / 5
                                               // A different object replaces it.
    p.update(&frag(0b1000_0000, 40, [1, 2, 3], 8));
    assert_eq!(
        (p.tag, p.m_ruf, p.c_ruf),
        (8, 0b1000_0000, Rgb::new(1, 2, 3))
    );
}

fn masks_complement<P: SamplePattern>(rng: &mut Rng) {
    // A quad split along a diagonal, and a triangle split into a fan:
    // no sample of any pixel is covered twice, and the fan covers exactly
    // what the whole triangle covers.
    let mut pt = || vsub(rng.range(-64, 32 * 16), rng.range(-64, 32 * 16), 0, [0; 3]);
    let (a, b, c, d) = (pt(), pt(), pt(), pt());
    // Split along ac when b and d lie on opposite sides of it (else the
    // halves overlap as areas, not just at the edge).
    let side = |p: Vertex, q: Vertex, r: Vertex| {
        let f = |v: Vertex| (v.x.to_bits() as i64, v.y.to_bits() as i64);
        let (p, q, r) = (f(p), f(q), f(r));
        ((q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)).signum()
    };
    if side(a, c, b) * side(a, c, d) >= 0 {
        return;
    }
    let whole = [[a, b, c], [a, c, d]];
    for py in -2..34 {
        for px in -2..34 {
            let m = whole.map(|t| triangle_mask::<P>(&t, px, py));
            assert_eq!(m[0] & m[1], 0, "{} at ({px}, {py})", P::NAME);
        }
    }
    // A fan around an inside point of triangle abc: its pieces partition
    // the triangle's samples exactly.
    let (x, y) = (
        (a.x.to_bits() + b.x.to_bits() + c.x.to_bits()) / 3,
        (a.y.to_bits() + b.y.to_bits() + c.y.to_bits()) / 3,
    );
    let o = vsub(x as i64, y as i64, 0, [0; 3]);
    let s = side(a, b, c);
    // The rounded centroid of a sliver can fall outside it.
    if s == 0 || side(a, b, o) != s || side(b, c, o) != s || side(c, a, o) != s {
        return;
    }
    let fan = [[o, a, b], [o, b, c], [o, c, a]];
    for py in -2..34 {
        for px in -2..34 {
            let m = fan.map(|t| triangle_mask::<P>(&t, px, py));
            let all = triangle_mask::<P>(&[a, b, c], px, py);
            assert_eq!(
                m[0] & m[1] | m[1] & m[2] | m[0] & m[2],
                0,
                "{} at ({px}, {py})",
                P::NAME
            );
            assert_eq!(m[0] | m[1] | m[2], all, "{} at ({px}, {py})", P::NAME);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(64)))]
    /// Shared edges split samples: no sample is covered twice.
    #[test]
    fn shared_edges_cover_complementary_samples(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        masks_complement::<Sparse4>(&mut rng);
        masks_complement::<Sparse8>(&mut rng);
        masks_complement::<Sparse16>(&mut rng);
        masks_complement::<Grid8x8>(&mut rng);
    }

    /// Hundreds of fragments in an order the RUF buffer explains exactly:
    /// each hides only samples of the one before it (which the RUF buffer
    /// holds) and may cover free ones. The only error left is the
    /// accumulator's rounding — at most 1.5/256 of a level per update
    /// (three rounded terms) — plus 1 for the two final roundings.
    #[test]
    fn accumulator_does_not_drift(seed in any::<u64>(), n in 64usize..400) {
        let mut rng = Rng::new(seed);
        let bg = rng.rgb();
        let mut p = RufPixel::<64>::new(u16::MAX);
        let mut ss = SsPixel::<64>::new(bg, u16::MAX);
        for k in 0..n {
            let mask = (p.m_ruf & rng.next_u64()) | (!p.m_ff & rng.next_u64() & rng.next_u64());
            let f = Fragment { mask, z: [(60000 - k * 100) as u16; 64], color: rng.rgb(), tag: k as u16 };
            p.update(&f);
            ss.update(&f);
        }
        let (r, s) = (p.resolve(bg), ss.resolve());
        let bound = 1.5 * n as f64 / 256.0 + 1.0;
        for (a, b) in [(r.r, s.r), (r.g, s.g), (r.b, s.b)] {
            prop_assert!((a as f64 - b as f64).abs() <= bound, "{:?} vs {:?} after {} updates", r, s, n);
        }
    }

    /// Adversarial orders: random masks and depths, so fragments hide
    /// samples of any earlier fragment and eq. 3's estimate is used often.
    /// Each estimated sample can be off by at most 255 levels / T, each
    /// update rounds three terms (1.5/256), the clamp only moves towards
    /// the true range: the resolved colour is within the sum of those of
    /// supersampling (with unique tags, so the RUF entry is one fragment's),
    /// and the accumulator never leaves `[0, 255 N(M_ff) / T]`.
    #[test]
    fn adversarial_orders_stay_within_the_estimate_bound(seed in any::<u64>(), n in 1usize..500, tags in 1u64..4) {
        let mut rng = Rng::new(seed);
        let bg = rng.rgb();
        let mut p = RufPixel::<16>::new(u16::MAX);
        let mut ss = SsPixel::<16>::new(bg, u16::MAX);
        let mut bound = 1.0;
        for k in 0..n {
            let z: [u16; 16] = std::array::from_fn(|_| rng.range(0, 65535) as u16);
            let tag = if tags == 1 { k as u16 } else { rng.range(0, tags as i64) as u16 };
            let f = Fragment { mask: rng.next_u64() & 0xFFFF, z, color: rng.rgb(), tag };
            let before = p;
            let sur = p.update(&f);
            ss.update(&f);
            let est = count(sur & before.m_ff & !before.m_ruf);
            bound += 255.0 * est as f64 / 16.0 + 1.5 / 256.0;
            let cap = (255u32 * 256 * count(p.m_ff)).div_ceil(16);
            prop_assert!(p.c_ff.iter().all(|&v| v as u32 <= cap));
        }
        if tags == 1 {
            let (r, s) = (p.resolve(bg), ss.resolve());
            for (a, b) in [(r.r, s.r), (r.g, s.g), (r.b, s.b)] {
                prop_assert!((a as f64 - b as f64).abs() <= bound, "{:?} vs {:?}, bound {}", r, s, bound);
            }
        }
    }
}

#[test]
fn table_3_from_the_formula() {
    // Seed 000 Table 3 with C = Z = 32 bits, tag = 16: bytes per pixel.
    let rows: Vec<(u32, u32, u32)> = [4, 8, 16, 64]
        .iter()
        .map(|&m| (m, ss_bits(m, 32, 32) / 8, ruf_bits(m, 32, 32, 16) / 8))
        .collect();
    assert_eq!(
        rows,
        [(4, 32, 27), (8, 64, 44), (16, 128, 78), (64, 512, 282)]
    );
}

mod tiles {
    use super::*;
    use tilerast_sim::{metrics, render, AaKind, Scene};

    fn scene() -> Scene {
        Scene::load(tilerast_tests::scene("ruf.toml")).unwrap()
    }

    #[test]
    fn coverage_frames_are_tile_size_independent() {
        let s = scene();
        for aa in [AaKind::Ruf8, AaKind::Ss4, AaKind::Ruf16] {
            let mut c = s.config;
            c.aa = aa;
            let whole = render(&c, &s.commands).unwrap();
            for tile in [(17, 23), (160, 12), (7, 120)] {
                c.tile = tile;
                let r = render(&c, &s.commands).unwrap();
                assert_eq!(r.raw, whole.raw, "{aa:?} tile {tile:?}");
            }
        }
    }

    #[test]
    fn ruf8_is_as_good_as_8_sparse_supersampling_on_one_surface_per_object() {
        // The paper's claim (Table 2) on a scene that meets its assumption
        // (back faces culled, objects apart): RUF-8 within 5% of 8ss, both
        // far better than one sample, against 8x8 supersampling.
        let s = scene();
        let mut c = s.config;
        c.format = tilerast_sim::FormatKind::Rgb888;
        let base = c;
        let err = |aa: AaKind, reference: &tilerast_sim::Image| {
            let mut c = base;
            c.aa = aa;
            let img = render(&c, &s.commands).unwrap().image;
            metrics::compare(&img, reference).unwrap().sse as f64
        };
        c.aa = AaKind::Grid8;
        let reference = render(&c, &s.commands).unwrap().image;
        let (one, ss8, ruf8) = (
            err(AaKind::None, &reference),
            err(AaKind::Ss8, &reference),
            err(AaKind::Ruf8, &reference),
        );
        assert!(ruf8 < ss8 * 1.05, "RUF-8 {ruf8} vs 8ss {ss8}");
        assert!(ruf8 < one / 5.0, "RUF-8 {ruf8} vs 1 sample {one}");
    }

    #[test]
    fn one_centre_sample_is_the_aliased_pipeline() {
        // Supersampling with one sample at the pixel centre covers exactly
        // the pixels the pipeline does (same fill rule, same depth test);
        // its colour is the Gouraud value at the centre rounded to 8 bits,
        // so within 1 LSB of the span DDA's.
        let mut rng = Rng::new(5);
        let cmds: Vec<Command> = (0..40)
            .map(|_| Command::Triangle {
                v: rng.triangle((-100, 700), (-100, 600)),
                state: State::default(),
            })
            .collect();
        let area = Rect::new(0, 0, 40, 32);
        let mut a: Box<Tile<160, Planes<Rgb888Format, Depth16>>> = Box::default();
        type OneSample = Planes<Rgb888Format, Depth16, NoWid, NoDither, Ss1>;
        let mut b: Box<Tile<160, OneSample>> = Box::default();
        a.begin(area, &Clear::default()).unwrap();
        b.begin(area, &Clear::default()).unwrap();
        for c in &cmds {
            a.draw(c).unwrap();
            b.draw(c).unwrap();
        }
        assert!(b.finish());
        for y in 0..32 {
            for x in 0..40 {
                let (p, q) = (a.raw(x, y).unwrap(), b.raw(x, y).unwrap());
                for sh in [0, 8, 16] {
                    let d = ((p >> sh) & 255).abs_diff((q >> sh) & 255);
                    assert!(d <= 1, "({x}, {y}): {p:06x} vs {q:06x}");
                }
            }
        }
    }
}
