"""The arrays follow the AOV table (core/aov_table.h): every row comes back with its dtype,
channel count and miss value, and a test-only row registered through the table appears in the
arrays with no code of its own in the module."""

from __future__ import annotations

import numpy as np
import pytest

import aperture
from aperture import _aperture

SCENE = aperture.Scene("procedural:sphere?radius=1.5")
# The sphere of radius 1.5 seen from z = 5: the corner pixels miss, the centre hits.
CAMERA = aperture.Camera(eye=(0, 0, 5), at=(0, 0, 0), size=(12, 10))


def expected_shape(row: dict, frames: int | None) -> tuple[int, ...]:
    shape = (10, 12) if row["channels"] == 1 else (10, 12, row["channels"])
    return shape if frames is None else (frames, *shape)


# Rows that read what a procedural mesh does not have (texture coordinates, colours,
# materials): refused on SCENE, before rendering (docs/aovs.md, "Surface AOVs").
NEED_SCENE_DATA = {"uv": "texture coordinates", "vertex-color": "vertex colours", "albedo": "no materials"}


def test_every_row_has_its_dtype_shape_and_miss() -> None:
    rows = [r for r in _aperture._aov_table() if r["name"] not in NEED_SCENE_DATA]
    assert [r["name"] for r in rows][:3] == ["color", "depth", "distance"]
    names = [r["name"] for r in rows]
    for frames, cameras in ((None, CAMERA), (2, [CAMERA, CAMERA])):
        out = SCENE.render(cameras, aovs=names)
        assert list(out) == names
        for row in rows:
            a = out[row["name"]]
            assert a.dtype == np.dtype(row["dtype"]), row["name"]
            assert a.shape == expected_shape(row, frames), row["name"]
            corner = a[..., 0, 0] if row["channels"] == 1 else a[..., 0, 0, :]
            assert np.all(corner == np.array(row["miss"], dtype=a.dtype)), row["name"]


def test_surface_rows_on_a_plain_mesh() -> None:
    out = SCENE.render(CAMERA, aovs="instance,mesh,material,barycentric")
    # One object with default ids: 0 where the sphere is hit.
    for name in ("instance", "mesh", "material"):
        assert out[name].dtype == np.uint32 and out[name][5, 6] == 0, name
    bary = out["barycentric"][5, 6]
    assert bary.shape == (2,) and bary.min() >= 0 and bary.sum() <= 1
    for name, message in NEED_SCENE_DATA.items():
        with pytest.raises(ValueError, match=message):
            SCENE.render(CAMERA, aovs=name)


def test_a_registered_row_appears_in_the_arrays(tmp_path) -> None:
    with _aperture._AovRegistration("test-uv", ["tuv.U", "tuv.V"], "float32", -1.0):
        row = next(r for r in _aperture._aov_table() if r["name"] == "test-uv")
        assert row["channels"] == 2 and row["dtype"] == "float32"
        out = SCENE.render([CAMERA, CAMERA, CAMERA], aovs="depth,test-uv")
        assert list(out) == ["depth", "test-uv"]
        uv = out["test-uv"]
        assert uv.dtype == np.float32 and uv.shape == (3, 10, 12, 2)
        # Nothing in the frame loop computes it: it holds its miss value everywhere.
        assert np.all(uv == -1.0)
        assert np.isfinite(out["depth"][:, 5, 6]).all()
        aperture.write(tmp_path / "uv.npy", uv[1], aov="test-uv")
        assert np.array_equal(aperture.read(tmp_path / "uv.npy"), uv[1])
    with pytest.raises(ValueError, match="unknown AOV 'test-uv'"):
        SCENE.render(CAMERA, aovs="depth,test-uv")
    assert "test-uv" not in [r["name"] for r in _aperture._aov_table()]
