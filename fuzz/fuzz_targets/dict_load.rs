//! Scene text read as a file and as the table `Scene.from_dict` makes of a dict (written out
//! by `toml`, read back): both refused, or both the same 4×4 picture in every bit. The
//! harness is `glint::fuzzing::dict_load`, which the regression tests run too.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = glint::fuzzing::dict_load(data);
});
