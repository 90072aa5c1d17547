#!/usr/bin/env python3
"""Frames per second of examples/python/turntable.py on a Dask LocalCluster against a
serial loop doing the same work (render, then write the PNG) in one process, in
interleaved rounds. The cluster's start is timed apart.

    python benches/python_dask.py scenes/bb8.toml --frames 24 --size 1024x768 --rounds 3
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import glint

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples" / "python"))
import turntable  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?", default="scenes/bb8.toml")
    p.add_argument("--frames", type=int, default=24)
    p.add_argument("--size", default="1024x768")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--backend", default="cpu")
    a = p.parse_args()
    from dask.distributed import Client, LocalCluster

    w, h = (int(x) for x in a.size.split("x"))
    t = time.perf_counter()
    cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    print(f"LocalCluster of {a.workers} workers started in {time.perf_counter() - t:.2f} s")
    scene = glint.Scene.load(a.scene)
    serial_fps, dask_fps = [], []
    try:
        for k in range(a.rounds):
            out = tempfile.mkdtemp(prefix="glint-dask-bench-")
            t = time.perf_counter()
            for i in range(a.frames):
                turntable.render_frame(scene, i, a.frames, out, "png", a.backend, (w, h))
            serial_fps.append(a.frames / (time.perf_counter() - t))
            shutil.rmtree(out)
            out = tempfile.mkdtemp(prefix="glint-dask-bench-")
            t = time.perf_counter()
            turntable.run(a.scene, a.frames, out, cluster.scheduler_address, "png", a.backend,
                          (w, h), progress=False)
            dask_fps.append(a.frames / (time.perf_counter() - t))
            shutil.rmtree(out)
            print(f"round {k + 1}: serial {serial_fps[-1]:.2f} frames/s, "
                  f"dask {dask_fps[-1]:.2f} frames/s", flush=True)
    finally:
        cluster.close()
    s, d = statistics.median(serial_fps), statistics.median(dask_fps)
    print(f"{a.scene} {a.size} {a.backend}, {a.frames} frames, {os.cpu_count()} CPUs: "
          f"serial {s:.2f} frames/s, dask ({a.workers} workers) {d:.2f} frames/s, "
          f"ratio {d / s:.2f}")


if __name__ == "__main__":
    main()
