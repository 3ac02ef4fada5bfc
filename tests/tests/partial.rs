//! Partial updates: a panel that receives only the tiles `Damage` reports
//! changed ends every frame of the animated gauge equal, pixel for pixel,
//! to a full refresh — and receives far fewer bytes.

use tilerast::prelude::*;
use tilerast_fw::anim::{self, AnimTile, FRAMES, SIDE};

#[test]
fn partial_updates_leave_the_panel_equal_to_full_refreshes() {
    let n = SIDE as usize;
    let mut panel = vec![0u8; n * n * 2];
    let mut tile: Box<AnimTile> = Box::default();
    let run = anim::run(&mut tile, &mut || 0, |t| {
        // Copy the sent tile's panel bytes into the panel.
        let a = t.area();
        let mut buf = vec![0u8; AnimTile::panel_len(a.w, a.h)];
        t.panel_bytes(&mut buf).unwrap();
        for row in 0..a.h as usize {
            let src = &buf[row * a.w as usize * 2..(row + 1) * a.w as usize * 2];
            let at = ((a.y as usize + row) * n + a.x as usize) * 2;
            panel[at..at + src.len()].copy_from_slice(src);
        }
    })
    .unwrap();
    // The panel after the last frame equals a full render of it.
    let frame = AnimTile::frame::<64, 32>(SIDE, SIDE).unwrap();
    let cmds = anim::frame_commands(FRAMES - 1);
    let mut full = vec![0u8; n * n * 2];
    frame
        .render_with(&mut tile, &cmds[..], |t| {
            let a = t.area();
            let mut buf = vec![0u8; AnimTile::panel_len(a.w, a.h)];
            t.panel_bytes(&mut buf).unwrap();
            for row in 0..a.h as usize {
                let src = &buf[row * a.w as usize * 2..(row + 1) * a.w as usize * 2];
                let at = ((a.y as usize + row) * n + a.x as usize) * 2;
                full[at..at + src.len()].copy_from_slice(src);
            }
            Ok::<(), ()>(())
        })
        .unwrap();
    assert!(panel == full, "the partially updated panel differs");
    assert_eq!(run.tiles, FRAMES * anim::TILES as u32);
    // The needle moves every frame, so some tiles are resent, but far from all.
    assert!(
        run.sent_tiles > FRAMES && run.bytes_sent * 3 < run.bytes_full,
        "{run:?}"
    );
}

#[test]
fn every_frame_of_the_gauge_matches_a_full_refresh() {
    // Frame by frame: replay the animation k frames, compare the panel.
    let n = SIDE as usize;
    let frame = AnimTile::frame::<64, 32>(SIDE, SIDE).unwrap();
    let mut tile: Box<AnimTile> = Box::default();
    let mut damage: Damage<{ anim::TILES }> = Damage::new();
    let mut panel = vec![0u32; n * n];
    for k in 0..FRAMES {
        let cmds = anim::frame_commands(k);
        frame
            .render_with(&mut tile, &cmds[..], |t| {
                if damage.changed(&frame, t) {
                    let a = t.area();
                    for y in a.y..a.y + a.h as i32 {
                        for x in a.x..a.x + a.w as i32 {
                            panel[y as usize * n + x as usize] = t.raw(x, y).unwrap();
                        }
                    }
                }
                Ok::<(), ()>(())
            })
            .unwrap();
        let mut full = vec![0u32; n * n];
        frame
            .render_with(&mut tile, &cmds[..], |t| {
                let a = t.area();
                for y in a.y..a.y + a.h as i32 {
                    for x in a.x..a.x + a.w as i32 {
                        full[y as usize * n + x as usize] = t.raw(x, y).unwrap();
                    }
                }
                Ok::<(), ()>(())
            })
            .unwrap();
        assert!(panel == full, "frame {k}");
    }
}
