"""examples/python/dataset.py on a Dask LocalCluster of 2 worker processes: each shard
holds the colour and the AOVs of a serial render, the manifest's checksums are the files',
the same seed gives the same bytes, and a worker killed mid-run loses no shard."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import glint
from conftest import ROOT, SCENES, bits

sys.path.insert(0, str(ROOT / "examples" / "python"))
import dataset  # noqa: E402

from dask.distributed import Client, LocalCluster  # noqa: E402

SCENE = SCENES / "bb8.toml"
AOVS = ["depth", "normal", "object_id", "mask"]


@pytest.fixture
def cluster():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as c:
        yield c


def check(out: Path, n: int, size, aovs, backend: str) -> dict:
    """The manifest lists every shard in order with its file's SHA-256, and each shard
    holds a serial render of its camera: the colour and each AOV, bit for bit."""
    m = json.loads((out / "manifest.json").read_text())
    assert [f["frame"] for f in m["frames"]] == list(range(n))
    scene = glint.Scene.load(SCENE)
    for f in m["frames"]:
        path = out / f["file"]
        assert dataset.sha256(str(path)) == f["sha256"], f["file"]
        cam = f["camera"]
        view = scene.with_camera(eye=tuple(cam["eye"]), look_at=tuple(cam["look_at"]),
                                 up=tuple(cam["up"]), fov=cam["fov"])
        ref = glint.render(view, backend=backend, size=size, aovs=aovs)
        with np.load(path) as shard:
            assert sorted(shard.files) == sorted(["color", *aovs])
            for name in ["color", *aovs]:
                a, b = shard[name], ref[name]
                assert a.dtype == b.dtype and a.shape == b.shape, name
                assert np.array_equal(a.view(np.uint32), b.view(np.uint32)), (f, name)
    return m


def test_a_dataset_on_two_workers_is_serial_renders_and_repeats_byte_for_byte(
        tmp_path, cluster):
    size = (96, 72)
    a, b = tmp_path / "a", tmp_path / "b"
    for out in (a, b):
        dataset.run(str(SCENE), 5, str(out), AOVS, seed=7, scheduler=cluster.scheduler_address,
                    backend="cpu", size=size, progress=False)
    m = check(a, 5, size, AOVS, "cpu")
    assert m["seed"] == 7 and m["aovs"] == AOVS and m["size"] == [96, 72]
    # The same seed, the same bytes: every shard and the manifest.
    assert (a / "manifest.json").read_bytes() == (b / "manifest.json").read_bytes()
    # The twin: another seed gives other cameras and other shards.
    other = dataset.random_cameras(glint.Scene.load(SCENE), 5, seed=8)
    assert [f["camera"]["eye"] for f in m["frames"]] != [list(c["eye"]) for c in other]
    # The twin of the check: a shard changed on disk is caught by its checksum.
    shard = a / dataset.shard_name(2)
    data = bytearray(shard.read_bytes())
    data[-100] ^= 1
    shard.write_bytes(bytes(data))
    with pytest.raises(AssertionError):
        check(a, 5, size, AOVS, "cpu")


def test_a_bad_aov_is_refused_before_any_task():
    with pytest.raises(ValueError, match="speed"):
        dataset.run(str(SCENE), 2, "/nonexistent/never-made", ["depth", "speed"],
                    scheduler="tcp://127.0.0.1:1", progress=False)


def test_a_killed_worker_loses_no_shard(tmp_path, cluster):
    n, size = 10, (640, 480)
    cmd = [sys.executable, str(ROOT / "examples" / "python" / "dataset.py"), str(SCENE),
           "--frames", str(n), "--scheduler", cluster.scheduler_address, "--out",
           str(tmp_path), "--aovs", "depth,prim_id", "--backend", "cpu-f64",
           "--size", "640x480", "--seed", "3"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    shards = lambda: [p for p in tmp_path.iterdir() if p.name.startswith("frame_")]
    deadline = time.monotonic() + 120
    while not shards() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.01)
    with Client(cluster.scheduler_address) as client:
        pids = client.run(os.getpid)
    before = len(shards())
    os.kill(next(iter(pids.values())), signal.SIGKILL)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert 0 < before < n, f"the worker was killed with {before} of {n} shards written"
    assert f"[{n}/{n}]" in out
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    check(tmp_path, n, size, ["depth", "prim_id"], "cpu-f64")
