#!/usr/bin/env bash
# On whatever Vulkan adapter this machine has (a real GPU, or lavapipe): the GPU tests, then
# the bench of the seed scenes, the dragon and the peers scenes on the shader (and on the
# ray-query tracer where the adapter has ray queries), with the Mrays/s of each (primary
# rays per second at the median frame), the acceleration-structure build apart; the cost of
# exact math (`--math corrected` against `fast`); then what
# still differs from the CPU mirror (every seed scene and triangle algorithm, `glint compare`).
#
#     bash benches/gpu.sh [ADAPTER]      # ADAPTER: part of the adapter's name (default: the best)
#
# On a machine without cargo, GLINT_PREBUILT=DIR takes `DIR/glint` and the GPU test binaries
# `DIR/tests/*` (built with `cargo test --release --no-run`, as `target/release/glint` is
# where the tests look for the program) instead of building them.
#
# Needs the meshes (`bash scenes/fetch-meshes.sh`) and the peers scenes
# (`python3 benches/peer_scene.py`, numpy) for those rows; the seed scenes always run.
set -euo pipefail
cd "$(dirname "$0")/.."
adapter="${1:-}"
if [ -z "${GLINT_PREBUILT:-}" ]; then
    cargo build --release --locked -q
fi
echo "== adapters"
./target/release/glint adapters
[ -n "$adapter" ] && export GLINT_ADAPTER="$adapter"
echo "== GPU tests on ${GLINT_ADAPTER:-the best adapter}"
if [ -n "${GLINT_PREBUILT:-}" ]; then
    for t in "$GLINT_PREBUILT"/tests/*; do
        echo "-- $(basename "$t")"
        "$t" 2>&1 | grep -E '^test result|FAILED|panicked|GPU tests on' || true
    done
else
    cargo test --release --locked $(for f in $(grep -l '^gpu_sentinel!();' tests/*.rs); do echo --test "$(basename "$f" .rs)"; done) 2>&1 |
        grep -E '^test result|FAILED|panicked|GPU tests on' || true
fi
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

# The price of exact math on this driver: the seed scenes and the dragon with the
# corrections always on against the driver's own division and square root.
echo
echo "== --math corrected against --math fast"
for math in corrected fast; do
    ./target/release/glint bench "${scenes[@]:0:6}" --runs 5 --triangle watertight --math "$math" \
        --out "$out/math-$math" ${adapter:+--adapter "$adapter"} >/dev/null
    echo "-- $math"
    awk -F'|' 'NR > 4 && ($3 ~ /gpu/) { printf "|%s|%s|%s|\n", $2, $3, $8 }' "$out/math-$math/report.md"
done

# GPU against the CPU mirror on this driver (docs/exactness.md): `glint compare` on every
# seed scene with every triangle algorithm and on the feature and mesh scenes, with exact
# math (the goal: 0 everywhere) and with the driver's own division and square root.
scenes_cmp=(sphere triangle umbrella bb8 mitsubishi bb8-shadows mitsubishi-shadows bb8-mirror whitted textured spot suzanne-ply)
[ -f scenes/meshes/bunny_glmark2.obj.gz ] && scenes_cmp+=(bunny)
[ -f scenes/meshes/dragon_full.obj.gz ] && scenes_cmp+=(dragon)
for math in exact fast; do
    echo
    echo "== GPU against the CPU mirror, 1024x768, --math $math ($(./target/release/glint adapters | grep -i -m1 -- "${GLINT_ADAPTER:-}" || true))"
    echo "| scene | triangles | pixels differing in some f32 bit | hit/miss | hits whose t differs | largest difference | in 8 bits |"
    echo "|---|---|---|---|---|---|---|"
    for s in "${scenes_cmp[@]}"; do
        for algo in naive moller-trumbore watertight; do
            # compare exits 1 when the images differ: that is a row, not a failure.
            line="$(./target/release/glint compare "scenes/$s.toml" --size 1024x768 --triangle "$algo" \
                --math "$math" --diff "$out/diff-$s-$algo.png" ${adapter:+--adapter "$adapter"} |
                grep '^gpu vs cpu' || true)"
            sed -E 's/^gpu vs cpu: [0-9]+ differing pixels \(8-bit\), ([0-9]+) differing in some f32 bit, ([0-9]+) hit\/miss disagreements, ([0-9]+) hits at a distance t that differs in some bit, largest channel difference ([^ ]+) \(([0-9]+) in 8 bits\).*/\1 | \2 | \3 | \4 | \5/' \
                <<<"$line" | awk -v s="$s" -v a="$algo" '{print "| " s " | " a " | " $0 " |"}'
        done
    done
done
