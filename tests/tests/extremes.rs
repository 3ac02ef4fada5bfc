//! Named extreme cases of the numeric contract: range limits and one past
//! them, NaN and infinities, degenerate triangles, depth at 0 and 65535, a
//! full display list, oversized tiles. Errors are values; nothing panics.

use tilerast::numeric::COORD_LIMIT;
use tilerast::prelude::*;
use tilerast_sim::{render, FormatKind};
use tilerast_tests::{config, tri, vsub};

#[test]
fn coordinates_at_the_limit_pass_and_one_past_fail() {
    let lim = COORD_LIMIT as i64 * 16;
    let ok = [
        vsub(-lim, -lim, 0, [1; 3]),
        vsub(lim - 1, -lim, 0, [1; 3]),
        vsub(0, lim - 1, 0, [1; 3]),
    ];
    let mut list: DisplayList<4> = DisplayList::new();
    assert_eq!(list.push(tri(ok, 0)), Ok(()));
    for bad in [
        vsub(lim, 0, 0, [0; 3]),
        vsub(0, lim, 0, [0; 3]),
        vsub(-lim - 1, 0, 0, [0; 3]),
        vsub(0, -lim - 1, 0, [0; 3]),
    ] {
        assert_eq!(
            list.push(tri([ok[0], ok[1], bad], 0)),
            Err(Error::CoordOutOfRange)
        );
        let mut tile: Tile<8, Rgb565Format> = Tile::new();
        tile.begin(Rect::new(0, 0, 8, 8), &Clear::default())
            .unwrap();
        assert_eq!(
            tile.draw(&tri([ok[0], ok[1], bad], 0)),
            Err(Error::CoordOutOfRange)
        );
    }
    // The triangle at the limits renders: it covers the whole screen.
    let c = config(40, 30, FormatKind::Rgb888);
    let r = render(&c, &list).unwrap();
    assert!(r.raw.iter().all(|&p| p == 0x010101));
}

#[test]
fn nan_and_infinities_are_errors() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(
            Vertex::try_from_f32(bad, 0.0, 0, Rgb::default()),
            Err(Error::NotFinite)
        );
        assert_eq!(
            Vertex::try_from_f32(0.0, bad, 0, Rgb::default()),
            Err(Error::NotFinite)
        );
    }
    assert_eq!(
        Vertex::try_from_f32(8192.0, 0.0, 0, Rgb::default()),
        Err(Error::CoordOutOfRange)
    );
    assert!(Vertex::try_from_f32(8191.9, -8192.0, 0, Rgb::default()).is_ok());
}

#[test]
fn full_display_list_is_an_error() {
    let mut list: DisplayList<3> = DisplayList::new();
    let f = Command::WidFill {
        rect: Rect::new(0, 0, 1, 1),
        wid: 1,
    };
    for _ in 0..3 {
        list.push(f).unwrap();
    }
    assert_eq!(list.push(f), Err(Error::ListFull));
    assert_eq!(list.len(), 3);
}

#[test]
fn degenerate_triangles_draw_nothing() {
    let c = config(32, 32, FormatKind::Rgb888);
    let cases = [
        [vsub(16, 16, 0, [255; 3]); 3], // a point
        [
            vsub(0, 0, 0, [255; 3]),
            vsub(300, 300, 0, [255; 3]),
            vsub(150, 150, 0, [255; 3]),
        ], // collinear
        [
            vsub(0, 8, 0, [255; 3]),
            vsub(500, 8, 0, [255; 3]),
            vsub(250, 8, 0, [255; 3]),
        ], // flat on centres
    ];
    for v in cases {
        let r = render(&c, &[tri(v, 0)]).unwrap();
        assert!(r.raw.iter().all(|&p| p == 0), "{v:?}");
    }
    // A sliver thinner than a sub-pixel still draws exactly the centres it covers.
    let v = [
        vsub(0, 8 * 16 + 8, 0, [255; 3]),
        vsub(512, 8 * 16 + 8, 0, [255; 3]),
        vsub(0, 8 * 16 + 9, 0, [255; 3]),
    ];
    let r = render(&c, &[tri(v, 0)]).unwrap();
    let lit: Vec<usize> = (0..r.raw.len()).filter(|&i| r.raw[i] != 0).collect();
    assert!(lit.iter().all(|&i| i / 32 == 8), "only row 8: {lit:?}");
}

#[test]
fn depth_at_zero_and_max() {
    let mut c = config(16, 16, FormatKind::Rgb888);
    c.depth = true;
    let big = |z: u16, col: [u8; 3]| {
        tri(
            [
                vsub(-99, -99, z, col),
                vsub(999, -99, z, col),
                vsub(-99, 999, z, col),
            ],
            0,
        )
    };
    // Z = 65535 never passes "less than" the cleared far plane (65535).
    let r = render(&c, &[big(65535, [255; 3])]).unwrap();
    assert!(r.raw.iter().all(|&p| p == 0));
    // Z = 0 passes once; a second Z = 0 does not (strictly less).
    let r = render(&c, &[big(0, [10; 3]), big(0, [20; 3])]).unwrap();
    assert!(r.raw.iter().all(|&p| p == 0x0A0A0A));
    assert!(r.depth.iter().all(|&z| z == 0));
    // 65534 passes against the cleared 65535.
    let r = render(&c, &[big(65534, [30; 3])]).unwrap();
    assert!(r.depth.iter().all(|&z| z == 65534));
}

#[test]
fn longest_span_and_out_of_range_spans() {
    let mut c = config(4096, 1, FormatKind::Rgb888);
    c.tile = (1000, 1);
    // 12096 pixels from far left: only the visible part is drawn, exactly;
    // values above 255 (up to 255.79 here) saturate.
    let span = SpanCmd {
        x: -8000,
        y: 0,
        len: 12096,
        color: [ColorFix::ZERO; 3],
        dcolor: [ColorStep::from_bits(1386), ColorStep::ZERO, ColorStep::ZERO], // 255/12096 per pixel
        z: ZFix::ZERO,
        dz: ZStep::ZERO,
        alpha: 255,
    };
    assert_eq!(span.validate(), Ok(()));
    let r = render(
        &c,
        &[Command::Span {
            span,
            state: State::default(),
        }],
    )
    .unwrap();
    for x in [0usize, 1, 2047, 4095] {
        let exact = ((8000 + x) as f64 * 1386.0 / 65536.0).min(255.0);
        let got = (r.raw[x] >> 16) as f64;
        assert!((got - exact).abs() <= 0.5 + 1e-9, "x={x}: {got} vs {exact}");
    }
    // A slightly steeper ramp ends at 256.1: outside 0..256, refused.
    let too_long = SpanCmd {
        dcolor: [ColorStep::from_bits(1388), ColorStep::ZERO, ColorStep::ZERO],
        ..span
    };
    assert_eq!(too_long.validate(), Err(Error::SpanOutOfRange));
    let negative = SpanCmd {
        dcolor: [ColorStep::from_num(-1), ColorStep::ZERO, ColorStep::ZERO],
        ..span
    };
    assert_eq!(negative.validate(), Err(Error::SpanOutOfRange));
    let past = SpanCmd {
        x: COORD_LIMIT - 10,
        len: 11,
        ..span
    };
    assert_eq!(past.validate(), Err(Error::CoordOutOfRange));
}

#[test]
fn bad_sizes_and_oversized_tiles_are_errors() {
    assert_eq!(Frame::new(0, 10, 8, 8), Err(Error::BadSize));
    assert_eq!(Frame::new(10, 4097, 8, 8), Err(Error::BadSize));
    let mut tile: Tile<2, Gray8Format> = Tile::new(); // 16 pixels
    assert_eq!(
        tile.begin(Rect::new(0, 0, 5, 4), &Clear::default()),
        Err(Error::TileTooLarge)
    );
    assert_eq!(
        tile.begin(Rect::new(0, 0, 0, 4), &Clear::default()),
        Err(Error::BadSize)
    );
    let frame = Frame::new(10, 10, 5, 4).unwrap();
    let none: &[Command] = &[];
    let r = frame.render_with(&mut tile, none, |_| Ok::<(), ()>(()));
    assert_eq!(r, Err(FlushError::Raster(Error::TileTooLarge)));
}

/// `Rect::intersect` works in 32 bits; this is its definition in 64, over
/// rectangles at every edge of `i32` and `u32` (proptest).
fn intersect_i64(a: &Rect, b: &Rect) -> Option<Rect> {
    let (x0, y0) = ((a.x as i64).max(b.x as i64), (a.y as i64).max(b.y as i64));
    let (x1, y1) = (a.x1().min(b.x1()), a.y1().min(b.y1()));
    (x0 < x1 && y0 < y1)
        .then(|| Rect::new(x0 as i32, y0 as i32, (x1 - x0) as u32, (y1 - y0) as u32))
}

fn edge_i32() -> impl proptest::strategy::Strategy<Value = i32> {
    use proptest::prelude::*;
    prop_oneof![
        any::<i32>(),
        -40i32..40,
        (i32::MAX - 40)..=i32::MAX,
        i32::MIN..(i32::MIN + 40)
    ]
}

fn edge_u32() -> impl proptest::strategy::Strategy<Value = u32> {
    use proptest::prelude::*;
    prop_oneof![any::<u32>(), 0u32..40, (u32::MAX - 40)..=u32::MAX]
}

proptest::proptest! {
    #[test]
    fn rect_intersection_matches_its_64_bit_definition(
        a in (edge_i32(), edge_i32(), edge_u32(), edge_u32()),
        b in (edge_i32(), edge_i32(), edge_u32(), edge_u32()),
    ) {
        let (a, b) = (Rect::new(a.0, a.1, a.2, a.3), Rect::new(b.0, b.1, b.2, b.3));
        proptest::prop_assert_eq!(a.intersect(&b), intersect_i64(&a, &b));
        proptest::prop_assert_eq!(b.intersect(&a), intersect_i64(&a, &b));
    }
}
