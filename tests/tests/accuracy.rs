//! Gouraud colour and Z against the f64 reference, within the bounds the
//! numeric contract states (`tilerast::numeric`): colour within
//! 0.5 + 2^-5 + 2^-10 LSB, Z within 0.5 + 2^-3 + 2^-9 LSB of the exact value.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_tests::{check_triangle as check, vsub};

fn vertex() -> impl Strategy<Value = Vertex> {
    // Screen is 96x64 = 1536x1024 sub-pixels; vertices reach 4 screens out.
    (
        -6000i64..7600,
        -4000i64..5000,
        0u16..65000,
        any::<[u8; 3]>(),
    )
        .prop_map(|(x, y, z, c)| vsub(x, y, z, c))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(200)))]
    #[test]
    fn gouraud_and_z_within_bound(v in [vertex(), vertex(), vertex()], tw in 5u16..96, th in 5u16..64) {
        check(96, 64, (tw, th), v)?;
    }

    #[test]
    fn small_and_sliver_triangles_within_bound(x in 0i64..1400, y in 0i64..900, d in prop::array::uniform4(-40i64..40), z in any::<[u16; 3]>(), c in any::<[[u8; 3]; 3]>()) {
        let z = z.map(|z| z.min(65000));
        let v = [vsub(x, y, z[0], c[0]), vsub(x + d[0], y + d[1], z[1], c[1]), vsub(x + d[2] * 30, y + d[3], z[2], c[2])];
        check(96, 64, (32, 16), v)?;
    }
}

#[test]
fn longest_span_drift_stays_within_bound() {
    // A 4096-pixel-wide row with the steepest colour and depth ramps across
    // it: the DDA runs the whole width from one restart.
    let w = 4096i64 * 16;
    let v = [
        vsub(0, 0, 0, [0, 255, 7]),
        vsub(w, 0, 65000, [255, 0, 200]),
        vsub(0, 2 * 16, 31000, [128, 3, 90]),
    ];
    let (c, z) = check(4096, 2, (4096, 2), v).unwrap();
    println!("longest span: colour error {c:.4} LSB, Z error {z:.4} LSB");
}

#[test]
fn largest_stepped_triangle_drift_stays_within_bound() {
    // The largest triangle set up in 32 bits (box just under 1024 px a
    // side), with steep ramps: every pixel's colour and Z come from the
    // anchor plane (`c + i gc + j gcy`), whose drift is at most one
    // half-unit per step along x and y plus the anchor's own rounding.
    let s = 16383i64;
    let v = [
        vsub(0, 0, 0, [0, 255, 7]),
        vsub(s, 40, 65000, [255, 0, 200]),
        vsub(30, s, 31000, [128, 3, 90]),
    ];
    let (c, z) = check(1024, 1024, (64, 32), v).unwrap();
    println!("largest stepped triangle: colour error {c:.4} LSB, Z error {z:.4} LSB");
}
