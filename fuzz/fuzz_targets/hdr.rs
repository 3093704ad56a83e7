#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| penumbra_fuzz_targets::hdr(data));
