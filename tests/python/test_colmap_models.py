"""COLMAP 4's camera models checked by pycolmap itself (a real client: `pip install pycolmap`,
which scripts/venv.sh installs; without it these tests skip with a message).

aperture renders each model from the centre of a sphere, so every ray it gives hits. Then:
 - every hit re-projects onto its pixel centre through pycolmap's `Camera.img_from_cam` (without
   its cheirality test: the division models and EUCM see behind the camera, and COLMAP's
   forward maps follow them there). COLMAP's fisheye models cannot project a point behind the
   camera (their `img_from_cam` works on x/z, y/z); there the hit's angle θ off-axis and its
   azimuth are those of pycolmap's own undistorted fisheye coordinates, which `cam_from_img`
   returns unchanged past 90° off-axis;
 - every pixel for which pycolmap's `cam_ray_from_img` gives a ray that `img_from_cam` takes
   back onto the pixel is a hit along that ray: aperture has a ray wherever COLMAP has one.
   Where COLMAP's inverse gives a ray that does not come back (past a fold, or the antipode of
   the true ray past the division model's circle), aperture gives the true ray or none;
 - the COLMAP model files aperture exports (`aperture camera --export colmap`) are read by
   pycolmap as the same model and parameters, and pycolmap's binary model (cameras.bin) of
   them reads back into aperture as the same camera.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import run_cli

W, H = 80, 60
CX, CY = 40.3, 29.7

# Each model with realistic, non-zero distortion and a focal length short enough that the image
# reaches past what the model can see (the fold, the limit of its formula, or behind the
# camera), so both hits and misses are checked.
CASES = {
    "SIMPLE_PINHOLE": [60, CX, CY],
    "PINHOLE": [60, 61, CX, CY],
    "SIMPLE_RADIAL": [60, CX, CY, -0.15],
    "RADIAL": [60, CX, CY, -0.2, 0.05],
    "OPENCV": [60, 61, CX, CY, -0.2, 0.03, 1e-3, -5e-4],
    "OPENCV_FISHEYE": [25, 25.5, CX, CY, -0.05, 0.002, 0, 0],
    "FULL_OPENCV": [60, 61, CX, CY, -0.2, 0.03, 1e-3, -5e-4, 0.01, 0.05, 0.002, 0.01],
    # ω = 0.9: the image circle ρ < π / (2ω) is 43.6 px at f = 25.
    "FOV": [25, 25.5, CX, CY, 0.9],
    "SIMPLE_RADIAL_FISHEYE": [25, CX, CY, -0.06],
    "RADIAL_FISHEYE": [25, CX, CY, -0.03, -0.002],
    "THIN_PRISM_FISHEYE": [25, 25.5, CX, CY, -0.06, 0.001, 1e-3, -1e-3, 0, 0, 1e-3, -5e-4],
    # k = −0.3: past ρ = 1/√0.3 (45.6 px at f = 25) the rays point behind the camera.
    "SIMPLE_DIVISION": [25, CX, CY, -0.3],
    # k = 0.2: the fold at ρ = 1/√0.2 (44.7 px at f = 20); the corners lie past it.
    "DIVISION": [20, 20.5, CX, CY, 0.2],
    "SIMPLE_FISHEYE": [20, CX, CY],
    "FISHEYE": [20, 20.5, CX, CY],
    # α = 0.6, β = 1.1: behind the camera past ρ = 1.59 (32 px at f = 20), nothing past
    # ρ = 1/√(β(2α − 1)) = 2.13 (43 px).
    "EUCM": [20, 20.5, CX, CY, 0.6, 1.1],
    # Project Aria's model, with tangential and thin-prism terms.
    "RAD_TAN_THIN_PRISM_FISHEYE": [
        25, 25.5, CX, CY, 0.02, -0.01, 0.002, -1e-4, 0, 0, 0.004, -0.003, 0.01, -0.002, -0.008, 0.001
    ],
    # The whole sphere: every pixel has its ray.
    "EQUIRECTANGULAR": [W, H],
}


# The cases whose image reaches past what the model sees (a fold, the limit of its formula),
# and those that see behind the camera (θ > 90°) in the image.
MISSES = {"FOV", "DIVISION", "EUCM", "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE"}
BEHIND = {
    "OPENCV_FISHEYE", "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE",
    "RAD_TAN_THIN_PRISM_FISHEYE", "SIMPLE_FISHEYE", "FISHEYE", "SIMPLE_DIVISION", "EUCM",
    "EQUIRECTANGULAR",
}


@pytest.fixture(scope="module")
def sphere() -> aperture.Scene:
    return aperture.Scene("procedural:sphere?radius=10&segments=256&rings=128")


def camera_of(pycolmap, model: str, params: list[float]) -> aperture.Camera:
    """aperture's calibrated camera of COLMAP's model and parameters, at the origin looking
    along +z (OpenCV axes = world axes)."""
    cam = pycolmap.Camera(model=model, width=W, height=H, params=params)
    focal, centre = cam.focal_length_idxs(), cam.principal_point_idxs()
    if cam.is_spherical():  # EQUIRECTANGULAR: w, h, and the linear part of its map
        intrinsics, coefficients = (W / (2 * math.pi), H / math.pi, W / 2, H / 2), params
    else:
        fx, fy = params[focal[0]], params[focal[-1]]
        intrinsics = (fx, fy, params[centre[0]], params[centre[1]])
        coefficients = [params[i] for i in cam.extra_params_idxs()]
    keys = dict(
        type="calibrated",
        size=(W, H),
        intrinsics=intrinsics,
        lens_model=model,
        world_to_camera=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
    )
    if coefficients:
        keys["distortion"] = list(coefficients)
    return aperture.Camera(**keys)


def sensitivity(cam, dirs: np.ndarray) -> np.ndarray:
    """How many pixels img_from_cam moves per radian the direction turns: the largest of four
    turns of 1e-8 rad (a turn past a fold, where img_from_cam has nothing, is left out)."""
    base = np.asarray(cam.img_from_cam(dirs, check_cheirality=False), dtype=np.float64)
    helper = np.where(np.abs(dirs[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    e1 = np.cross(dirs, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(dirs, e1)
    worst = np.zeros(len(dirs))
    for e in (e1, -e1, e2, -e2):
        moved = np.asarray(cam.img_from_cam(dirs + 1e-8 * e, check_cheirality=False), dtype=np.float64)
        worst = np.fmax(worst, np.linalg.norm(moved - base, axis=1) / 1e-8)
    return worst


def rays_through_pycolmap(cam, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """pycolmap's ray of each pixel centre that img_from_cam takes back onto the centre (NaN
    where it has none), and whether each is one."""
    rays = np.asarray(cam.cam_ray_from_img(centres), dtype=np.float64)
    back = np.asarray(cam.img_from_cam(rays, check_cheirality=False), dtype=np.float64)
    ok = np.all(np.isfinite(rays), axis=1) & (np.linalg.norm(back - centres, axis=1) < 1e-6)
    rays[~ok] = np.nan
    return rays, ok


@pytest.mark.parametrize("model", sorted(CASES))
def test_every_hit_reprojects_through_pycolmap_and_every_colmap_ray_is_a_hit(
    pycolmap, sphere: aperture.Scene, model: str
) -> None:
    params = CASES[model]
    cam = pycolmap.Camera(model=model, width=W, height=H, params=params)
    assert cam.model_name == model
    out = sphere.render(camera_of(pycolmap, model, params), aovs=["position", "primid"])
    hit = out["primid"] != 0xFFFFFFFF
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    centres = np.stack([jj + 0.5, ii + 0.5], axis=-1).reshape(-1, 2).astype(np.float64)
    hit = hit.reshape(-1)
    points = out["position"].reshape(-1, 3).astype(np.float64)
    with np.errstate(invalid="ignore"):  # a miss's P is 0
        dirs = points / np.linalg.norm(points, axis=1, keepdims=True)
    fisheye = cam.is_perspective_fisheye()

    # Every hit: its pixel centre through img_from_cam, or for a COLMAP fisheye behind the
    # camera, through the fisheye coordinates pycolmap's cam_from_img returns there.
    projected = np.asarray(cam.img_from_cam(dirs[hit], check_cheirality=False), dtype=np.float64)
    error = np.linalg.norm(projected - centres[hit], axis=1)
    behind = dirs[hit][:, 2] <= 1e-6
    if fisheye:
        uv = np.asarray(cam.cam_from_img(centres[hit][behind]), dtype=np.float64)
        theta = np.linalg.norm(uv, axis=1)
        assert np.all(theta >= math.pi / 2 - 1e-6), "cam_from_img returns its input only past 90°"
        expected = np.column_stack(
            [uv * (np.sin(theta) / theta)[:, None], np.cos(theta)]
        )
        error[behind] = np.linalg.norm(dirs[hit][behind] - expected, axis=1) * params[0]
    # The hit points are float32 (P): their directions carry ~1e-7 of rounding, which a lens
    # magnifies by how fast its pixel moves with the direction (near a fold, a lot): the
    # tolerance is 1e-3 px plus ten times that.
    tolerance = 1e-3 + 1e-6 * sensitivity(cam, dirs[hit])
    bad = np.flatnonzero(~(error < tolerance))
    assert bad.size == 0, (
        f"{model}: {bad.size} of {hit.sum()} hits do not re-project onto their pixel centre "
        f"(worst {np.nanmax(error):.3g} px; first at pixel {centres[hit][bad[0]]})"
    )

    # Every pixel COLMAP gives a ray that comes back is a hit along it.
    rays, has = rays_through_pycolmap(cam, centres)
    missing = np.flatnonzero(has & ~hit)
    assert missing.size == 0, f"{model}: COLMAP has a ray at {centres[missing[:5]]}, aperture none"
    both = has & hit
    angle = np.linalg.norm(dirs[both] - rays[both], axis=1)
    assert np.all(angle < 1e-5), f"{model}: rays differ by up to {angle.max():.3g}"

    # The image reaches past what the model sees (misses) and, where the case says so, behind
    # the camera (hits with z < 0).
    if model in MISSES:
        assert hit.sum() < W * H, f"{model}: the case must reach past the valid region"
    else:
        assert hit.all(), f"{model}: every pixel has a ray"
    if model in BEHIND:
        assert (dirs[hit][:, 2] < 0).any(), f"{model}: the case must see behind the camera"


def flags_of(cam: aperture.Camera) -> list[str]:
    """The command-line flags of a camera's parameters (its job-file keys)."""
    flags = []
    for key, value in cam.params.items():
        flag = "--camera" if key == "type" else "--" + key.replace("_", "-")
        if isinstance(value, (list, tuple)):
            value = ",".join(repr(float(v)) if isinstance(v, float) else str(v) for v in value)
        flags += [flag, str(value)]
    return flags


@pytest.mark.parametrize("model", sorted(CASES))
def test_colmap_files_round_trip_through_pycolmap(
    pycolmap, cli: Path, tmp_path: Path, model: str
) -> None:
    params = CASES[model]
    cam = camera_of(pycolmap, model, params)
    text = tmp_path / "text"
    done = run_cli(cli, "camera", *flags_of(cam), "--export", "colmap", "--out", str(text))
    assert done.returncode == 0, done.stderr
    rec = pycolmap.Reconstruction(str(text))
    (colmap_cam,) = rec.cameras.values()
    assert colmap_cam.model_name == model
    assert (colmap_cam.width, colmap_cam.height) == (W, H)
    assert list(colmap_cam.params) == params, "every parameter exact"

    binary = tmp_path / "binary"
    binary.mkdir()
    rec.write_binary(str(binary))
    (back,) = aperture.load_cameras(str(binary))
    for key in ("lens_model", "intrinsics", "distortion", "size"):
        assert back.params.get(key) == cam.params.get(key), key
