#!/usr/bin/env python3
"""Writes the peers' benchmark scene (../shared/peers/scene_common.py: a heightfield grid of
T triangles, N spheres on a lattice, camera (0,20,12) -> (0,0,0), vfov 40, one point light)
as a glint scene: OUT/grid_T.obj and OUT/peers_T.toml, from the same numbers.

    python3 benches/peer_scene.py --peers ../shared/peers --tris 100000 --spheres 10 --out bench-out/peers

Materials are diffuse (Mitsuba's `direct` integrator: primary ray + one shadow ray); glint has
no 1/r² falloff, so the images differ in brightness, not in the rays traced. `shadows = true`
matches Mitsuba `direct`; render with the scene's `shadows = false` copy (peers_T_noshadow.toml)
to set beside Mitsuba's `raycast`/`aov` (primary rays only).
"""
import argparse
import os
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--peers", default="../shared/peers", help="folder with scene_common.py")
    ap.add_argument("--tris", type=int, default=2)
    ap.add_argument("--spheres", type=int, default=10)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--out", default="bench-out/peers")
    a = ap.parse_args()
    sys.path.insert(0, os.path.abspath(a.peers))
    import scene_common as sc  # noqa: E402  (the peers' own numbers)

    os.makedirs(a.out, exist_ok=True)
    verts, faces = sc.grid_mesh(a.tris)
    obj = f"grid_{a.tris}.obj"
    with open(os.path.join(a.out, obj), "w") as f:
        f.write(f"# scene_common.grid_mesh({a.tris}): {len(faces)} triangles\n")
        for v in verts:
            f.write(f"v {float(v[0])!r} {float(v[1])!r} {float(v[2])!r}\n")
        for t in faces:
            f.write(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n")
    fmt = lambda v: "[" + ", ".join(repr(float(x)) for x in v) + "]"  # noqa: E731
    for shadows, suffix in [(True, ""), (False, "_noshadow")]:
        lines = [
            f"# The peers' scene (shared/peers/scene_common.py) at {len(faces)} triangles, "
            f"{a.spheres} spheres; written by benches/peer_scene.py.",
            "ambient = [0.05, 0.05, 0.05]",
            f"shadows = {'true' if shadows else 'false'}",
            'triangle = "watertight"',
            "",
            "[camera]",
            f"eye = {fmt(sc.CAM_ORIGIN)}",
            f"look_at = {fmt(sc.CAM_TARGET)}",
            f"up = {fmt(sc.CAM_UP)}",
            f"fov = {float(sc.FOV_Y)!r}",
            f"width = {a.width}",
            f"height = {a.height}",
            "",
            "[[lights]]",
            f"position = {fmt(sc.LIGHT_POS)}",
            "color = [1.0, 1.0, 1.0]",
            "",
            "[materials.ground]",
            'model = "diffuse"',
            "ka = [0.5, 0.5, 0.5]",
            "kd = [0.5, 0.5, 0.5]",
            "",
            "[materials.ball]",
            'model = "diffuse"',
            "ka = [0.8, 0.3, 0.2]",
            "kd = [0.8, 0.3, 0.2]",
            "",
            "[[meshes]]",
            f'file = "{obj}"',
            'material = "ground"',
        ]
        for c, r in sc.spheres(a.spheres):
            lines += ["", "[[spheres]]", f"center = {fmt(c)}", f"radius = {float(r)!r}", 'material = "ball"']
        path = os.path.join(a.out, f"peers_{a.tris}{suffix}.toml")
        with open(path, "w") as f:
            f.write("\n".join(lines) + "\n")
        print(path)


if __name__ == "__main__":
    main()
