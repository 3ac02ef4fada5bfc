//! Fuzz target `obj`: see `tilerast_tests::fuzz::obj` for the input and the oracle.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    tilerast_tests::fuzz::obj(data);
});
