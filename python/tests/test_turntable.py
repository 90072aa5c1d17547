"""examples/python/turntable.py on a Dask LocalCluster of 2 worker processes: every frame
equals a serial render bit for bit, also when a worker is killed mid-run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import glint
from conftest import ROOT, SCENES, same_bits

sys.path.insert(0, str(ROOT / "examples" / "python"))
import turntable  # noqa: E402

from dask.distributed import Client, LocalCluster  # noqa: E402

SCENE = SCENES / "whitted.toml"


def serial(n: int, backend: str, size) -> list:
    s = glint.Scene.load(SCENE)
    return [glint.render(turntable.frame_scene(s, k, n), backend=backend, size=size)
            for k in range(n)]


def check_frames(out: Path, n: int, backend: str, size) -> None:
    names = sorted(p.name for p in out.iterdir())
    assert names == [turntable.frame_name(k, "exr") for k in range(n)], names
    for k, ref in enumerate(serial(n, backend, size)):
        assert same_bits(glint.load(out / turntable.frame_name(k, "exr")), ref), k


@pytest.fixture
def cluster():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as c:
        yield c


def test_a_turntable_on_two_workers_equals_serial_renders(tmp_path, cluster):
    paths = turntable.run(str(SCENE), 6, str(tmp_path), cluster.scheduler_address,
                          fmt="exr", backend="cpu", size=(160, 120), progress=False)
    assert [Path(p).name for p in paths] == [turntable.frame_name(k, "exr") for k in range(6)]
    check_frames(tmp_path, 6, "cpu", (160, 120))
    # The twin: the camera turns, so neighbouring frames differ.
    a, b = (glint.load(tmp_path / turntable.frame_name(k, "exr")) for k in (0, 1))
    assert not same_bits(a, b)
    # The twin of the check: a lost frame is seen.
    (tmp_path / turntable.frame_name(3, "exr")).unlink()
    with pytest.raises(AssertionError):
        check_frames(tmp_path, 6, "cpu", (160, 120))


def test_a_killed_worker_loses_no_frame(tmp_path, cluster):
    n, size = 12, (1024, 768)
    cmd = [sys.executable, str(ROOT / "examples" / "python" / "turntable.py"), str(SCENE),
           "--frames", str(n), "--scheduler", cluster.scheduler_address, "--out",
           str(tmp_path), "--format", "exr", "--backend", "cpu-f64", "--size", "1024x768"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    frames = lambda: [p for p in tmp_path.iterdir() if p.name.startswith("frame_")]
    deadline = time.monotonic() + 120
    while not frames() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.01)
    with Client(cluster.scheduler_address) as client:
        pids = client.run(os.getpid)
    before = len(frames())
    os.kill(next(iter(pids.values())), signal.SIGKILL)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert 0 < before < n, f"the worker was killed with {before} of {n} frames written"
    assert sum(line.startswith("[") for line in out.splitlines()) == n, out  # a line a frame
    assert f"[{n}/{n}]" in out
    check_frames(tmp_path, n, "cpu-f64", size)
