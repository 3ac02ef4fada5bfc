//! Fuzz target `nifti`: see `tilerast_tests::fuzz::nifti` for the input and the oracle.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    tilerast_tests::fuzz::nifti(data);
});
