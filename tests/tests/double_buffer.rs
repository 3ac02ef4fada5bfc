//! The seed's double buffer (seed 001 §II.2): two dithered RGB444 images in
//! one 24-bit plane ([`Rgb444PairFormat`]). Drawing a frame into one half
//! through its plane mask gives exactly the picture the same commands give
//! in a plain dithered RGB444 tile, and leaves the other half untouched —
//! over random command lists (triangles, spans, lines, antialiased edges,
//! fills).

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_tests::{random_command, Rng};

const W: u32 = 48;
const H: u32 = 40;
type Pair = Planes<Rgb444PairFormat, Depth16, NoWid, Bayer8>;
type Plain = Planes<Rgb444Format, Depth16, NoWid, Bayer8>;
const N: usize = (W * H / 8) as usize;

/// A frame: a masked clear of the back half (colour and depth), then the
/// commands, each with the back half's plane mask.
fn frame(seed: u64, half: Half) -> Vec<Command> {
    let mut rng = Rng::new(seed);
    let mut state = State::new(0);
    state.plane_mask = half.mask();
    let screen = Rect::new(0, 0, W, H);
    let mut out = vec![
        Command::Fill {
            rect: screen,
            color: Rgb::new(seed as u8, 40, 200),
            state,
            alpha: 255,
        },
        Command::ZFill {
            rect: screen,
            z: u16::MAX,
            state,
        },
    ];
    for _ in 0..40 {
        let mut c = random_command(&mut rng, 0);
        match &mut c {
            Command::Triangle { state: s, .. }
            | Command::Span { state: s, .. }
            | Command::Line { state: s, .. }
            | Command::Edge { state: s, .. }
            | Command::Fill { state: s, .. } => s.plane_mask = half.mask(),
            _ => continue,
        }
        out.push(c);
    }
    out
}

/// The same commands in a plain RGB444 tile, unmasked.
fn plain(cmds: &[Command]) -> Vec<Rgb444> {
    let mut t: Tile<N, Plain> = Tile::new();
    t.begin(Rect::new(0, 0, W, H), &Clear::default()).unwrap();
    for c in cmds {
        let mut c = *c;
        match &mut c {
            Command::Triangle { state, .. }
            | Command::Span { state, .. }
            | Command::Line { state, .. }
            | Command::Edge { state, .. }
            | Command::Fill { state, .. }
            | Command::ZFill { state, .. } => state.plane_mask = u32::MAX,
            _ => {}
        }
        let _ = t.draw(&c);
    }
    (0..H as i32)
        .flat_map(|y| (0..W as i32).map(move |x| (x, y)))
        .map(|(x, y)| t.pixel(x, y).unwrap())
        .collect()
}

fn half_of(t: &Tile<N, Pair>, h: Half) -> Vec<Rgb444> {
    (0..H as i32)
        .flat_map(|y| (0..W as i32).map(move |x| (x, y)))
        .map(|(x, y)| Rgb444PairFormat::half(t.raw(x, y).unwrap(), h))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(64)))]
    #[test]
    fn each_half_is_its_own_dithered_rgb444_frame(a in any::<u64>(), b in any::<u64>()) {
        let mut t: Tile<N, Pair> = Tile::new();
        t.begin(Rect::new(0, 0, W, H), &Clear::default()).unwrap();
        // Frame 1 into the low half, frame 2 into the high half while the
        // low one is "shown", then frame 3 into the low half again.
        let (f1, f2, f3) = (frame(a, Half::Low), frame(b, Half::High), frame(a ^ b, Half::Low));
        for c in &f1 {
            let _ = t.draw(c);
        }
        prop_assert_eq!(half_of(&t, Half::Low), plain(&f1));
        for c in &f2 {
            let _ = t.draw(c);
        }
        prop_assert_eq!(half_of(&t, Half::High), plain(&f2));
        prop_assert_eq!(half_of(&t, Half::Low), plain(&f1), "frame 2 changed the front half");
        for c in &f3 {
            let _ = t.draw(c);
        }
        prop_assert_eq!(half_of(&t, Half::Low), plain(&f3));
        prop_assert_eq!(half_of(&t, Half::High), plain(&f2), "frame 3 changed the front half");
    }
}

#[test]
fn the_pair_costs_three_bytes_a_pixel() {
    // Two 12-bit images in 3 bytes a pixel, against 4 for two RGB565
    // buffers (colour plane only; the depth plane is the scene's choice).
    assert_eq!(Tile::<N, Rgb444PairFormat>::bits_per_pixel(), 24);
    assert_eq!(2 * Tile::<N, Rgb565Format>::bits_per_pixel(), 32);
}
