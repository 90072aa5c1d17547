//! OBJ bytes (and an MTL, the input's second half) through the mesh loader, as a scene's
//! `[[meshes]]` entry reads them: an error or triangles, never a panic. The harness is
//! `glint::fuzzing::obj_load`, which the regression tests run too.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = glint::fuzzing::obj_load(data);
});
