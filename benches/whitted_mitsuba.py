#!/usr/bin/env python3
"""Mitsuba 3 render time on the geometry of glint's Whitted scene (scenes/whitted.toml).

What it renders (built in Python with mi.load_dict, nothing read but the floor OBJ/MTL):
  * perspective sensor: eye (0, 1.6, 5) -> (0, 0.7, -1), up +y, vertical fov 45
    (fov_axis 'y'), hdrfilm WxH (default 1024x768), box filter, independent sampler, 1 spp;
  * the checker floor scenes/whitted-floor.obj, split by `usemtl` into two mi.Mesh objects
    (red and yellow) with `diffuse` BSDFs whose reflectance is the MTL file's Kd;
  * the mirror sphere (center (-0.9, 1.0, -2.2), r 1.0): `conductor`, material 'none'
    (a perfect mirror);
  * the glass sphere (center (0.7, 0.75, 0.3), r 0.75): `dielectric`, int_ior 1.5,
    ext_ior 1.0;
  * one `point` light at (4, 8, 6) (white; its intensity only scales the image);
  * integrator `path`, max_depth 8, rr_depth 100 (Russian roulette off).

Why max_depth 8: Mitsuba's max_depth counts path segments, camera segment and the final
segment to the light included (1 = emitters seen directly, 2 = direct lighting only).
glint's max_depth 6 allows 6 reflections/refractions after the primary hit and shades every
hit, the 6th included, with a shadow ray to the light: camera segment + 6 bounces + light
segment = 8 segments. (With 8, Mitsuba also traces one last continuation ray from the 7th
vertex that can only collect emission; there is none to find here. With 7 it would skip
the shadow ray at that vertex.)

The timing is mi.render(...) + dr.eval + dr.sync_thread, after one warm-up render (in the
LLVM variants the warm-up JIT-compiles the megakernel; later renders reuse the cached
kernel but still re-trace the Python-side integrator call, which is counted). Scene loading
is not timed. Prints each run and the median in ms.

Install (a virtual environment anywhere outside the repository):
  python3 -m venv ~/mts-venv && . ~/mts-venv/bin/activate
  pip install mitsuba drjit numpy
`llvm_ad_rgb` needs libLLVM; Dr.Jit finds the system's by itself, or takes the path in
DRJIT_LIBLLVM_PATH. LLVM 15 (Debian 12's default libLLVM-15) aborts compiling the `path`
kernel ("LLVM ERROR: Cannot select: ... f32 = fminimum", from the Russian-roulette
minimum, which is compiled even when roulette never triggers); LLVM 19 works. Without
installing it system-wide (which would change the LLVM every Dr.Jit user here picks up):
  mkdir -p ~/llvm19 && cd ~/llvm19 && apt-get download libllvm19 && dpkg-deb -x libllvm19_*.deb root
  export DRJIT_LIBLLVM_PATH=~/llvm19/root/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1

Run (from the repository root):
  python benches/whitted_mitsuba.py                     # 1024x768, 2 threads, 10 reps
  python benches/whitted_mitsuba.py --reps 5 --threads 2 --out /tmp/mts.exr
  python benches/whitted_mitsuba.py --json              # also one JSON line with all numbers

--out writes the last render (.exr, or .png tonemapped to sRGB by Mitsuba).
"""
import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_OBJ = os.path.join(HERE, "..", "scenes", "whitted-floor.obj")

EYE = [0.0, 1.6, 5.0]
LOOK_AT = [0.0, 0.7, -1.0]
UP = [0.0, 1.0, 0.0]
FOV_Y = 45.0
MIRROR = ([-0.9, 1.0, -2.2], 1.0)
GLASS = ([0.7, 0.75, 0.3], 0.75)
LIGHT = [4.0, 8.0, 6.0]
# glint's point light has no distance falloff; Mitsuba's falls off as 1/r^2. This makes the
# floor under the spheres about as bright as in glint (r^2 = 116 from the origin), for the
# image only: it does not change the work done.
LIGHT_INTENSITY = 116.0


def read_obj(path):
    """Vertices and, per `usemtl` material, triangles (0-based) of a plain OBJ, plus the
    Kd of each material from the `mtllib` files. Polygons are fanned into triangles."""
    verts, groups, kd, mtl = [], {}, {}, None
    libs = []
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w or w[0].startswith("#"):
                continue
            if w[0] == "v":
                verts.append([float(x) for x in w[1:4]])
            elif w[0] == "usemtl":
                mtl = w[1]
            elif w[0] == "mtllib":
                libs.append(os.path.join(os.path.dirname(path), " ".join(w[1:])))
            elif w[0] == "f":
                idx = []
                for tok in w[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                tris = groups.setdefault(mtl, [])
                for k in range(1, len(idx) - 1):
                    tris.append([idx[0], idx[k], idx[k + 1]])
    for lib in libs:
        cur = None
        with open(lib) as f:
            for line in f:
                w = line.split()
                if not w:
                    continue
                if w[0] == "newmtl":
                    cur = w[1]
                elif w[0] == "Kd" and cur is not None:
                    kd[cur] = [float(x) for x in w[1:4]]
    return np.array(verts, dtype=np.float32), {m: np.array(t, dtype=np.uint32) for m, t in groups.items()}, kd


def make_mesh(mi, name, verts, faces, rgb):
    """An mi.Mesh holding only the vertices `faces` uses, with a diffuse BSDF."""
    used, inv = np.unique(faces.ravel(), return_inverse=True)
    v = verts[used]
    fc = inv.reshape(-1, 3).astype(np.uint32)
    props = mi.Properties()
    props["bsdf"] = mi.load_dict({"type": "diffuse",
                                  "reflectance": {"type": "rgb", "value": rgb}})
    mesh = mi.Mesh(name, len(v), len(fc), props=props,
                   has_vertex_normals=False, has_vertex_texcoords=False)
    p = mi.traverse(mesh)
    p["vertex_positions"] = type(p["vertex_positions"])(v.ravel())
    p["faces"] = type(p["faces"])(fc.ravel())
    p.update()
    return mesh


def build_scene(mi, a):
    verts, groups, kd = read_obj(a.obj)
    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": FOV_Y, "fov_axis": "y",
            "near_clip": 0.001, "far_clip": 1000.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=EYE, target=LOOK_AT, up=UP),
            "film": {"type": "hdrfilm", "width": a.width, "height": a.height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": 1},
        },
        "light": {"type": "point", "position": LIGHT,
                  "intensity": {"type": "rgb", "value": [LIGHT_INTENSITY] * 3}},
        "mirror": {"type": "sphere", "center": MIRROR[0], "radius": MIRROR[1],
                   "bsdf": {"type": "conductor", "material": "none"}},
        "glass": {"type": "sphere", "center": GLASS[0], "radius": GLASS[1],
                  "bsdf": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}},
    }
    ntris = 0
    for m, faces in groups.items():
        d[f"floor_{m}"] = make_mesh(mi, f"floor_{m}", verts, faces, kd.get(m, [0.5, 0.5, 0.5]))
        ntris += len(faces)
    return mi.load_dict(d), ntris, sorted(groups)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--obj", default=DEFAULT_OBJ, help="floor OBJ (default scenes/whitted-floor.obj)")
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--max-depth", type=int, default=8,
                    help="path integrator max_depth (segments; 8 = glint's max_depth 6, see above)")
    ap.add_argument("--reps", type=int, default=10, help="timed renders after one warm-up")
    ap.add_argument("--threads", type=int, default=2, help="dr.set_thread_count (0: leave default)")
    ap.add_argument("--out", default=None, help="write the last image here (.exr or .png)")
    ap.add_argument("--json", action="store_true", help="also print one JSON line")
    a = ap.parse_args()

    import mitsuba as mi
    import drjit as dr
    mi.set_variant(a.variant)
    mi.set_log_level(mi.LogLevel.Warn)  # no progress bar
    if a.threads:
        dr.set_thread_count(a.threads)

    t0 = time.perf_counter()
    scene, ntris, mats = build_scene(mi, a)
    t_load = time.perf_counter() - t0
    integ = mi.load_dict({"type": "path", "max_depth": a.max_depth,
                          "rr_depth": a.max_depth + 100})

    def render():
        img = mi.render(scene, integrator=integ, spp=1, seed=0)
        dr.eval(img)
        dr.sync_thread()
        return img

    print(f"mitsuba {mi.__version__} / drjit {dr.__version__}, variant {a.variant}, "
          f"threads {dr.thread_count()}: 2 spheres + {ntris} floor tris ({', '.join(mats)}), "
          f"{a.width}x{a.height} 1 spp, path max_depth {a.max_depth}, rr off; "
          f"scene load {t_load * 1e3:.0f} ms", flush=True)
    t0 = time.perf_counter()
    img = render()  # warm-up: JIT compile (or kernel-cache load)
    t_warm = time.perf_counter() - t0
    load0 = open("/proc/loadavg").read().split()[0]
    times, cpu = [], []
    for _ in range(a.reps):
        c0 = time.process_time()
        t0 = time.perf_counter()
        img = render()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    med = statistics.median(times)
    arr = np.array(img)
    if a.out:
        mi.util.write_bitmap(a.out, img, write_async=False)
    print(f"warm-up {t_warm * 1e3:.0f} ms; runs {', '.join(f'{t * 1e3:.1f}' for t in times)} ms "
          f"(cpu {', '.join(f'{t * 1e3:.0f}' for t in cpu)} ms); img mean {arr.mean():.4g}")
    print(f"median {med * 1e3:.1f} ms", flush=True)
    if a.json:
        print(json.dumps({
            "peer": "mitsuba3", "scene": "whitted", "mitsuba_version": mi.__version__,
            "drjit_version": dr.__version__, "variant": a.variant, "integrator": "path",
            "max_depth": a.max_depth, "threads": dr.thread_count(), "width": a.width,
            "height": a.height, "spp": 1, "tris": ntris, "t_scene_load_s": t_load,
            "t_warmup_s": t_warm, "loadavg_before": load0, "times_s": times, "cpu_s": cpu,
            "median_ms": med * 1e3, "img_mean": float(arr.mean()),
        }))


if __name__ == "__main__":
    main()
