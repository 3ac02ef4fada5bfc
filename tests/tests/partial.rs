//! Partial updates: a panel that receives only the tiles `Damage` reports
//! changed — found from their pixels after drawing, or from their commands
//! before (`Frame::render_changed`, which then draws only those) — ends
//! every frame of the animated gauge equal, pixel for pixel, to a full
//! refresh, and receives far fewer bytes.

use tilerast::bin::Bins;
use tilerast::prelude::*;
use tilerast_fw::anim::{self, AnimTile, Changes, FRAMES, SIDE};

#[test]
fn partial_updates_leave_the_panel_equal_to_full_refreshes() {
    for changes in [Changes::Output, Changes::Input] {
        partial_updates_match(changes);
    }
}

fn partial_updates_match(changes: Changes) {
    let n = SIDE as usize;
    let mut panel = vec![0u8; n * n * 2];
    let mut tile: Box<AnimTile> = Box::default();
    let run = anim::run(&mut tile, &mut || 0, changes, |t| {
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
    assert!(
        panel == full,
        "the partially updated panel differs ({changes:?})"
    );
    assert_eq!(run.tiles, FRAMES * anim::TILES as u32);
    // The needle moves every frame, so some tiles are resent, but far from all.
    assert!(
        run.sent_tiles > FRAMES && run.bytes_sent * 3 < run.bytes_full,
        "{run:?}"
    );
    match changes {
        Changes::Output => assert_eq!(run.drawn, run.tiles),
        // Far fewer tiles drawn: the first frame's, then those the
        // needle's bounds entered or left; of those, the ones whose pixels
        // changed were sent.
        Changes::Input => assert!(
            run.drawn >= run.sent_tiles && run.drawn * 3 < run.tiles,
            "{run:?}"
        ),
    }
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

/// `render_changed` on random scenes: frame after frame a few commands
/// move, change colour or depth, appear or vanish, with bins large enough
/// or too small (bands, unbinned tiles); the panel fed only the tiles it
/// drew always equals a full render, and a frame whose list did not change
/// draws nothing.
#[test]
fn render_changed_keeps_the_panel_equal_to_full_renders() {
    type T = Tile<{ groups(32, 16) }, Planes<Rgb565Format, Depth16>>;
    let (w, h) = (96u16, 64u16);
    let frame = T::frame::<32, 16>(w, h).unwrap();
    let mut rnd = {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        move |n: u32| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 16) as u32 % n
        }
    };
    let tri = |rnd: &mut dyn FnMut(u32) -> u32| {
        let v = |rnd: &mut dyn FnMut(u32) -> u32| {
            Vertex::new(
                Coord::from_bits(rnd(16 * 110) as i32 - 80),
                Coord::from_bits(rnd(16 * 80) as i32 - 80),
                rnd(65535) as u16,
                Rgb::new(rnd(256) as u8, rnd(256) as u8, rnd(256) as u8),
            )
        };
        Command::triangle([v(rnd), v(rnd), v(rnd)])
    };
    for bins_big in [true, false] {
        let mut list: Vec<Command> = (0..12).map(|_| tri(&mut rnd)).collect();
        list.push(Command::fill(
            Rect::new(10, 10, 20, 12),
            Rgb::new(9, 80, 200),
        ));
        let mut tile: Box<T> = Box::default();
        let (mut big, mut small) = (Bins::<256, 12>::new(), Bins::<1, 2>::new());
        let mut damage = Damage::<12>::new();
        let mut panel = vec![0u32; w as usize * h as usize];
        let mut unbinned = 0;
        for k in 0..40 {
            // Change the scene, except every fifth frame.
            if k % 5 != 4 {
                for _ in 0..1 + rnd(2) {
                    let i = rnd(list.len() as u32) as usize;
                    match rnd(4) {
                        0 => list[i] = tri(&mut rnd),
                        1 if list.len() > 4 => {
                            list.remove(i);
                        }
                        2 => list.push(tri(&mut rnd)),
                        _ => {
                            if let Command::Triangle { v, .. } = &mut list[i] {
                                v[rnd(3) as usize].color = Rgb::new(rnd(256) as u8, 1, 2);
                            }
                        }
                    }
                }
            }
            let mut drawn = 0;
            let put = |t: &mut T, panel: &mut Vec<u32>| {
                let a = t.area();
                for y in a.y..a.y + a.h as i32 {
                    for x in a.x..a.x + a.w as i32 {
                        panel[y as usize * w as usize + x as usize] = t.raw(x, y).unwrap();
                    }
                }
            };
            let stats = if bins_big {
                frame.render_changed(&mut tile, &mut big, &list[..], &mut damage, |t| {
                    drawn += 1;
                    put(t, &mut panel);
                    Ok::<(), ()>(())
                })
            } else {
                frame.render_changed(&mut tile, &mut small, &list[..], &mut damage, |t| {
                    drawn += 1;
                    put(t, &mut panel);
                    Ok::<(), ()>(())
                })
            }
            .unwrap();
            assert_eq!(stats.tiles + stats.unchanged_tiles, 12);
            unbinned += stats.unbinned_tiles;
            assert_eq!(stats.tiles, drawn);
            if k == 0 {
                assert_eq!(drawn, 12, "the first frame draws every tile");
            }
            if k % 5 == 4 {
                assert_eq!(drawn, 0, "frame {k}: nothing changed, nothing drawn");
            }
            let mut full = vec![0u32; w as usize * h as usize];
            frame
                .render_with(&mut tile, &list[..], |t| {
                    put(t, &mut full);
                    Ok::<(), ()>(())
                })
                .unwrap();
            assert!(panel == full, "frame {k}, big bins {bins_big}");
        }
        // The small bins overflow: bands, and tiles that replay the list.
        assert_eq!(unbinned > 0, !bins_big);
    }
}
