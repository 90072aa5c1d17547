#!/usr/bin/env bash
# glint beside Mitsuba 3 on the peers' scene (../shared/peers), interleaved in one run: for
# T in 2, 100k, 1M grid triangles (+ 10 spheres) at 1024x768, ROUNDS rounds (default 3) of
# glint's bench (release, CPU tracers, watertight, median of 5) with and without shadows,
# then Mitsuba's llvm_ad_rgb `direct` (primary + shadow ray), `aov` and `raycast` (median
# of 3). The machine's speed drifts by more than the gaps measured, so each round pairs
# glint with Mitsuba minutes apart at most, and the table gives each round's ratio and
# their median. GPU=1 adds one pass of glint's GPU rows at the end. Needs the peers' venv
# (see their README):
#   PEERS=../shared/peers VENV=~/peers/venv bash benches/peers.sh bench-out/peers
# Output: OUT/peers.md (the side-by-side table), OUT/glint-rN/ and OUT/mitsuba-rN.jsonl.
# INSTANCES=1 measures the instanced scenes instead (benches/instances_scene.py: 100 and
# 10,000 Stanford dragons on a ground plane, with and without shadows; needs
# scenes/meshes/dragon_full.obj.gz from scenes/fetch-meshes.sh): glint's bench beside
# benches/instances_mitsuba.py (the mesh in a `shapegroup`, N `instance`s), ROUNDS rounds.
# Output: OUT/instances.md.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench-out/peers}
rounds=${ROUNDS:-3}
peers=$(cd "${PEERS:-../shared/peers}" && pwd)
. "${VENV:-$HOME/peers/venv}/bin/activate"
mkdir -p "$out"
cargo build --release --locked -q
if [ "${INSTANCES:-0}" = 1 ]; then
  gzip -dc scenes/meshes/dragon_full.obj.gz > "$out/dragon_full.obj"
  scenes=()
  for n in 100 10000; do
    python3 benches/instances_scene.py --count "$n" --out "$out" >/dev/null
    sed 's/^shadows = true/shadows = false/' "$out/dragons_$n.toml" > "$out/dragons_${n}_noshadow.toml"
    scenes+=("$out/dragons_$n.toml" "$out/dragons_${n}_noshadow.toml")
  done
  for r in $(seq 1 "$rounds"); do
    echo "== round $r: glint $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
    ./target/release/glint bench "${scenes[@]}" --runs 5 --triangle watertight --no-gpu \
      --out "$out/glint-instances-r$r" 2>/dev/null | grep cpu-f32
    : > "$out/mitsuba-instances-r$r.jsonl"
    for n in 100 10000; do
      echo "== round $r: mitsuba N=$n $(date -u +%FT%TZ)"
      python3 -u benches/instances_mitsuba.py "$out/dragons_$n.toml" --obj "$out/dragon_full.obj" \
        --reps 3 >> "$out/mitsuba-instances-r$r.jsonl"
    done
  done
  python3 - "$out" "$rounds" <<'PY' | tee "$out/instances.md"
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
glint, mitsuba = {}, {}
for r in range(1, rounds + 1):
    for row in json.load(open(f"{out}/glint-instances-r{r}/report.json"))["rows"]:
        if row["tracer"] == "cpu-f32":
            glint.setdefault(row["scene"], []).append(row["median_ms"])
    for line in open(f"{out}/mitsuba-instances-r{r}.jsonl"):
        m = json.loads(line)
        mitsuba.setdefault((m["instances"], m["integrator"]), []).append(1000 * m["median_s"])
print("| scene | Mitsuba mode | glint ms per round | Mitsuba ms per round | ratio per round | median ratio |")
print("|---|---|---|---|---|---|")
for n in (100, 10000):
    for shadows, mode in ((True, "direct"), (False, "aov")):
        name = f"dragons_{n}" + ("" if shadows else "_noshadow")
        g, m = glint.get(name, []), mitsuba.get((n, mode), [])
        ratios = [a / b for a, b in zip(g, m)]
        fmt = lambda xs, f: ", ".join(f.format(x) for x in xs)
        print(f"| {name} | {mode} | {fmt(g, '{:.1f}')} | {fmt(m, '{:.1f}')} | {fmt(ratios, '{:.2f}')} "
              f"| **{statistics.median(ratios):.2f}** |")
PY
  exit 0
fi
scenes=()
for t in 2 100000 1000000; do
  python3 benches/peer_scene.py --peers "$peers" --tris "$t" --spheres 10 --out "$out" >/dev/null
  scenes+=("$out/peers_$t.toml" "$out/peers_${t}_noshadow.toml")
done
for r in $(seq 1 "$rounds"); do
  echo "== round $r: glint $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
  ./target/release/glint bench "${scenes[@]}" --runs 5 --triangle watertight --no-gpu \
    --out "$out/glint-r$r" 2>/dev/null | grep cpu-f32
  : > "$out/mitsuba-r$r.jsonl"
  for t in 2 100000 1000000; do
    echo "== round $r: mitsuba T=$t $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
    (cd "$peers" && python3 -u mitsuba_bench.py --spheres 10 --tris "$t" --width 1024 --height 768 \
       --variant llvm_ad_rgb --integrator all --reps 3 --json) | grep '^{' >> "$out/mitsuba-r$r.jsonl"
  done
done
if [ "${GPU:-0}" = 1 ]; then
  ./target/release/glint bench "${scenes[@]}" --runs 5 --triangle watertight --out "$out/glint-gpu" 2>/dev/null
fi
python3 - "$out" "$rounds" <<'PY' | tee "$out/peers.md"
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
def median(xs):
    return statistics.median(xs) if xs else float("nan")
glint, mitsuba = {}, {}
for r in range(1, rounds + 1):
    for row in json.load(open(f"{out}/glint-r{r}/report.json"))["rows"]:
        if row["tracer"] == "cpu-f32":
            glint.setdefault(row["scene"], []).append(row["median_ms"])
    for line in open(f"{out}/mitsuba-r{r}.jsonl"):
        m = json.loads(line)
        mitsuba.setdefault((m["tris"], m["integrator"]), []).append(1000 * m["median_s"])
print(f"glint's CPU tracer (f32, watertight, median of 5) beside Mitsuba 3 llvm_ad_rgb (2 threads, "
      f"median of 3), 1024×768, {rounds} interleaved rounds; ratio = glint / Mitsuba, per round.\n")
print("| scene | Mitsuba mode | glint ms per round | Mitsuba ms per round | ratio per round | median ratio |")
print("|---|---|---|---|---|---|")
for t in (2, 100000, 1000000):
    for shadows, mode in ((True, "direct"), (False, "aov")):
        name = f"peers_{t}" + ("" if shadows else "_noshadow")
        g, m = glint.get(name, []), mitsuba.get((t, mode), [])
        ratios = [a / b for a, b in zip(g, m)]
        fmt = lambda xs, f: ", ".join(f.format(x) for x in xs)
        print(f"| {name} | {mode} | {fmt(g, '{:.1f}')} | {fmt(m, '{:.1f}')} | {fmt(ratios, '{:.2f}')} "
              f"| **{median(ratios):.2f}** |")
PY
