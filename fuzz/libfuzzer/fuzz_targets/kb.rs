#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| prf_fuzz::kb::run(data));
