"""Every example of the Python guide (docs/python.md, which the README links to) runs as
written: its Python blocks, and its turntable command, from a folder that holds the
repository's scenes and examples."""

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


def python_blocks() -> list:
    return re.findall(r"```python\n(.*?)```", section(), re.S)


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
    lines = out.getvalue().splitlines()
    assert lines[0] == "<dict>: camera.look_at: equals camera.eye: no view direction"
    assert lines[1] == "camera.look_at"
    assert lines[2].startswith("[")
    assert np.array_equal(scope["rgb"], scope["image"][..., :3])


def test_the_turntable_command_runs(readme_dir):
    cmd = shlex.split(commands()[1])
    cmd[0] = sys.executable
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    names = sorted(p.name for p in (readme_dir / "frames").iterdir())
    assert names == [f"frame_{k:05d}.png" for k in range(8)]
    assert "[8/8]" in r.stdout
