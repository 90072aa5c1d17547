//! Makes `GLINT_SKIP_GPU=1` visible in the test summary: with it set, the tests are built
//! with `--cfg glint_skip_gpu`, and each test binary's `gpu_tests_ran` sentinel is listed as
//! "ignored" with the reason (`tests/common/mod.rs`), instead of every GPU check passing
//! quietly.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(glint_skip_gpu)");
    println!("cargo::rerun-if-env-changed=GLINT_SKIP_GPU");
    println!("cargo::rerun-if-changed=build.rs");
    if std::env::var("GLINT_SKIP_GPU").is_ok_and(|v| v == "1") {
        println!("cargo::rustc-cfg=glint_skip_gpu");
    }
}
