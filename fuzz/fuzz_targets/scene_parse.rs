//! Scene text (any bytes) through the parser and validator: an error or a scene, never a
//! panic; a scene that validates is also flattened, its BVH built and rendered at 4×4. The
//! harness is `glint::fuzzing::scene_parse`, which the regression tests run too.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = glint::fuzzing::scene_parse(data);
});
