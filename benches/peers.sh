#!/usr/bin/env bash
# glint beside Mitsuba 3 on the peers' scene (../shared/peers), measured in one run:
# for T in 2, 100k, 1M grid triangles (+ 10 spheres) at 1024x768, glint's bench (release,
# median of 5) with and without shadows, then Mitsuba's llvm_ad_rgb `direct` (primary +
# shadow ray), `aov` and `raycast` (median of 3). Needs the peers' venv (see their README):
#   PEERS=../shared/peers VENV=~/peers/venv bash benches/peers.sh bench-out/peers
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench-out/peers}
peers=$(cd "${PEERS:-../shared/peers}" && pwd)
. "${VENV:-$HOME/peers/venv}/bin/activate"
mkdir -p "$out"
cargo build --release --locked -q
scenes=()
for t in 2 100000 1000000; do
  python3 benches/peer_scene.py --peers "$peers" --tris "$t" --spheres 10 --out "$out" >/dev/null
  scenes+=("$out/peers_$t.toml" "$out/peers_${t}_noshadow.toml")
done
echo "== glint $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
./target/release/glint bench "${scenes[@]}" --runs 5 --triangle watertight --out "$out/glint" 2>/dev/null
: > "$out/mitsuba.jsonl"
for t in 2 100000 1000000; do
  echo "== mitsuba T=$t $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
  (cd "$peers" && python3 -u mitsuba_bench.py --spheres 10 --tris "$t" --width 1024 --height 768 \
     --variant llvm_ad_rgb --integrator all --reps 3 --json) | grep '^{' | tee -a "$out/mitsuba.jsonl"
done
python3 "$peers/summarize.py" "$out/mitsuba.jsonl" > "$out/mitsuba.md" || true
cat "$out/mitsuba.md"
