//! Window-ID isolation: random commands never change a pixel (colour or
//! depth) whose window ID differs from the command's.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_sim::{render, FormatKind};
use tilerast_tests::{config, random_command, Rng};

const W: u16 = 80;
const H: u16 = 60;

fn windows() -> Vec<Command> {
    vec![
        Command::WidFill {
            rect: Rect::new(5, 5, 40, 30),
            wid: 1,
        },
        Command::WidFill {
            rect: Rect::new(30, 20, 45, 35),
            wid: 2,
        },
        Command::WidFill {
            rect: Rect::new(60, 0, 20, 10),
            wid: 3,
        },
    ]
}

fn wid_at(x: i32, y: i32) -> u8 {
    let mut id = 0;
    for c in windows() {
        if let Command::WidFill { rect, wid } = c {
            if rect.intersect(&Rect::new(x, y, 1, 1)).is_some() {
                id = wid;
            }
        }
    }
    id
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(48)))]
    #[test]
    fn commands_stay_inside_their_window(seed in any::<u64>(), wid in 0u8..4, fmt in 0usize..5, tw in 7u16..80) {
        let formats = [FormatKind::Rgb888, FormatKind::Rgb565, FormatKind::Rgb444, FormatKind::Gray8, FormatKind::Binary];
        let mut c = config(W, H, formats[fmt]);
        c.depth = true;
        c.wid = true;
        c.dither = 4;
        c.tile = (tw, 13);
        let mut rng = Rng::new(seed);
        // A background that differs per window so that writes are visible.
        let mut base = windows();
        for w in 0..4u8 {
            base.push(Command::fill(Rect::new(0, 0, W as u32, H as u32), Rgb::new(w * 60, 255 - w * 50, 7)).window(w));
            base.push(Command::ZFill { rect: Rect::new(0, 0, W as u32, H as u32), z: 30000, state: State { wid: w, ..State::default() } });
        }
        let before = render(&c, &base).unwrap();
        let mut cmds = base.clone();
        for _ in 0..10 {
            cmds.push(random_command(&mut rng, wid));
        }
        let after = render(&c, &cmds).unwrap();
        for y in 0..H as i32 {
            for x in 0..W as i32 {
                let i = (y * W as i32 + x) as usize;
                if wid_at(x, y) != wid {
                    prop_assert_eq!(after.raw[i], before.raw[i], "colour changed at ({}, {}) in window {}", x, y, wid_at(x, y));
                    prop_assert_eq!(after.depth[i], before.depth[i]);
                }
            }
        }
    }
}

#[test]
fn isolation_is_not_vacuous() {
    // Same machinery, a command known to hit window 2: its pixels change.
    let mut c = config(W, H, FormatKind::Rgb565);
    c.wid = true;
    let mut cmds = windows();
    let before = render(&c, &cmds).unwrap();
    cmds.push(
        Command::fill(Rect::new(0, 0, W as u32, H as u32), Rgb::new(255, 255, 255)).window(2),
    );
    let after = render(&c, &cmds).unwrap();
    let changed = (0..before.raw.len())
        .filter(|&i| before.raw[i] != after.raw[i])
        .count();
    assert_eq!(changed, 45 * 35); // all of window 2, nothing else
}
