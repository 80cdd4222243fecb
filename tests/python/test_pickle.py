"""Scene and Camera pickle: a scene as its specification (paths and flags, or its arrays), built
again when unpickled, renders the same images bit for bit; a camera comes back as the same
camera through pickle and through Camera(**params). The reference is the original object's
render and describe() (the camera's resolved frame, lens and counts as the command line prints
them), both independent of the pickling code."""

from __future__ import annotations

import os
import pickle
import warnings
from pathlib import Path

import numpy as np
import pytest

import aperture
from aperture import distributed
from conftest import assert_same_bits, uv_sphere

AOVS = "depth,normal,primid"
EYE, AT = (0.4, 1.1, 4.0), (0.0, 0.2, 0.0)

CAMERAS = [
    dict(type="perspective", eye=EYE, at=AT, fov=35, size=(37, 25)),
    dict(type="thinlens", eye=EYE, at=AT, fov=40, size=(20, 16), spp=4, aperture=0.05, focus=3.5),
    dict(type="orthographic", eye=EYE, at=AT, viewport=(4, 3), size=(24, 18)),
    dict(type="equirect", eye=EYE, size=(32, 16)),
    dict(type="fisheye", eye=EYE, at=AT, fisheye_fov=200, size=(21, 21)),
    dict(type="calibrated", eye=EYE, at=AT, intrinsics=(30, 29, 15.5, 11.5), lens_model="OPENCV",
         distortion=(0.05, -0.01, 0.001, 0.0), size=(32, 23)),
    dict(eye=EYE, at=AT, fov=50, fov_axis="x", up=(0.1, 1, 0), shift=(0.1, -0.05), size=(30, 20)),
]


def views() -> list[aperture.Camera]:
    return [aperture.Camera(eye=EYE, at=AT, fov=40, size=(40, 30)),
            aperture.Camera(eye=(-3.0, 0.5, 2.0), at=AT, fov=30, size=(40, 30))]


def sphere_arrays(dtype: type) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere of radius 1.2, built here (not by aperture)."""
    v, f = uv_sphere(rings=12, segments=24, radius=1.2)
    return v.astype(dtype), f


@pytest.mark.parametrize("spec", ["procedural:default", "procedural:sphere?radius=1.5"])
def test_a_pickled_path_scene_renders_the_same_bits(spec: str) -> None:
    scene = aperture.Scene(spec, quality="medium", compact=True)
    data = pickle.dumps(scene)
    assert len(data) < 2000, "a scene of paths pickles as its specification, not its BVH"
    again = pickle.loads(data)
    assert again is not scene and again.triangle_count == scene.triangle_count
    assert again._spec["quality"] == "medium" and again._spec["compact"] is True
    assert_same_bits(scene.render(views(), aovs=AOVS), again.render(views(), aovs=AOVS))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_pickled_array_scene_renders_the_same_bits(dtype: type) -> None:
    v, f = sphere_arrays(dtype)
    scene = aperture.Scene(vertices=v, faces=f, robust=False)
    again = pickle.loads(pickle.dumps(scene))
    assert again._spec["vertices"].dtype == dtype and again._spec["robust"] is False
    out = scene.render(views(), aovs=AOVS)
    assert np.isfinite(out["depth"]).sum() > 500, "the views should see the sphere"
    assert_same_bits(out, again.render(views(), aovs=AOVS))


def test_a_scene_copies() -> None:
    """copy.copy and copy.deepcopy go through the specification too: a second, independent scene."""
    import copy

    scene = aperture.Scene("procedural:default", world_space=True)
    for other in (copy.copy(scene), copy.deepcopy(scene)):
        assert other._scene is not scene._scene
        assert_same_bits(scene.render(views(), aovs=AOVS), other.render(views(), aovs=AOVS))


def test_a_pickled_file_scene_is_found_from_another_directory(
    tmp_path: Path, bunny: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A relative mesh path pickles as an absolute one: a worker elsewhere finds the file."""
    monkeypatch.chdir(bunny.parent)
    scene = aperture.Scene(bunny.name)
    data = pickle.dumps(scene)
    monkeypatch.chdir(tmp_path)
    again = pickle.loads(data)
    camera = aperture.Camera(eye=(-0.02, 0.11, 0.22), at=(-0.02, 0.11, 0.0), fov=40, size=(40, 30))
    assert_same_bits(scene.render(camera, aovs=AOVS), again.render(camera, aovs=AOVS))


def test_unpickling_builds_once_and_counts(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    log = tmp_path / "builds.log"
    monkeypatch.setenv("APERTURE_SCENE_BUILD_LOG", str(log))
    scene = aperture.Scene("procedural:sphere")
    before = distributed.scene_builds()
    data = pickle.dumps(scene)
    assert distributed.scene_builds() == before, "pickling builds nothing"
    pickle.loads(data)
    pickle.loads(data)
    assert distributed.scene_builds() == before + 2
    lines = log.read_text().splitlines()
    assert len(lines) == 2
    host, pid, seconds, triangles = lines[0].split()
    assert int(pid) == os.getpid() and float(seconds) >= 0 and int(triangles) == scene.triangle_count


def test_large_arrays_warn_when_pickled(monkeypatch: pytest.MonkeyPatch) -> None:
    assert aperture._PICKLE_WARN_BYTES == 64 * 2**20
    v, f = sphere_arrays(np.float32)
    scene = aperture.Scene(vertices=v, faces=f)
    size = scene._spec["vertices"].nbytes + scene._spec["faces"].nbytes
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pickle.dumps(scene)  # below the limit: silent
        pickle.dumps(aperture.Scene("procedural:sphere"))
    monkeypatch.setattr(aperture, "_PICKLE_WARN_BYTES", size - 1)
    with pytest.warns(UserWarning, match=r"travel with every pickle.*Scene\(path\)"):
        pickle.dumps(scene)


@pytest.mark.parametrize("keywords", CAMERAS, ids=[str(k.get("type", "shifted")) for k in CAMERAS])
def test_a_camera_round_trips(keywords: dict) -> None:
    camera = aperture.Camera(**keywords)
    camera.name = "left/0001.jpg"
    again = pickle.loads(pickle.dumps(camera))
    rebuilt = aperture.Camera(**camera.params)
    for other in (again, rebuilt):
        assert other.describe() == camera.describe()
        assert other.params == camera.params
        assert (other.width, other.height, other.type, other.spp) == (
            camera.width, camera.height, camera.type, camera.spp)
    assert again.name == "left/0001.jpg"
    scene = aperture.Scene("procedural:sphere?radius=1.5")
    reference = scene.render(camera, aovs=AOVS)
    assert_same_bits(reference, scene.render(again, aovs=AOVS))
    assert_same_bits(reference, scene.render(rebuilt, aovs=AOVS))


def test_a_camera_of_a_file_round_trips(tmp_path: Path, cli: Path) -> None:
    from conftest import run_cli

    model = tmp_path / "sparse"
    done = run_cli(cli, "camera", "--camera", "calibrated", "--intrinsics", "50,48,20.5,15",
                   "--lens-model", "OPENCV", "--distortion", "0.02,0.001,0,0", "--size", "40x30",
                   "--eye", "0.3,0.5,4", "--at", "0,0,0", "--export", "colmap", "--out", str(model))
    assert done.returncode == 0, done.stderr
    (camera,) = aperture.load_cameras(model)
    again = pickle.loads(pickle.dumps(camera))
    assert again.name == camera.name != ""
    assert again.describe() == camera.describe()
    assert aperture.Camera(**camera.params).describe() == camera.describe()


def test_a_moved_camera_describes_differently() -> None:
    """describe() is a sharp enough reference: a camera moved by 1e-9 differs."""
    a = aperture.Camera(eye=EYE, at=AT, fov=35, size=(37, 25))
    b = aperture.Camera(eye=(EYE[0] + 1e-9, EYE[1], EYE[2]), at=AT, fov=35, size=(37, 25))
    assert a.describe() != b.describe()
