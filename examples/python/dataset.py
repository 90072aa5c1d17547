#!/usr/bin/env python3
"""A synthetic data set of any glint scene: frames with their AOVs, across a Dask cluster.

    python examples/python/dataset.py scenes/bb8.toml --frames 100 --seed 7 --out data/
    python examples/python/dataset.py scenes/bb8.toml --aovs depth,normal,prim_id --out data/
    python examples/python/dataset.py scene.toml --path --frames 121 --out data/   # [[camera.keys]]

Frame k's camera is either the scene's camera path at frame k (``--path``: its
``[[camera.keys]]``) or a random view from ``--seed``: the eye at the scene's own distance
from ``look_at``, in a direction drawn uniformly over the upper half sphere about the
scene's up axis (numpy's PCG64 generator, the same draws on every machine). Each frame is
one Dask task, which renders the colour and the AOVs (``glint.render(..., aovs=...)``) and
writes one shard, ``frame_KKKKK.npz`` (numpy's uncompressed archive: ``color`` and one
array per AOV, see docs/aov.md), to a temporary name then renamed into place, so a shard
is always whole; a frame that a dead worker left is rendered again by another (Dask's
retries), and the same bits are written again.

When every frame is in, ``manifest.json`` lists them in order: the frame, its camera, the
shard's file name and its SHA-256, the AOVs, the scene and the seed. The same scene, seed,
size and AOVs give the same bytes, shard for shard, on any machine and on any backend
that is bit-exact (the CPU tracers; the GPU on lavapipe, where GPU = CPU in every bit).

``--scheduler local`` (the default) starts a ``LocalCluster`` here; on a real cluster pass
``--scheduler tcp://HOST:8786`` (the scene's files and ``--out`` at the same paths on every
worker).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import sys
import time
import uuid
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

import glint

DEFAULT_AOVS = ["depth", "normal", "albedo", "object_id", "mask"]


def random_cameras(scene: glint.Scene, n: int, seed: int) -> List[Dict[str, Any]]:
    """``n`` cameras looking at the scene's ``look_at`` from its own distance, each eye in
    a direction uniform over the half sphere above (about the scene's ``up``), drawn from
    ``seed``."""
    cam = scene.camera
    eye, at, up = (np.array(cam[key], np.float64) for key in ("eye", "look_at", "up"))
    up /= np.linalg.norm(up)
    dist = float(np.linalg.norm(eye - at))
    # A frame (u, w, up) about the up axis.
    helper = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    u = np.cross(up, helper)
    u /= np.linalg.norm(u)
    w = np.cross(up, u)
    rng = np.random.Generator(np.random.PCG64(seed))
    out = []
    for _ in range(n):
        z, phi = rng.uniform(0.05, 1.0), rng.uniform(0.0, 2.0 * math.pi)
        r = math.sqrt(1.0 - z * z)
        d = r * math.cos(phi) * u + r * math.sin(phi) * w + z * up
        out.append({"eye": tuple(float(x) for x in at + dist * d),
                    "look_at": cam["look_at"], "up": cam["up"], "fov": cam["fov"]})
    return out


def path_cameras(scene: glint.Scene, n: int) -> List[Dict[str, Any]]:
    """Frames 0 to ``n`` − 1 of the scene's camera path."""
    return [{key: scene.camera_at(k)[key] for key in ("eye", "look_at", "up", "fov")}
            for k in range(n)]


def shard_name(k: int) -> str:
    """The file name of frame ``k``'s shard."""
    return f"frame_{k:05d}.npz"


def render_shard(
    scene: glint.Scene,
    k: int,
    camera: Dict[str, Any],
    out: str,
    aovs: Sequence[str],
    backend: str,
    size: Optional[Tuple[int, int]],
) -> str:
    """Renders frame ``k`` with ``camera`` and its AOVs, and writes its shard whole (a
    temporary name in ``out``, then a rename). Returns the shard's path."""
    view = scene.with_camera(eye=tuple(camera["eye"]), look_at=tuple(camera["look_at"]),
                             up=tuple(camera["up"]), fov=camera["fov"])
    arrays = glint.render(view, backend=backend, size=size, aovs=list(aovs))
    final = os.path.join(out, shard_name(k))
    tmp = os.path.join(out, f".{shard_name(k)}.{uuid.uuid4().hex[:8]}.tmp")
    with open(tmp, "wb") as f:
        # Uncompressed, and numpy's archive stamps no time: the same arrays, the same bytes.
        np.savez(f, **{name: arrays[name] for name in ["color", *aovs]})
    os.replace(tmp, final)
    return final


def sha256(path: str) -> str:
    """The file's SHA-256, in hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_manifest(out: str, meta: Dict[str, Any], cameras: List[Dict[str, Any]]) -> str:
    """Writes ``manifest.json`` (whole, by a rename): ``meta`` and each frame's camera,
    shard and SHA-256, read from the shards as they are on disk."""
    frames = [{"frame": k, "camera": cam, "file": shard_name(k),
               "sha256": sha256(os.path.join(out, shard_name(k)))}
              for k, cam in enumerate(cameras)]
    path = os.path.join(out, "manifest.json")
    tmp = path + f".{uuid.uuid4().hex[:8]}.tmp"
    with open(tmp, "w") as f:
        json.dump({**meta, "frames": frames}, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)
    return path


def run(
    scene_path: str,
    frames: int,
    out: str,
    aovs: Sequence[str] = DEFAULT_AOVS,
    seed: int = 0,
    path: bool = False,
    scheduler: str = "local",
    backend: str = "cpu",
    size: Optional[Tuple[int, int]] = None,
    workers: int = 2,
    progress: bool = True,
) -> str:
    """Renders the data set on the cluster at ``scheduler`` (or a local one) and returns
    the manifest's path."""
    from dask.distributed import Client, LocalCluster, as_completed

    unknown = [a for a in aovs if a not in glint.aovs()]
    if unknown:
        raise ValueError(f"unknown AOVs {unknown}: the AOVs are {', '.join(glint.aovs())}")
    os.makedirs(out, exist_ok=True)
    scene = glint.Scene.load(scene_path)  # errors here, before any task is sent
    cameras = path_cameras(scene, frames) if path else random_cameras(scene, frames, seed)
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
                render_shard, scene_f, k, cam, out, list(aovs), backend, size,
                key=f"glint-shard-{k}-{uuid.uuid4().hex[:8]}", retries=2,
            )
            for k, cam in enumerate(cameras)
        ]
        start = time.perf_counter()
        for done, fut in enumerate(as_completed(futures), 1):
            shard = fut.result()
            if progress:
                rate = done / max(time.perf_counter() - start, 1e-9)
                print(f"[{done}/{frames}] {shard} ({rate:.1f} frames/s)", flush=True)
        for f in os.listdir(out):
            if f.startswith(".frame_") and f.endswith(".tmp"):
                os.unlink(os.path.join(out, f))  # left by a worker that died writing
        meta = {"scene": str(scene_path), "seed": None if path else seed,
                "cameras": "path" if path else "random", "aovs": list(aovs),
                "backend": backend, "size": list(size) if size else list(scene.camera["size"])}
        return write_manifest(out, meta, cameras)
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
    p.add_argument("--frames", type=int, default=16, help="frames in the data set")
    p.add_argument("--out", required=True, help="the folder the shards go to")
    p.add_argument("--aovs", default=",".join(DEFAULT_AOVS),
                   help="comma-separated AOVs (docs/aov.md)")
    p.add_argument("--seed", type=int, default=0, help="the random cameras' seed")
    p.add_argument("--path", action="store_true",
                   help="the scene's camera path ([[camera.keys]]) instead of random views")
    p.add_argument("--scheduler", default="local",
                   help="a Dask scheduler's address, or 'local' for a LocalCluster here")
    p.add_argument("--backend", default="cpu", choices=glint.backends())
    p.add_argument("--size", type=_size, default=None, help="WIDTHxHEIGHT")
    p.add_argument("--workers", type=int, default=2, help="worker processes of 'local'")
    a = p.parse_args(argv)
    if a.frames < 1:
        p.error("--frames must be at least 1")
    aovs = [s.strip() for s in a.aovs.split(",") if s.strip()]
    try:
        run(a.scene, a.frames, a.out, aovs, a.seed, a.path, a.scheduler, a.backend, a.size,
            a.workers)
    except (glint.SceneError, OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
