//! `docs/sizing.md`'s table is measured here: the bin passes, peak entries
//! and unbinned tiles of real frames for several bin capacities, rendered
//! by the `Renderer`. The test fails when the page and the measurement
//! disagree; `TILERAST_BLESS=1` rewrites the table.

use tilerast::prelude::*;
use tilerast_sim::Scene;
use tilerast_tests::{repo, scene};

/// One row: the frame's statistics with `CAP` bin entries in bands of up
/// to `TB` tiles, and the renderer's bytes.
fn row<const N: usize, const CAP: usize, const TB: usize>(
    name: &str,
    s: &Scene,
    tile: (u16, u16),
) -> String {
    type C = Planes<Rgb565Format, Depth16, Wid8, Bayer4, NoAa, FullPrecision, AlphaBlending>;
    let mut r: Renderer<C, N, CAP, TB> =
        Renderer::with_tile(s.config.width, s.config.height, tile.0, tile.1).unwrap();
    let st = r
        .render(&s.commands[..], |_| Ok::<(), ()>(()))
        .expect("renders");
    format!(
        "| {name} | {}x{} | {} | {CAP} x {TB} | {} | {} | {} | {} | {} |",
        tile.0,
        tile.1,
        s.commands.len(),
        Bins::<CAP, TB>::BYTES,
        st.bin_passes,
        st.bin_peak,
        st.unbinned_tiles,
        st.replayed,
    )
}

fn table() -> String {
    let demo = Scene::load(scene("demo.toml")).unwrap();
    let teapot = Scene::load(scene("teapot.toml")).unwrap();
    const T: usize = groups(64, 32);
    let rows = [
        row::<T, 64, 32>("demo", &demo, (64, 32)),
        row::<T, 256, 32>("demo", &demo, (64, 32)),
        row::<T, 1024, 32>("demo", &demo, (64, 32)),
        row::<T, 64, 32>("teapot", &teapot, (64, 32)),
        row::<T, 256, 32>("teapot", &teapot, (64, 32)),
        row::<T, 1024, 32>("teapot", &teapot, (64, 32)),
        row::<T, 4096, 32>("teapot", &teapot, (64, 32)),
        row::<T, 256, 32>("teapot", &teapot, (240, 8)),
        row::<T, 1024, 32>("teapot", &teapot, (240, 8)),
    ];
    let mut t = String::from(
        "| scene | tile | commands | bins (entries x tiles a band) | bin bytes | bin passes | peak entries | tiles unbinned | commands replayed |\n\
         | --- | --- | ---: | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for r in rows {
        t += &r;
        t.push('\n');
    }
    t
}

#[test]
fn the_sizing_page_is_measured() {
    let path = repo().join("docs/sizing.md");
    let page = std::fs::read_to_string(&path).unwrap();
    let (begin, end) = ("<!-- measured:begin -->\n", "<!-- measured:end -->");
    let a = page.find(begin).expect("begin marker") + begin.len();
    let b = page.find(end).expect("end marker");
    let now = table();
    if std::env::var_os("TILERAST_BLESS").is_some() {
        std::fs::write(&path, format!("{}{now}{}", &page[..a], &page[b..])).unwrap();
        return;
    }
    assert_eq!(
        page[a..b],
        now,
        "docs/sizing.md's table differs from the measurement (TILERAST_BLESS=1 rewrites it)"
    );
}
