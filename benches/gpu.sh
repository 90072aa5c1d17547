#!/usr/bin/env bash
# On whatever Vulkan adapter this machine has (a real GPU, or lavapipe): the GPU tests, then
# the bench of the seed scenes, the dragon and the peers scenes on the shader (and on the
# ray-query tracer where the adapter has ray queries), with the Mrays/s of each (primary
# rays per second at the median frame), the acceleration-structure build apart.
#
#     bash benches/gpu.sh [ADAPTER]      # ADAPTER: part of the adapter's name (default: the best)
#
# Needs the meshes (`bash scenes/fetch-meshes.sh`) and the peers scenes
# (`python3 benches/peer_scene.py`, numpy) for those rows; the seed scenes always run.
set -euo pipefail
cd "$(dirname "$0")/.."
adapter="${1:-}"
cargo build --release --locked -q
echo "== adapters"
./target/release/glint adapters
[ -n "$adapter" ] && export GLINT_ADAPTER="$adapter"
echo "== GPU tests on ${GLINT_ADAPTER:-the best adapter}"
cargo test --release --locked $(for f in $(grep -l '^gpu_sentinel!();' tests/*.rs); do echo --test "$(basename "$f" .rs)"; done) 2>&1 |
    grep -E '^test result|FAILED|panicked|GPU tests on' || true
scenes=(scenes/sphere.toml scenes/triangle.toml scenes/umbrella.toml scenes/bb8.toml scenes/mitsubishi.toml)
[ -f scenes/meshes/dragon_full.obj.gz ] && scenes+=(scenes/dragon.toml)
for t in 2 100000 1000000; do
    for s in bench-out/peers/peers_$t.toml bench-out/peers/peers_${t}_noshadow.toml; do
        [ -f "$s" ] && scenes+=("$s")
    done
done
out=bench-out/gpu
./target/release/glint bench "${scenes[@]}" --runs 5 --triangle watertight --out "$out" \
    ${adapter:+--adapter "$adapter"} >/dev/null
head -n 1 "$out/report.md"
echo
echo "| scene | tracer | median ms | Mrays/s | AS build ms | largest error vs f64 | hit/miss vs f64 | = CPU f32 |"
echo "|---|---|---|---|---|---|---|---|"
awk -F'|' 'NR > 4 && ($3 ~ /gpu|cpu-f32/) { printf "|%s|%s|%s|%s|%s|%s|%s|%s|\n", $2, $3, $8, $9, $12, $15, $18, $19 }' "$out/report.md"
