#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| prf_fuzz::joint_states::run(data));
