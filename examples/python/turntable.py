#!/usr/bin/env python3
"""A turntable of any glint scene, its frames rendered across a Dask cluster.

    python examples/python/turntable.py scenes/bb8.toml --frames 36 --out frames/
    python examples/python/turntable.py scenes/bb8.toml --scheduler tcp://host:8786 --out /shared/frames

Frame k puts the camera's eye at angle 360°·k/N around the vertical line through
``look_at`` (the scene's up axis), at the scene's own distance and height. Each frame is one
Dask task: a worker renders it with glint (one renderer per worker process, kept across
tasks) and ``glint.save`` writes it to a temporary name in ``--out``, then renames it into
place, so a frame file is always whole. Where a worker dies, Dask runs its frames again on
another; a frame written twice is the same bits written twice, never a torn file. Once
every frame is in, the temporary files of writers that died are removed (``--out`` belongs
to this run).

``--scheduler local`` (the default) starts a ``LocalCluster`` on this machine. On a real
cluster start ``dask scheduler`` on one machine and ``dask worker tcp://HOST:8786`` on each
of the others (each with glint installed), then pass ``--scheduler tcp://HOST:8786``. The
scene's mesh files and ``--out`` must be at the same paths on every worker (a shared file
system).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import uuid
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

import glint


def frame_scene(scene: glint.Scene, k: int, n: int) -> glint.Scene:
    """The scene with the camera turned to frame ``k`` of ``n`` around its up axis (the
    meshes are not read again: ``with_camera`` copies the scene in memory)."""
    cam = scene.camera
    eye, at, up = (np.array(cam[key], np.float64) for key in ("eye", "look_at", "up"))
    up /= np.linalg.norm(up)
    v = eye - at
    h = v @ up  # height along up
    r = v - h * up  # the part that turns
    angle = 2.0 * math.pi * k / n
    turned = at + h * up + math.cos(angle) * r + math.sin(angle) * np.cross(up, r)
    return scene.with_camera(eye=tuple(float(x) for x in turned))


def frame_name(k: int, fmt: str) -> str:
    """The file name of frame ``k``."""
    return f"frame_{k:05d}.{fmt}"


def render_frame(
    scene: glint.Scene,
    k: int,
    n: int,
    out: str,
    fmt: str,
    backend: str,
    size: Optional[Tuple[int, int]],
) -> str:
    """Renders frame ``k`` of ``n`` into ``out`` and returns its path. ``glint.save`` writes
    the file whole: a temporary name in the same folder, then a rename."""
    image = glint.render(frame_scene(scene, k, n), backend=backend, size=size)
    final = os.path.join(out, frame_name(k, fmt))
    glint.save(final, image)
    return final


def remove_stale_temporaries(out: str) -> List[str]:
    """Removes what killed workers left in ``out``: the temporary files of frames whose
    writer died before its rename (``.frame_*.tmp``). Called once every frame is in, when
    no writer of this run is left. Returns their names."""
    stale = [f for f in os.listdir(out) if f.startswith(".frame_") and f.endswith(".tmp")]
    for f in stale:
        os.unlink(os.path.join(out, f))
    return stale


def run(
    scene_path: str,
    frames: int,
    out: str,
    scheduler: str = "local",
    fmt: str = "png",
    backend: str = "auto",
    size: Optional[Tuple[int, int]] = None,
    workers: int = 2,
    progress: bool = True,
) -> List[str]:
    """Renders the turntable on the cluster at ``scheduler`` (or a local one) and returns
    the frames' paths in order."""
    from dask.distributed import Client, LocalCluster, as_completed

    os.makedirs(out, exist_ok=True)
    scene = glint.Scene.load(scene_path)  # errors here, before any task is sent
    cluster = None
    if scheduler == "local":
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        scene_f = client.scatter(scene, broadcast=True)
        futures = [
            client.submit(
                render_frame, scene_f, k, frames, out, fmt, backend, size,
                key=f"glint-frame-{k}-{uuid.uuid4().hex[:8]}", retries=2,
            )
            for k in range(frames)
        ]
        start = time.perf_counter()
        done = 0
        for fut in as_completed(futures):
            path = fut.result()
            done += 1
            if progress:
                rate = done / max(time.perf_counter() - start, 1e-9)
                print(f"[{done}/{frames}] {path} ({rate:.1f} frames/s)", flush=True)
        paths = [f.result() for f in futures]
        for f in remove_stale_temporaries(out):
            print(f"removed {f}, left by a worker that died while writing", flush=True)
        return paths
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _size(s: str) -> Tuple[int, int]:
    w, _, h = s.partition("x")
    return int(w), int(h)


def main(argv: Optional[List[str]] = None) -> int:
    """The command line."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help="the scene file (TOML)")
    p.add_argument("--frames", type=int, default=36, help="frames in a full turn")
    p.add_argument("--scheduler", default="local",
                   help="a Dask scheduler's address, or 'local' for a LocalCluster here")
    p.add_argument("--out", required=True, help="the folder the frames go to")
    p.add_argument("--format", choices=["png", "exr"], default="png")
    p.add_argument("--backend", default="auto", choices=glint.backends())
    p.add_argument("--size", type=_size, default=None, help="WIDTHxHEIGHT")
    p.add_argument("--workers", type=int, default=2, help="worker processes of 'local'")
    a = p.parse_args(argv)
    if a.frames < 1:
        p.error("--frames must be at least 1")
    try:
        run(a.scene, a.frames, a.out, a.scheduler, a.format, a.backend, a.size, a.workers)
    except (glint.SceneError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
