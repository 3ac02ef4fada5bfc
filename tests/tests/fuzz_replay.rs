//! The fuzz inputs replayed on stable, without libFuzzer: the hand-written
//! seeds (`fuzz/seeds/<target>/`, valid inputs that must reach the
//! oracles) and the corpora the fuzzer grew (`fuzz/corpus/<target>/`,
//! mostly inputs that explore the error paths), each through its target's
//! body ([`tilerast_tests::fuzz`]) and then through a deterministic set of
//! mutations, so a change that breaks an oracle fails here before anyone
//! fuzzes. `cargo xtask fuzz --seconds N` grows the corpora.

use tilerast_tests::{fuzz, repo, Rng};

type Body = fn(&[u8]) -> bool;

const TARGETS: [(&str, Body); 10] = [
    ("wire", fuzz::wire),
    ("commands", fuzz::commands),
    ("tile_api", fuzz::tile_api),
    ("scene", fuzz::scene),
    ("obj", fuzz::obj),
    ("mesh", fuzz::mesh),
    ("volume", fuzz::volume),
    ("occlusion", fuzz::occlusion),
    ("png", fuzz::png),
    ("nifti", fuzz::nifti),
];

/// Mutations per stored input (more with `FUZZ_REPLAY_MUTATIONS`).
fn mutations() -> u64 {
    std::env::var("FUZZ_REPLAY_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(8)
}

fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..1 + rng.range(0, 4) {
        let at = rng.range(0, v.len().max(1) as i64) as usize;
        let last = v.len().saturating_sub(1);
        match rng.range(0, 4) {
            0 if !v.is_empty() => v[at.min(last)] ^= 1 << rng.range(0, 8),
            1 if !v.is_empty() => v[at.min(last)] = rng.next_u64() as u8,
            2 => v.insert(at.min(v.len()), rng.next_u64() as u8),
            _ => v.truncate(at),
        }
    }
    v
}

/// The files of `fuzz/<kind>/<target>/`, sorted.
fn inputs(kind: &str, target: &str) -> Vec<std::path::PathBuf> {
    let dir = repo().join("fuzz").join(kind).join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{}: empty", dir.display());
    files
}

fn replay(name: &str, body: Body) {
    let seeds = inputs("seeds", name);
    for f in seeds.iter().chain(&inputs("corpus", name)) {
        let input = std::fs::read(f).unwrap();
        let reached = body(&input);
        // The oracles are not vacuous: every seed gets through to them.
        assert!(
            reached || !seeds.contains(f),
            "{}: a seed that does not reach the oracles",
            f.display()
        );
        let mut rng = Rng::new(input.len() as u64 ^ 0x9E37_79B9_7F4A_7C15);
        for _ in 0..mutations() {
            body(&mutate(&mut rng, &input));
        }
    }
}

/// One test per target, so they run in parallel and fail by name.
macro_rules! corpus_tests {
    ($($test:ident: $i:expr;)*) => {$(
        #[test]
        fn $test() {
            replay(TARGETS[$i].0, TARGETS[$i].1);
        }
    )*};
}

corpus_tests! {
    wire_corpus: 0;
    commands_corpus: 1;
    tile_api_corpus: 2;
    scene_corpus: 3;
    obj_corpus: 4;
    mesh_corpus: 5;
    volume_corpus: 6;
    occlusion_corpus: 7;
    png_corpus: 8;
    nifti_corpus: 9;
}

#[test]
fn every_fuzz_target_has_a_corpus_and_a_binary() {
    for (name, _) in TARGETS {
        assert!(
            repo()
                .join("fuzz/fuzz_targets")
                .join(format!("{name}.rs"))
                .exists(),
            "{name}"
        );
        assert!(repo().join("fuzz/corpus").join(name).is_dir(), "{name}");
        assert!(repo().join("fuzz/seeds").join(name).is_dir(), "{name}");
    }
}
