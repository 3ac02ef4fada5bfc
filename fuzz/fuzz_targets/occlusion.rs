//! Fuzz target `occlusion`: see `tilerast_tests::fuzz::occlusion` for the input and the oracle.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    tilerast_tests::fuzz::occlusion(data);
});
