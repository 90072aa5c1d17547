"""Scenes from Python: from files, TOML text and dicts, validated as the command line
validates a file, with its errors; to_dict; pickling."""

from __future__ import annotations

import pickle
import subprocess

import numpy as np
import pytest

import glint
from conftest import ROOT, SCENES, glint_bin, run_cli, same_bits

GOOD = {
    "ambient": [0.2, 0.2, 0.2],
    "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0], "fov": 45, "width": 32, "height": 24},
    "lights": [{"position": [1.0, 1.0, 2.0], "color": [1.0, 1.0, 1.0]}],
    "materials": {"red": {"model": "diffuse", "ka": [0.3, 0, 0], "kd": [0.8, 0, 0]}},
    "spheres": [{"center": [0, 0, 0], "radius": 1.0, "material": "red"}],
}


def test_load_from_toml_and_from_dict_are_one_scene():
    path = SCENES / "whitted.toml"
    a = glint.Scene.load(path)
    b = glint.Scene.from_toml(path.read_text(), base_dir=SCENES)
    c = glint.Scene.from_dict(a.to_dict(), base_dir=SCENES)
    assert a.size == b.size == c.size
    assert a.triangles == b.triangles == c.triangles > 0  # the OBJ floor, read from SCENES
    images = [glint.render(s, backend="cpu", size=(64, 48)) for s in (a, b, c)]
    assert same_bits(images[0], images[1]) and same_bits(images[0], images[2])
    assert str(a.path) == str(path)


def test_dicts_take_numpy_values_and_paths():
    d = dict(GOOD)
    d["camera"] = dict(GOOD["camera"], eye=np.array([0.0, 0.0, 5.0], np.float32),
                       fov=np.float32(45), width=np.int64(32))
    s = glint.Scene.from_dict(d)
    assert same_bits(glint.render(s, backend="cpu"), glint.render(GOOD, backend="cpu"))
    mesh = dict(GOOD, meshes=[{"file": SCENES / "whitted-floor.obj"}])
    assert glint.Scene.from_dict(mesh).triangles > 0
    with pytest.raises(glint.SceneError, match=r"camera\.eye\[0\]: a object is not"):
        glint.Scene.from_dict(dict(GOOD, camera=dict(GOOD["camera"], eye=[object(), 0, 0])))


def test_to_dict_round_trips():
    s = glint.Scene.from_dict(GOOD)
    d = s.to_dict()
    assert d["camera"]["width"] == 32 and d["materials"]["red"]["model"] == "diffuse"
    assert glint.Scene.from_dict(d).to_dict() == d


def test_a_file_error_is_the_clis_message_with_file_line_and_key(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera]\neye=[0.0,0.0,1.0]\nlook_at=[0.0,0.0,1.0]\nfov=40.0\n"
                   "width=8\nheight=8\n")
    with pytest.raises(glint.SceneError) as e:
        glint.Scene.load(bad)
    assert isinstance(e.value, ValueError)
    assert (e.value.file, e.value.line, e.value.key) == (str(bad), 3, "camera.look_at")
    cli = subprocess.run([str(glint_bin()), "render", str(bad), "-o", str(tmp_path / "x.png")],
                         capture_output=True, text=True)
    assert cli.returncode == 1
    assert cli.stderr.strip() == f"error: {e.value}"
    # The same scene given as a path to render raises the same error.
    with pytest.raises(glint.SceneError, match="equals camera.eye"):
        glint.render(bad, backend="cpu")


def test_a_dict_is_validated_as_a_file_is():
    d = dict(GOOD, camera=dict(GOOD["camera"], look_at=[0, 0, 5]))
    with pytest.raises(glint.SceneError) as e:
        glint.Scene.from_dict(d)
    assert str(e.value) == "<dict>: camera.look_at: equals camera.eye: no view direction"
    assert (e.value.file, e.value.line, e.value.key) == ("<dict>", None, "camera.look_at")
    with pytest.raises(glint.SceneError, match="spheres.0..radius: -1 must be finite and > 0"):
        glint.render(dict(GOOD, spheres=[dict(GOOD["spheres"][0], radius=-1.0)]), backend="cpu")
    with pytest.raises(glint.SceneError, match="unknown field `colour`"):
        glint.Scene.from_dict(dict(GOOD, lights=[{"position": [0, 0, 0], "colour": [1, 1, 1]}]))
    # The twin: the good dict renders.
    assert glint.render(GOOD, backend="cpu").shape == (24, 32, 4)


def test_dicts_that_contain_themselves_are_errors_not_crashes():
    # A dict or list that contains itself, and one nested 10,000 deep, is a SceneError
    # naming where it went too deep (it was a stack overflow: the process died).
    looped: dict = dict(GOOD)
    looped["camera"] = dict(GOOD["camera"])
    looped["camera"]["self"] = looped["camera"]
    with pytest.raises(glint.SceneError, match="camera.self.self.*nested deeper than 32"):
        glint.Scene.from_dict(looped)
    items: list = []
    items.append(items)
    with pytest.raises(glint.SceneError, match=r"spheres\[0\]\[0\].*nested deeper"):
        glint.Scene.from_dict(dict(GOOD, spheres=items))
    deep: dict = {}
    for _ in range(10_000):
        deep = {"a": deep}
    with pytest.raises(glint.SceneError, match="nested deeper than 32") as e:
        glint.Scene.from_dict(deep)
    assert e.value.key.startswith("a.a.a")
    # The twin: the same scene without the loop loads.
    assert glint.Scene.from_dict(dict(GOOD, camera=dict(GOOD["camera"]))).spheres == 1


def test_aovs_as_one_string_is_a_type_error():
    with pytest.raises(TypeError, match=r"aovs: a list of AOV names, such as \['depth'\]"):
        glint.render(GOOD, backend="cpu", aovs="depth")
    assert set(glint.render(GOOD, backend="cpu", aovs=["depth"])) == {"color", "depth"}


def test_toml_text_errors_name_the_line():
    with pytest.raises(glint.SceneError) as e:
        glint.Scene.from_toml("[camera]\nfov = 'wide'\n", base_dir="/tmp")
    assert e.value.line == 2 and e.value.file.endswith("<toml>")


def test_io_errors_are_os_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        glint.Scene.load(tmp_path / "missing.toml")
    with pytest.raises(FileNotFoundError):
        glint.render(tmp_path / "missing.toml", backend="cpu")
    with pytest.raises(glint.SceneError, match="meshes.0..file"):
        glint.Scene.from_dict(dict(GOOD, meshes=[{"file": "missing.obj"}]), base_dir=tmp_path)


@pytest.mark.parametrize("make", [
    lambda: glint.Scene.load(SCENES / "whitted.toml"),
    lambda: glint.Scene.from_toml((SCENES / "whitted.toml").read_text(), base_dir=SCENES),
    lambda: glint.Scene.from_dict(glint.Scene.load(SCENES / "whitted.toml").to_dict(),
                                  base_dir=SCENES),
])
def test_a_scene_pickles(make):
    s = make()
    t = pickle.loads(pickle.dumps(s))
    assert type(t) is glint.Scene and t.path == s.path and t.triangles == s.triangles
    assert same_bits(glint.render(s, backend="cpu", size=(48, 36)),
                     glint.render(t, backend="cpu", size=(48, 36)))


def test_a_scene_loads_with_the_cache(tmp_path):
    s = glint.Scene.load(SCENES / "whitted.toml", cache=tmp_path / "cache")
    t = pickle.loads(pickle.dumps(s))
    assert same_bits(glint.render(s, backend="cpu", size=(32, 24)),
                     glint.render(t, backend="cpu", size=(32, 24)))


def test_the_camera_reads_and_changes_without_reloading(tmp_path):
    s = glint.Scene.load(SCENES / "bb8.toml", cache=False)
    c = s.camera
    assert set(c) == {"eye", "look_at", "up", "fov", "size", "samples"}
    assert c["size"] == s.size
    t = s.with_camera(eye=(0.0, 3.0, 9.0), fov=30.0, size=(40, 30))
    assert t.camera["eye"] == (0.0, 3.0, 9.0) and t.camera["fov"] == 30.0
    assert t.size == (40, 30) and t.camera["look_at"] == c["look_at"]
    assert s.camera == c, "the scene it came from is unchanged"
    # The same image as a scene file written with that camera: text, dict and pickle
    # carry the camera, and each renders the same bits.
    direct = glint.render(t, backend="cpu")
    from_text = glint.Scene.from_toml(t.to_toml(), base_dir=SCENES)
    from_dict = glint.Scene.from_dict(t.to_dict(), base_dir=SCENES)
    pickled = pickle.loads(pickle.dumps(t))
    for other in (from_text, from_dict, pickled):
        assert other.camera == t.camera
        assert same_bits(glint.render(other, backend="cpu"), direct)
    # The twin: the old camera renders another image.
    assert not same_bits(glint.render(s, backend="cpu", size=(40, 30)), direct)
    # Setting the camera changes this scene, as with_camera makes a new one.
    u = glint.Scene.load(SCENES / "bb8.toml", cache=False)
    u.camera = {"eye": (0.0, 3.0, 9.0), "fov": 30.0, "size": (40, 30)}
    assert u.camera == t.camera
    assert same_bits(glint.render(u, backend="cpu"), direct)
    with pytest.raises(KeyError, match="focal"):
        u.camera = {"focal": 3.0}
    with pytest.raises(glint.SceneError, match="camera.fov"):
        u.camera = {"fov": 0.0}
    assert u.camera == t.camera, "a refused camera changes nothing"
    # A bad camera is named as a scene file's would be.
    with pytest.raises(glint.SceneError, match="camera.fov"):
        s.with_camera(fov=200.0)
    with pytest.raises(glint.SceneError, match="camera"):
        s.with_camera(eye=c["look_at"])


def test_load_caches_as_the_command_line_does(tmp_path, monkeypatch):
    # The default is the command line's folder (GLINT_CACHE_DIR here); False caches nothing.
    monkeypatch.setenv("GLINT_CACHE_DIR", str(tmp_path / "cache"))
    mesh = tmp_path / "many.obj"
    n = 100_000  # glint.cache.DEFAULT_MIN_PRIMS: smaller meshes are not cached
    mesh.write_text("".join(f"v {i % 200 * 0.01} {i // 200 * 0.01} 0\n"
                            f"v {i % 200 * 0.01 + 0.005} {i // 200 * 0.01} 0\n"
                            f"v {i % 200 * 0.01} {i // 200 * 0.01 + 0.005} 0\n" for i in range(n))
                    + "".join(f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}\n" for i in range(n)))
    scene = tmp_path / "many.toml"
    scene.write_text('[camera]\neye = [1.0, 1.0, 5.0]\nlook_at = [1.0, 1.0, 0.0]\nfov = 60.0\n'
                     'width = 16\nheight = 16\n[materials.m]\nmodel = "ambient"\nka = [1, 1, 1]\n'
                     '[[meshes]]\nfile = "many.obj"\nmaterial = "m"\n')
    glint.Scene.load(scene, cache=False)
    assert not (tmp_path / "cache").exists()
    glint.render(glint.Scene.load(scene), backend="cpu")
    assert (tmp_path / "cache").is_dir() and any((tmp_path / "cache").rglob("*"))


def test_camera_at_is_the_clis_frame_in_every_bit(tmp_path):
    # bb8 with a camera path; frame 5 of `glint render --frames` against the scene moved
    # to camera_at(5) and rendered here.
    text = (SCENES / "bb8.toml").read_text() + (
        "\n[[camera.keys]]\nframe = 0\n"
        "\n[[camera.keys]]\nframe = 8\neye = [6.0, 3.0, 9.0]\nfov = 30.0\n")
    path = tmp_path / "path.toml"
    path.write_text(text)
    s = glint.Scene.load(path, cache=False)
    c = s.camera_at(5)
    assert set(c) == set(s.camera)
    assert s.camera_at(0) == s.camera and s.camera_at(-3) == s.camera
    assert s.camera_at(4)["fov"] == 37.5  # halfway between 45 and 30
    assert s.camera_at(100) == s.camera_at(8)
    run_cli("render", str(path), "--frames", "5", "-o", str(tmp_path / "f_{}.exr"),
            "--backend", "cpu", "--size", "40x30", "--no-cache")
    cli = glint.load(tmp_path / "f_5.exr")
    mine = glint.render(s.with_camera(**c), backend="cpu", size=(40, 30))
    assert same_bits(cli, mine)
    # The twin: frame 4's camera is another image.
    assert not same_bits(cli, glint.render(s.with_camera(**s.camera_at(4)), backend="cpu",
                                           size=(40, 30)))
    with pytest.raises(ValueError, match="not a finite number"):
        s.camera_at(float("nan"))


def test_instances_in_bulk_from_numpy_are_the_files_tables():
    text = (SCENES / "suzanne-instances.toml").read_text()
    head, tail = text.split("\n[[triangles]]", 1)
    base = head.split("\n[[instances]]\n")[0] + "\n[[triangles]]" + tail  # without its instances
    plain = glint.Scene.from_toml(base, base_dir=SCENES)
    maps = np.zeros((2, 4, 4))
    maps[:, 3, 3] = 1.0
    maps[0, :3, :3] = np.diag([2.0, 2.0, 2.0])
    maps[0, :3, 3] = [1.0, -0.5, -1.0]
    maps[1, :3, :3] = np.diag([-1.0, 0.5, 1.0])
    maps[1, :3, 3] = [-1.5, -0.5, 1.0]
    bulk = plain.with_instances("suzanne", maps, material="jade")
    tables = "".join(
        f'\n[[instances]]\nmesh = "suzanne"\nscale = {s}\ntranslate = {t}\nmaterial = "jade"\n'
        for s, t in (([2.0, 2.0, 2.0], [1.0, -0.5, -1.0]), ([-1.0, 0.5, 1.0], [-1.5, -0.5, 1.0]))
    )
    written = glint.Scene.from_toml(base + tables, base_dir=SCENES)
    a = glint.render(bulk, backend="cpu", size=(80, 60))
    b = glint.render(written, backend="cpu", size=(80, 60))
    assert same_bits(a, b)
    # The twin: the scene without them is another picture.
    assert not same_bits(a, glint.render(plain, backend="cpu", size=(80, 60)))
    # (N, 3, 4) is the same; the instances travel in the text and through pickling.
    again = plain.with_instances("suzanne", maps[:, :3, :], material="jade")
    assert same_bits(a, glint.render(again, backend="cpu", size=(80, 60)))
    assert bulk.to_toml().count("matrix = ") == 2
    assert same_bits(a, glint.render(pickle.loads(pickle.dumps(bulk)), backend="cpu", size=(80, 60)))


def test_bulk_instances_refuse_what_they_cannot_place():
    plain = glint.Scene.load(SCENES / "suzanne-instances.toml")
    good = np.tile(np.eye(4), (3, 1, 1))
    with pytest.raises(ValueError, match='no mesh is named "x"'):
        plain.with_instances("x", good)
    flat = good.copy()
    flat[2, 0, :3] = [1.0, 1.0, 0.0]
    flat[2, 1, :3] = [1.0, 1.0, 0.0]
    with pytest.raises(ValueError, match="map 2: the map is singular"):
        plain.with_instances("suzanne", flat)
    skew = good.copy()
    skew[1, 3, 0] = 0.5
    with pytest.raises(ValueError, match="map 1: a 4x4 map's last row"):
        plain.with_instances("suzanne", skew)
    with pytest.raises(ValueError, match="of shape"):
        plain.with_instances("suzanne", np.zeros((3, 3)))
    with pytest.raises(ValueError, match="no material"):
        plain.with_instances("suzanne", good, material="chrome")
