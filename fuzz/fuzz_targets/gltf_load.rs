//! Any bytes through `glint::fuzzing::gltf_load` (see there: the input's first byte picks the
//! file's form); it checks what it got, and the regression tests run it too.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = glint::fuzzing::gltf_load(data);
});
