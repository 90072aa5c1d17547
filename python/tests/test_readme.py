"""Every example of the Python guide (docs/python.md, which the README links to) and of
the README runs as written: their Python blocks, and the guide's turntable command, from a
folder that holds the repository's scenes and examples."""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT


def section() -> str:
    return (ROOT / "docs" / "python.md").read_text()


def python_blocks(text: str = "") -> list:
    return re.findall(r"```python\n(.*?)```", text or section(), re.S)


def commands() -> list:
    return [line.strip() for line in section().splitlines()
            if line.startswith("    python ") or line.startswith("    pip ")]


@pytest.fixture
def readme_dir(tmp_path, monkeypatch):
    for name in ("scenes", "examples"):
        (tmp_path / name).symlink_to(ROOT / name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_guide_has_its_examples():
    assert len(python_blocks()) == 2
    assert commands() == [
        "pip install ./python",
        "python examples/python/turntable.py scenes/bb8.toml --frames 8 --size 320x240 --out frames",
        "python examples/python/dataset.py scenes/bb8.toml --frames 8 --seed 7 --aovs depth,normal,object_id,mask --size 320x240 --out data",
    ]


def test_the_python_blocks_run(readme_dir):
    out = io.StringIO()
    scope: dict = {}
    with contextlib.redirect_stdout(out):
        for block in python_blocks():
            exec(compile(block, "docs/python.md", "exec"), scope)
    assert scope["image"].shape == (600, 800, 4)
    assert (readme_dir / "bb8.exr").is_file()
    assert scope["frame"].shape == (240, 320, 4)
    assert (readme_dir / "whitted.png").is_file()
    assert scope["moved"].camera["eye"] == (0.0, 2.0, 9.0)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("(") and lines[0].endswith("(800, 600)"), lines[0]
    assert lines[1] == "<dict>: camera.look_at: equals camera.eye: no view direction"
    assert lines[2] == "camera.look_at"
    assert lines[3].startswith("[")
    assert np.array_equal(scope["rgb"], scope["image"][..., :3])


def test_the_readmes_python_runs(readme_dir):
    blocks = python_blocks((ROOT / "README.md").read_text())
    assert len(blocks) == 1
    scope: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), scope)
    assert scope["image"].shape == (600, 800, 4)
    assert (readme_dir / "bb8.exr").is_file()


def test_the_turntable_command_runs(readme_dir):
    cmd = shlex.split(commands()[1])
    cmd[0] = sys.executable
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    names = sorted(p.name for p in (readme_dir / "frames").iterdir())
    assert names == [f"frame_{k:05d}.png" for k in range(8)]
    assert "[8/8]" in r.stdout


def test_the_dataset_command_runs(readme_dir):
    cmd = shlex.split(commands()[2])
    cmd[0] = sys.executable
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    names = sorted(p.name for p in (readme_dir / "data").iterdir())
    assert names == [f"frame_{k:05d}.npz" for k in range(8)] + ["manifest.json"]
    with np.load(readme_dir / "data" / "frame_00000.npz") as shard:
        assert sorted(shard.files) == ["color", "depth", "mask", "normal", "object_id"]
        assert shard["normal"].shape == (240, 320, 3)
    assert "[8/8]" in r.stdout
