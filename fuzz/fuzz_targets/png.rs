//! Fuzz target `png`: see `tilerast_tests::fuzz::png` for the input and the oracle.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    tilerast_tests::fuzz::png(data);
});
