"""Python renders equal the command line's EXR bit for bit: every AOV, several camera types.
The command line is the independent path (its own flag parsing, view path and EXR writer);
read_exr reads its file back through core's EXR reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import run_cli

SCENE = "procedural:sphere?radius=1.5"
EYE, AT = (0.4, 1.1, 4.0), (0.0, 0.2, 0.0)

# (camera keywords, the same as command-line flags): different models, sizes and spp.
CASES = [
    (dict(type="perspective", fov=35, size=(67, 45)), ["--camera", "perspective", "--fov", "35", "--size", "67x45"]),
    (dict(type="thinlens", fov=40, size=(40, 32), spp=4, aperture=0.05),
     ["--camera", "thinlens", "--fov", "40", "--size", "40x32", "--spp", "4", "--aperture", "0.05"]),
    (dict(type="orthographic", viewport=(4, 3), size=(48, 36)),
     ["--camera", "orthographic", "--viewport", "4,3", "--size", "48x36"]),
    (dict(type="equirect", size=(64, 32)), ["--camera", "equirect", "--size", "64x32"]),
    (dict(type="fisheye", fisheye_fov=200, size=(41, 41)),
     ["--camera", "fisheye", "--fisheye-fov", "200", "--size", "41x41"]),
    (dict(type="calibrated", intrinsics=(60, 58, 31.5, 22.5), lens_model="OPENCV",
          distortion=(0.05, -0.01, 0.001, 0.0), size=(64, 46)),
     ["--camera", "calibrated", "--intrinsics", "60,58,31.5,22.5", "--lens-model", "OPENCV",
      "--distortion", "0.05,-0.01,0.001,0", "--size", "64x46"]),
]


def vec(v: tuple[float, ...]) -> str:
    return ",".join(repr(float(x)) for x in v)


@pytest.mark.parametrize("keywords,flags", CASES, ids=[c[0]["type"] for c in CASES])
def test_every_aov_equals_the_cli_exr(tmp_path: Path, cli: Path, keywords: dict, flags: list[str]) -> None:
    out = tmp_path / "cli.exr"
    done = run_cli(cli, "render", "--quiet", "--mesh", SCENE, "--aov", "all", "--eye", vec(EYE),
                   "--at", vec(AT), *flags, "--out", str(out))
    assert done.returncode == 0, done.stderr
    reference = aperture.read_exr(out)

    scene = aperture.Scene(SCENE)
    camera = aperture.Camera(eye=EYE, at=AT, **keywords)
    mine = scene.render(camera, aovs="all")

    assert sorted(mine) == sorted(reference)
    assert set(mine) >= {"color", "depth", "distance", "normal", "position", "primid", "geomid"}
    for name, ref in reference.items():
        assert mine[name].dtype == ref.dtype, name
        assert mine[name].shape == ref.shape, name
        # Bit for bit (NaN-safe and -0 != +0): compare the raw bits.
        assert np.array_equal(mine[name].view(np.uint32), ref.view(np.uint32)), name
    assert np.isfinite(mine["depth"]).sum() > 30, "the camera should see the sphere"


def test_a_moved_camera_is_caught(tmp_path: Path, cli: Path) -> None:
    """The comparison is not vacuous: a camera moved by a hundredth of a unit differs."""
    out = tmp_path / "cli.exr"
    done = run_cli(cli, "render", "--quiet", "--mesh", SCENE, "--aov", "depth", "--eye", vec(EYE),
                   "--at", vec(AT), "--size", "32x24", "--out", str(out))
    assert done.returncode == 0, done.stderr
    moved = aperture.Camera(eye=(EYE[0] + 0.01, EYE[1], EYE[2]), at=AT, size=(32, 24))
    depth = aperture.Scene(SCENE).render(moved, aovs="depth")["depth"]
    assert not np.array_equal(depth, aperture.read_exr(out)["depth"])


def test_camera_file_images_equal_the_cli(tmp_path: Path, cli: Path) -> None:
    """load_cameras gives the images of a camera file as the CLI's --cameras/--image renders them."""
    model = tmp_path / "sparse"
    done = run_cli(cli, "camera", "--camera", "calibrated", "--intrinsics", "50,50,20,15",
                   "--size", "40x30", "--eye", "0,0.5,4", "--at", "0,0,0", "--export", "colmap",
                   "--out", str(model))
    assert done.returncode == 0, done.stderr
    cameras = aperture.load_cameras(model)
    assert len(cameras) >= 1
    name = cameras[0].name
    out = tmp_path / "cli.exr"
    done = run_cli(cli, "render", "--quiet", "--mesh", SCENE, "--aov", "depth,normal,primid",
                   "--cameras", str(model), "--image", name, "--out", str(out))
    assert done.returncode == 0, done.stderr
    mine = aperture.Scene(SCENE).render(cameras[0], aovs=["depth", "normal", "primid"])
    for key, ref in aperture.read_exr(out).items():
        assert np.array_equal(mine[key].view(np.uint32), ref.view(np.uint32)), key


def test_the_bunny_equals_the_cli(tmp_path: Path, cli: Path, bunny: Path) -> None:
    """A real PLY (../shared) through both loaders' road: every AOV of the reference view."""
    eye, at = (-0.02, 0.11, 0.22), (-0.02, 0.11, 0.0)
    out = tmp_path / "cli.exr"
    done = run_cli(cli, "render", "--quiet", "--mesh", str(bunny), "--aov", "all", "--eye", vec(eye),
                   "--at", vec(at), "--fov", "40", "--size", "80x60", "--out", str(out))
    assert done.returncode == 0, done.stderr
    mine = aperture.Scene(bunny).render(aperture.Camera(eye=eye, at=at, fov=40, size=(80, 60)), aovs="all")
    reference = aperture.read_exr(out)
    assert sorted(mine) == sorted(reference)
    for name, ref in reference.items():
        assert np.array_equal(mine[name].view(np.uint32), ref.view(np.uint32)), name
    assert np.isfinite(mine["depth"]).sum() > 500, "the bunny should fill part of the view"
