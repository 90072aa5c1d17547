#!/usr/bin/env python3
"""The Python package's cost per render: the same scene rendered by a kept Renderer from
Rust (examples/render_loop.rs) and from Python (glint.Renderer.render), in interleaved
rounds. Prints each round's medians and the overhead (Python - Rust).

    cargo build --release --example render_loop
    python benches/python_overhead.py scenes/bb8.toml --backend cpu --reps 30 --rounds 5
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import time
from pathlib import Path

import glint

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?", default="scenes/bb8.toml")
    p.add_argument("--backend", default="cpu")
    p.add_argument("--reps", type=int, default=30)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--size", default="1024x768")
    a = p.parse_args()
    w, h = (int(x) for x in a.size.split("x"))
    exe = ROOT / "target" / "release" / "examples" / "render_loop"
    scene = glint.Scene.load(a.scene)
    r = glint.Renderer(a.backend)
    warm = 3
    rows = []
    for k in range(a.rounds):
        out = subprocess.run([str(exe), a.scene, a.backend, str(a.reps + warm), a.size],
                             capture_output=True, text=True, check=True).stdout.split()
        rust = statistics.median(float(x) for x in out[warm:])
        times = []
        for i in range(a.reps + warm):
            t = time.perf_counter()
            r.render(scene, size=(w, h))
            times.append((time.perf_counter() - t) * 1e3)
        py = statistics.median(times[warm:])
        rows.append((rust, py))
        print(f"round {k + 1}: rust {rust:.3f} ms, python {py:.3f} ms, "
              f"overhead {py - rust:+.3f} ms ({(py / rust - 1) * 100:+.1f} %)", flush=True)
    d = [py - rust for rust, py in rows]
    print(f"{a.scene} {a.size} {a.backend}: median rust "
          f"{statistics.median(x for x, _ in rows):.3f} ms, python "
          f"{statistics.median(y for _, y in rows):.3f} ms, overhead median {statistics.median(d):+.3f} ms "
          f"({statistics.median((y / x - 1) * 100 for x, y in rows):+.1f} %)")


if __name__ == "__main__":
    main()
