#!/usr/bin/env bash
# The seed scenes' bench on the three lavapipes in one run, with `benches/none.toml` (no
# primitive: the no-traversal frame, camera + background + readback): `glint bench` on the
# system's Vulkan driver, then on Mesa 25.0's and Mesa 26.1's lavapipe (`.ci/lavapipe.sh`;
# 26.1 through its own dynamic loader), then one side-by-side table of the GPU rows (each
# column headed by the driver the adapter reports) with the CPU tracers' rows from the
# same run:
#
#     bash benches/drivers.sh [OUT]        # default OUT: bench-out/drivers; RUNS=5
#
# Writes OUT/system/, OUT/mesa25/, OUT/mesa26/ (each glint bench's report.md, .json, plot) and
# OUT/drivers.md. Needs python3 (standard library only) for the table.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-bench-out/drivers}"
runs="${RUNS:-5}"
mkdir -p "$out"
cargo build --release --locked -q
export GLINT_ADAPTER="${GLINT_ADAPTER:-llvmpipe}"
scenes=(scenes/sphere.toml scenes/triangle.toml scenes/umbrella.toml scenes/bb8.toml
    scenes/mitsubishi.toml benches/none.toml)
./target/release/glint bench "${scenes[@]}" --runs "$runs" --out "$out/system" --adapter "$GLINT_ADAPTER" >/dev/null
(
    eval "$(bash .ci/lavapipe.sh 25)"
    ./target/release/glint bench "${scenes[@]}" --runs "$runs" --out "$out/mesa25" --adapter "$GLINT_ADAPTER" >/dev/null
)
(
    eval "$(bash .ci/lavapipe.sh 26)"
    "$GLINT_LAVAPIPE_LOADER" ./target/release/glint bench "${scenes[@]}" --runs "$runs" --out "$out/mesa26" \
        --adapter "$GLINT_ADAPTER" >/dev/null
)
python3 - "$out" <<'PY' | tee "$out/drivers.md"
import json, sys
out = sys.argv[1]
a = json.load(open(f"{out}/system/report.json"))
b = json.load(open(f"{out}/mesa25/report.json"))
c = json.load(open(f"{out}/mesa26/report.json"))
def driver(r):
    d = r["adapter"]
    return d[d.find("Mesa"):].split(" (")[0] if "Mesa" in d else d
key = lambda r: (r["scene"], r["tracer"], r["triangle"])
rb = {key(r): r for r in b["rows"]}
rc = {key(r): r for r in c["rows"]}
print(f"Seed scenes at {a['rows'][0]['size'][0]}×{a['rows'][0]['size'][1]}, median of {a['runs']} runs "
      f"after a warm-up, CPU tracers on {a['cpu_threads']} threads. GPU: lavapipe, a CPU Vulkan.\n")
print(f"| scene | triangles | GPU {driver(a)} ms | GPU {driver(b)} ms | GPU {driver(c)} ms "
      f"| GPU-RQ {driver(b)} ms (AS build) "
      f"| CPU f32 ms | CPU f64 ms | GPU = CPU f32 (three drivers) | largest error vs f64 | px ≥ 1/255 "
      f"| GPU-RQ largest error, px ≥ 1/255, hit/miss |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
rows = {key(r): r for r in a["rows"]}
for r in a["rows"]:
    if r["tracer"] != "gpu":
        continue
    k = key(r)
    cpu = rows.get((k[0], "cpu-f32", k[2]))
    f64 = rows.get((k[0], "cpu-f64", k[2]))
    other = rb.get(k)
    third = rc.get(k)
    same = " / ".join("every bit" if x and x.get("equals_cpu_f32") else "NO" for x in (r, other, third))
    rq = rb.get((k[0], "gpu-rq", k[2]))
    rq_ms = f"{rq['median_ms']:.1f} ({rq['accel_ms']:.1f})" if rq else "–"
    rq_err = f"{rq['max_err']:.1e}, {rq['pixels_off']}, {rq['hit_miss']}" if rq else "–"
    print(f"| {k[0]} | {k[2]} | {r['median_ms']:.1f} | {other['median_ms'] if other else float('nan'):.1f} "
          f"| {third['median_ms'] if third else float('nan'):.1f} | {rq_ms} "
          f"| {cpu['median_ms'] if cpu else float('nan'):.1f} | {f64['median_ms'] if f64 else float('nan'):.1f} "
          f"| {same} | {r['max_err']:.1e} | {r['pixels_off']} | {rq_err} |")
PY
