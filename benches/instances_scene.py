#!/usr/bin/env python3
"""Writes the instancing benchmark: N instances of the Stanford dragon (871,414 triangles,
scenes/meshes/dragon_full.obj.gz from `bash scenes/fetch-meshes.sh`) on a ground plane,
a square grid of them, each turned and scaled a little by a fixed pseudo-random sequence
(so the file is the same every time), seen from above at an angle.

    python3 benches/instances_scene.py --count 10000 --out bench-out/instances

writes OUT/dragons_N.toml (meshes relative to the repository's scenes/ folder). N = 1 is
the single dragon, the baseline of the warm frame.
"""
import argparse
import math
import os


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=10000)
    ap.add_argument("--out", default="bench-out/instances")
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    side = math.ceil(math.sqrt(a.count))
    spacing = 2.2
    half = (side - 1) * spacing / 2
    mesh = os.path.relpath(
        os.path.join(os.path.dirname(__file__), "..", "scenes", "meshes", "dragon_full.obj.gz"),
        a.out,
    )
    extent = half + 2.0
    dist = max(3.0, extent * 1.6)
    lines = [
        f"# {a.count} instances of the Stanford dragon (871,414 triangles each) on a ground plane:",
        "# written by benches/instances_scene.py.",
        "ambient = [0.12, 0.12, 0.12]",
        "background = [0.05, 0.06, 0.09]",
        'triangle = "watertight"',
        "shadows = true",
        "",
        "[camera]",
        f"eye = [0.0, {dist * 0.8:.3f}, {dist:.3f}]",
        "look_at = [0.0, -0.8, 0.0]",
        "fov = 40.0",
        f"width = {a.width}",
        f"height = {a.height}",
        "",
        "[[lights]]",
        f"position = [{-extent:.3f}, {extent * 2 + 5:.3f}, {extent + 6:.3f}]",
        "color = [0.75, 0.72, 0.65]",
        "",
        "[materials.jade]",
        'model = "phong"',
        "ka = [0.35, 0.7, 0.45]",
        "kd = [0.3, 0.65, 0.4]",
        "ks = [0.7, 0.7, 0.7]",
        "n = 60.0",
        "",
        "[materials.gold]",
        'model = "phong"',
        "ka = [0.5, 0.38, 0.12]",
        "kd = [0.75, 0.56, 0.18]",
        "ks = [0.8, 0.75, 0.6]",
        "n = 40.0",
        "",
        "[materials.floor]",
        'model = "diffuse"',
        "ka = [0.4, 0.4, 0.45]",
        "kd = [0.45, 0.45, 0.5]",
        "",
        "[[meshes]]",
        'name = "dragon"',
        "hidden = true",
        f'file = "{mesh}"',
        'material = "jade"',
        "scale = [11.0, 11.0, 11.0]",
        "translate = [0.06, -1.45, 0.05]",
        "",
        "[[triangles]]",
        f"vertices = [[{-extent:.3f}, -1.0, {-extent:.3f}], [{extent:.3f}, -1.0, {extent:.3f}], [{extent:.3f}, -1.0, {-extent:.3f}]]",
        'material = "floor"',
        "",
        "[[triangles]]",
        f"vertices = [[{-extent:.3f}, -1.0, {-extent:.3f}], [{-extent:.3f}, -1.0, {extent:.3f}], [{extent:.3f}, -1.0, {extent:.3f}]]",
        'material = "floor"',
        "",
    ]
    seed = 12345
    for k in range(a.count):
        seed = (seed * 1103515245 + 12345) % 2**31
        turn = seed % 360
        scale = 0.8 + (seed >> 9) % 40 / 100
        x = (k % side) * spacing - half
        z = (k // side) * spacing - half
        lines += [
            "[[instances]]",
            'mesh = "dragon"',
            f"scale = [{scale:.2f}, {scale:.2f}, {scale:.2f}]",
            f"rotate = [0.0, {turn}.0, 0.0]",
            f"translate = [{x:.3f}, {scale - 1.0:.3f}, {z:.3f}]",  # the feet stay on y = -1
        ]
        if k % 7 == 3:
            lines.append('material = "gold"')
        lines.append("")
    path = os.path.join(a.out, f"dragons_{a.count}.toml")
    with open(path, "w") as f:
        f.write("\n".join(lines))
    print(path)


if __name__ == "__main__":
    main()
