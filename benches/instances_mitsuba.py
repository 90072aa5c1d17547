#!/usr/bin/env python3
"""Mitsuba 3 on glint's instancing benchmark (benches/instances_scene.py): the same camera,
point light, ground plane and N instances of the Stanford dragon, the mesh in one
`shapegroup` placed by N `instance`s (each instance's scale, rotation about y and
translation over the mesh entry's own scale and translation, as glint composes them).
Modes: `direct` (primary + one shadow ray, as glint with `shadows = true`) and `aov`
(depth: primary rays only). Times mi.render + dr.eval + dr.sync_thread after one warm-up,
median of --reps, and prints one JSON line per mode. The mesh must be an uncompressed OBJ:

    gzip -dc scenes/meshes/dragon_full.obj.gz > /tmp/dragon.obj
    python3 benches/instances_mitsuba.py bench-out/instances/dragons_10000.toml --obj /tmp/dragon.obj

Needs mitsuba and drjit (pip install mitsuba drjit numpy), variant llvm_ad_rgb.
"""
import argparse
import json
import math
import statistics
import time
import tomllib

import numpy as np


def srt(scale, rotate_deg, translate):
    """glint's map: scale, then rotate x, then y, then z (degrees), then translate."""
    ax, ay, az = (math.radians(d) for d in rotate_deg)
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rz @ ry @ rx @ np.diag(scale)
    m[:3, 3] = translate
    return m


def place(t):
    return srt(t.get("scale", [1, 1, 1]), t.get("rotate", [0, 0, 0]), t.get("translate", [0, 0, 0]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--obj", required=True)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--out", default=None, help="write each mode's image to OUT_MODE.exr")
    a = ap.parse_args()
    s = tomllib.load(open(a.scene, "rb"))

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(a.variant)
    mi.set_log_level(mi.LogLevel.Warn)
    cam, light = s["camera"], s["lights"][0]
    mesh = s["meshes"][0]
    diffuse = lambda c: {"type": "diffuse", "reflectance": {"type": "rgb", "value": c}}
    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective", "fov": cam["fov"], "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam["eye"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])),
            "film": {"type": "hdrfilm", "width": cam["width"], "height": cam["height"],
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": 1},
        },
        "light": {"type": "point", "position": light["position"],
                  "intensity": {"type": "rgb", "value": light["color"]}},
        "dragon": {"type": "shapegroup", "mesh": {
            "type": "obj", "filename": a.obj, "face_normals": True,
            "to_world": mi.ScalarTransform4f(place(mesh).tolist()),
            "bsdf": diffuse([0.3, 0.65, 0.4])}},
    }
    for k, tri in enumerate(s.get("triangles", [])):
        v = np.array(tri["vertices"], dtype=np.float32)
        m = mi.Mesh(f"floor{k}", 3, 1, has_vertex_normals=False, has_vertex_texcoords=False)
        p = mi.traverse(m)
        p["vertex_positions"] = type(p["vertex_positions"])(v.ravel())
        p["faces"] = type(p["faces"])(np.array([0, 1, 2], dtype=np.uint32))
        p.update()
        d[f"floor{k}"] = m
    for k, x in enumerate(s.get("instances", [])):
        d[f"i{k}"] = {"type": "instance", "shapegroup": {"type": "ref", "id": "dragon"},
                      "to_world": mi.ScalarTransform4f(place(x).tolist())}
    t0 = time.perf_counter()
    scene = mi.load_dict(d)
    t_load = time.perf_counter() - t0
    modes = {"direct": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
             "aov": {"type": "aov", "aovs": "dd.y:depth"}}
    for name, spec in modes.items():
        integ = mi.load_dict(spec)

        def render():
            img = mi.render(scene, integrator=integ, spp=1, seed=0)
            dr.eval(img)
            dr.sync_thread()
            return img

        t0 = time.perf_counter()
        img = render()
        warm = time.perf_counter() - t0
        if a.out:
            mi.Bitmap(img).write(f"{a.out}_{name}.exr")
        times = []
        for _ in range(a.reps):
            t0 = time.perf_counter()
            render()
            times.append(time.perf_counter() - t0)
        print(json.dumps({"scene": a.scene, "instances": len(s.get("instances", [])),
                          "integrator": name, "variant": a.variant,
                          "threads": dr.thread_count(), "load_s": t_load, "warmup_s": warm,
                          "median_s": statistics.median(times), "times_s": times}))


if __name__ == "__main__":
    main()
