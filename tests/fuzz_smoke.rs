//! The fuzz smoke CI runs: every fuzz target's harness (`glint::fuzzing`, what the
//! cargo-fuzz targets in `fuzz/` call) on inputs mutated from its seeds, a fixed number per
//! target, the same inputs every run.
//!
//! libFuzzer's coverage-guided runs need an instrumented build of every crate (4 min on the
//! 2-core machine) and minutes per target, which CI's 30-minute budget has no room for; they
//! are run by hand and measured in docs/robustness.md. This smoke needs no other build: it
//! runs in the test suite, in every CI pass 1, and mutates as libFuzzer's basic mutators do
//! (bit flips, interesting bytes and integers, deletions, duplications, splices, tokens the
//! formats care about). A panic, or an input slower than [`SLOW`], is a finding: the input is
//! written under `target/tmp/fuzz-smoke/` and the test fails naming it. Fix it and keep the
//! input in `tests/data/fuzz/TARGET-NAME.bin` (tests/fuzz_regressions.rs replays it).
//!
//! `GLINT_FUZZ_SMOKE_SEED=N` explores other inputs than CI's, `GLINT_FUZZ_SMOKE_INPUTS=N`
//! sets the count per target.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glint::fuzzing::{dict_load, gltf_load, obj_load, ply_load, scene_parse, texture_load};

/// A fuzz target's harness.
type Harness = fn(&[u8]) -> Result<(), String>;

/// The inputs per target in CI.
const INPUTS: usize = 20_000;
/// The largest input, as the long runs' `-max_len`.
const MAX_LEN: usize = 16 * 1024;
/// An input that takes longer is a finding (the long runs' `-timeout=10` is for release
/// builds; the test profile is slower, and this is generous for it).
const SLOW: Duration = Duration::from_secs(10);

/// splitmix64: a small generator whose sequence is the same on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A number in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Bytes the formats give meaning to, and the edges of bytes.
const BYTES: &[u8] = b"\x00\x01\x7f\x80\xff09-+.eE[]{}\"'=,:#\n\r\t \\/";
/// Tokens of the formats' text: numbers at the edges of f32 and u32, TOML's specials,
/// PLY's and OBJ's keywords, glTF's keys, URIs.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-0.0",
    "0",
    "1",
    "-1",
    "1e39",
    "1e-45",
    "3.4028235e38",
    "4294967295",
    "4294967296",
    "2147483648",
    "-2147483649",
    "99999999999999999999",
    "[]",
    "{}",
    "\"\"",
    "[[",
    "]]",
    "true",
    "false",
    "element vertex ",
    "property float x\n",
    "end_header\n",
    "format binary_little_endian 1.0\n",
    "f 1 2 3\n",
    "v 0 0 0\n",
    "vt ",
    "vn ",
    "mtllib ",
    "usemtl ",
    "newmtl ",
    "map_Kd ",
    "\"accessors\"",
    "\"bufferViews\"",
    "\"byteStride\"",
    "\"count\"",
    "data:application/octet-stream;base64,",
    "../",
    "/etc/",
    "[[meshes]]\n",
    "[[spheres]]\n",
    "[[triangles]]\n",
    "[[lights]]\n",
    "[camera]\n",
];
/// Little-endian integers at the edges: counts, lengths and offsets in binary formats.
const INTS: &[u32] = &[
    0,
    1,
    2,
    3,
    4,
    12,
    16,
    255,
    256,
    0x7FFF,
    0xFFFF,
    0x1_0000,
    0x7FFF_FFFF,
    0x8000_0000,
    0xFFFF_FFFE,
    0xFFFF_FFFF,
];

/// One mutation of `d`, with `seeds` to splice from.
fn mutate_once(d: &mut Vec<u8>, seeds: &[Vec<u8>], r: &mut Rng) {
    let at = |r: &mut Rng, d: &Vec<u8>| r.below(d.len() + 1);
    match r.below(9) {
        0 if !d.is_empty() => {
            let i = r.below(d.len());
            d[i] ^= 1 << r.below(8);
        }
        1 if !d.is_empty() => {
            let i = r.below(d.len());
            d[i] = BYTES[r.below(BYTES.len())];
        }
        2 if !d.is_empty() => {
            let i = r.below(d.len());
            let n = 1 + r.below(16.min(d.len() - i));
            d.drain(i..i + n);
        }
        3 if !d.is_empty() => {
            let i = r.below(d.len());
            let n = 1 + r.below(64.min(d.len() - i));
            let copy = d[i..i + n].to_vec();
            let j = at(r, d);
            d.splice(j..j, copy);
        }
        4 => {
            let t = TOKENS[r.below(TOKENS.len())].as_bytes();
            let j = at(r, d);
            d.splice(j..j, t.iter().copied());
        }
        5 if d.len() >= 4 => {
            let i = r.below(d.len() - 3);
            let v = INTS[r.below(INTS.len())];
            d[i..i + 4].copy_from_slice(&v.to_le_bytes());
        }
        6 => {
            // A number in the text replaced by a token.
            let digits: Vec<usize> = (0..d.len()).filter(|&i| d[i].is_ascii_digit()).collect();
            if digits.is_empty() {
                return;
            }
            let mut i = digits[r.below(digits.len())];
            while i > 0 && (d[i - 1].is_ascii_digit() || b".-e".contains(&d[i - 1])) {
                i -= 1;
            }
            let mut j = i;
            while j < d.len() && (d[j].is_ascii_digit() || b".-+eE".contains(&d[j])) {
                j += 1;
            }
            let t = TOKENS[r.below(16)].as_bytes();
            d.splice(i..j, t.iter().copied());
        }
        7 => {
            // Splice: this input's head, another seed's tail.
            let other = &seeds[r.below(seeds.len())];
            let i = at(r, d);
            let j = r.below(other.len() + 1);
            d.truncate(i);
            d.extend_from_slice(&other[j..]);
        }
        _ => d.truncate(at(r, d)),
    }
}

/// What a smoke of one harness found.
#[derive(Default)]
struct Smoke {
    inputs: usize,
    accepted: usize,
    slowest: Duration,
    findings: Vec<PathBuf>,
}

/// Runs `harness` on `inputs` mutants of `seeds` drawn from `seed`; findings are written
/// under `out` as `NAME-K.bin`.
fn smoke(
    name: &str,
    harness: &dyn Fn(&[u8]) -> Result<(), String>,
    seeds: &[Vec<u8>],
    inputs: usize,
    seed: u64,
    out: &Path,
) -> Smoke {
    let mut r = Rng(seed
        ^ name
            .bytes()
            .fold(0u64, |h, b| h.wrapping_mul(31) ^ b as u64));
    let mut s = Smoke::default();
    for k in 0..inputs {
        let mut d = seeds[r.below(seeds.len())].clone();
        for _ in 0..1 + r.below(3) {
            mutate_once(&mut d, seeds, &mut r);
        }
        d.truncate(MAX_LEN);
        let t = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| harness(&d)));
        let took = t.elapsed();
        s.slowest = s.slowest.max(took);
        s.inputs += 1;
        s.accepted += matches!(result, Ok(Ok(()))) as usize;
        if result.is_err() || took > SLOW {
            std::fs::create_dir_all(out).unwrap();
            let path = out.join(format!("{name}-{k}.bin"));
            std::fs::write(&path, &d).unwrap();
            s.findings.push(path);
        }
    }
    s
}

/// The seeds of `target`: `fuzz/seeds/TARGET/`, and for the scene and OBJ targets the
/// shipped scenes (as `cargo fuzz run TARGET corpus/TARGET ../scenes` is seeded), each OBJ
/// with its MTL after a 0xFF byte as `obj_load` takes them.
fn seeds(target: &str) -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    let files = |dir: &Path| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
            .map(|it| it.map(|e| e.unwrap().path()).collect())
            .unwrap_or_default();
        v.sort();
        v
    };
    for p in files(&root.join("fuzz/seeds").join(target)) {
        out.push(std::fs::read(p).unwrap());
    }
    for p in files(&root.join("scenes")) {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or_default();
        match (target, ext) {
            ("scene_parse" | "dict_load", "toml") => out.push(std::fs::read(&p).unwrap()),
            ("obj_load", "obj") => {
                let mut d = std::fs::read(&p).unwrap();
                d.push(0xFF);
                d.extend(std::fs::read(p.with_extension("mtl")).unwrap_or_default());
                out.push(d);
            }
            _ => {}
        }
    }
    out.retain(|d| d.len() <= MAX_LEN);
    out
}

fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("{name}={v}: not a number"))
        })
        .unwrap_or(default)
}

#[test]
fn every_fuzz_target_survives_its_smoke() {
    let targets: [(&str, Harness); 6] = [
        ("scene_parse", scene_parse),
        ("dict_load", dict_load),
        ("obj_load", obj_load),
        ("ply_load", ply_load),
        ("gltf_load", gltf_load),
        ("texture_load", texture_load),
    ];
    let inputs = env_number("GLINT_FUZZ_SMOKE_INPUTS", INPUTS as u64) as usize;
    let seed = env_number("GLINT_FUZZ_SMOKE_SEED", 0);
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-smoke");
    let mut findings = Vec::new();
    for (name, harness) in targets {
        let seeds = seeds(name);
        assert!(!seeds.is_empty(), "{name}: no seeds");
        let t = Instant::now();
        let s = smoke(name, &harness, &seeds, inputs, seed, &out);
        eprintln!(
            "{name}: {} seeds, {} inputs ({} accepted) in {:.1} s, slowest {:.0} ms, {} findings",
            seeds.len(),
            s.inputs,
            s.accepted,
            t.elapsed().as_secs_f64(),
            s.slowest.as_secs_f64() * 1e3,
            s.findings.len()
        );
        // Mutants must reach both verdicts, or the smoke tests only one path.
        assert!(
            s.accepted > 0 && s.accepted < s.inputs,
            "{name}: {} of {} inputs accepted",
            s.accepted,
            s.inputs
        );
        findings.extend(s.findings);
    }
    assert!(
        findings.is_empty(),
        "fuzz smoke findings (replay each with its target's harness; once fixed, keep it in tests/data/fuzz/):\n{}",
        findings
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The twin: a harness with a planted bug (a panic on any scene text holding `nan`, which
/// no seed holds) is caught within the smoke's inputs, and its input written out.
#[test]
fn a_planted_panic_is_a_finding() {
    let seeds = seeds("scene_parse");
    assert!(seeds.iter().all(|d| !d.windows(3).any(|w| w == b"nan")));
    let planted = |d: &[u8]| -> Result<(), String> {
        if d.windows(3).any(|w| w == b"nan") {
            panic!("planted");
        }
        scene_parse(d)
    };
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-smoke-twin");
    let s = smoke("planted", &planted, &seeds, 300, 0, &out);
    assert!(!s.findings.is_empty(), "the planted panic was not found");
    for p in &s.findings {
        let d = std::fs::read(p).unwrap();
        assert!(d.windows(3).any(|w| w == b"nan"), "{}", p.display());
    }
}
