//! Phase I of one of the volume report's renders, timed `n` times in one
//! process (`reports/volume.md`'s "phase I ms" column, without the other
//! columns' renders): the median, the minimum, and a hash of the image so a
//! change to the fetch can be checked for identical output. Run under
//! `valgrind --tool=callgrind` with a small `n` for instruction counts.
//!
//! `volume_cost <sphere|mri64|mri128|mri256> <viewport> <n>`

use tilerast_lab::volume;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, set, vp, n] = &args[..] else {
        eprintln!("usage: volume_cost <sphere|mri64|mri128|mri256> <viewport> <n>");
        std::process::exit(2);
    };
    let (vp, n): (u16, usize) = (vp.parse().expect("a viewport"), n.parse().expect("a count"));
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let want = match set.as_str() {
        "sphere" => "sphere".to_string(),
        s => format!("MRI {}^3", s.trim_start_matches("mri")),
    };
    let sets = volume::datasets(&root).expect("datasets load");
    let Some((name, data)) = sets.into_iter().find(|(name, _)| *name == want) else {
        eprintln!("no dataset {want}");
        std::process::exit(2);
    };
    let tf = if name == "sphere" { "sphere" } else { "cortex" };
    let side = data.dims[0];
    let vs = volume::scene(data, tf, false, side).expect("scene");
    let cfg = volume::config(vp);
    let mut times = Vec::with_capacity(n);
    let mut last = None;
    for _ in 0..n.max(1) {
        let (img, t) = volume::run_normal(&vs, &cfg, true).expect("renders");
        times.push(t.phase1_ns / 1e6);
        last = Some(img);
    }
    // FNV-1a of the last image's bytes (every render draws the same).
    let hash = last.map_or(0, |img| {
        img.pixels
            .iter()
            .flatten()
            .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
                (h ^ b as u64).wrapping_mul(0x1000_0000_01b3)
            })
    });
    times.sort_by(f64::total_cmp);
    println!(
        "{name} {vp}^2 phase I median {:.2} ms min {:.2} ms over {} image 0x{hash:016x}",
        times[times.len() / 2],
        times[0],
        times.len()
    );
}
