//! One scene of the culling report walked in one mode, `n` times in one
//! process (`reports/cull.md`'s "µs / frame" column for that row, without
//! the other rows): the median over the frames of each frame's fastest
//! walk. Run under `valgrind --tool=callgrind` with `n` = 1 for
//! instruction counts of one mode alone.
//!
//! `cull_cost <scene 0-3> <none|s&w|chc|single-pass> <frames> <n>`

use tilerast::occlusion::CullMode;
use tilerast_lab::cull;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, scene, mode, frames, n] = &args[..] else {
        eprintln!("usage: cull_cost <scene 0-3> <none|s&w|chc|single-pass> <frames> <n>");
        std::process::exit(2);
    };
    let scenes = cull::scenes();
    let (name, place) = scenes[scene.parse::<usize>().expect("a scene index").min(3)];
    let mode = CullMode::ALL
        .into_iter()
        .find(|m| m.name() == mode)
        .expect("a mode: none, s&w, chc or single-pass");
    let frames: u32 = frames.parse().expect("a frame count");
    let mut best: Vec<f64> = vec![];
    let mut stats = None;
    for _ in 0..n.parse::<usize>().expect("a count").max(1) {
        let (t, s) = cull::walk_times(&place, frames.max(2), mode).expect("walks");
        best = if best.is_empty() {
            t
        } else {
            best.iter().zip(t).map(|(a, b)| a.min(b)).collect()
        };
        stats = Some(s);
    }
    best.sort_by(f64::total_cmp);
    println!(
        "{name}, {}: median {:.1} µs a frame over {} frames; {:?}",
        mode.name(),
        best[best.len() / 2] / 1e3,
        best.len(),
        stats.expect("walked")
    );
}
