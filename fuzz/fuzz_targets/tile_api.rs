//! Fuzz target `tile_api`: see `tilerast_tests::fuzz::tile_api` for the input and the oracle.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    tilerast_tests::fuzz::tile_api(data);
});
