"""What render returns: shapes and dtypes per call form, arrays that own the framebuffer
memory and export DLPack, render_iter equal to render and flat in memory, progress calls."""

from __future__ import annotations

import gc
import os

import numpy as np
import pytest

import aperture

SCENE = aperture.Scene("procedural:sphere?radius=1.5")


def cams(n: int, size: tuple[int, int] = (24, 16)) -> list[aperture.Camera]:
    return [aperture.Camera(eye=(np.sin(k) * 4, 0.5, np.cos(k) * 4), at=(0, 0, 0), size=size) for k in range(n)]


def test_shapes_and_dtypes() -> None:
    one = SCENE.render(cams(1)[0], aovs=["depth", "normal", "primid", "color"])
    assert one["depth"].shape == (16, 24) and one["depth"].dtype == np.float32
    assert one["normal"].shape == (16, 24, 3) and one["color"].shape == (16, 24, 4)
    assert one["primid"].dtype == np.uint32
    many = SCENE.render(cams(3), aovs="depth,normal,primid")
    assert many["depth"].shape == (3, 16, 24) and many["normal"].shape == (3, 16, 24, 3)
    assert many["primid"].shape == (3, 16, 24) and many["primid"].dtype == np.uint32
    listed = SCENE.render(cams(1), aovs="depth")
    assert listed["depth"].shape == (1, 16, 24)
    mixed = SCENE.render([cams(1)[0], cams(1, (8, 5))[0]], aovs="depth")
    assert [a.shape for a in mixed["depth"]] == [(16, 24), (5, 8)]


def test_each_stacked_frame_is_its_own_render() -> None:
    cameras = cams(4)
    stacked = SCENE.render(cameras, aovs="depth,normal,primid")
    for k, camera in enumerate(cameras):
        alone = SCENE.render(camera, aovs="depth,normal,primid")
        for name in alone:
            assert np.array_equal(stacked[name][k], alone[name]), (k, name)
    # The frames differ (the cameras do), so a mixed-up order would be seen.
    assert not np.array_equal(stacked["depth"][0], stacked["depth"][1])


def test_misses_follow_the_documented_values() -> None:
    out = SCENE.render(aperture.Camera(eye=(0, 0, 5), at=(0, 0, 0), size=(32, 32)), aovs="depth,primid,normal")
    miss = ~np.isfinite(out["depth"])
    assert miss[0, 0] and not miss[16, 16]
    assert np.all(out["depth"][miss] == np.inf)
    assert np.all(out["primid"][miss] == 0xFFFFFFFF)
    assert np.all(out["normal"][miss] == 0)
    # Centre pixel: the sphere of radius 1.5 seen from z = 5 is hit at depth 3.5 (tessellated: a bit more).
    assert 3.5 <= out["depth"][16, 16] < 3.51


def test_arrays_own_their_memory_and_export_dlpack() -> None:
    out = SCENE.render(cams(1)[0], aovs="depth,normal")
    depth = out.pop("depth")
    del out
    gc.collect()
    assert depth.flags.writeable and depth.base is not None  # a view of the framebuffer, no copy
    shared = np.from_dlpack(depth)
    assert np.shares_memory(shared, depth)
    assert np.array_equal(shared, depth)
    assert hasattr(depth, "__dlpack__") and depth.__dlpack_device__()[0] == 1  # kDLCPU


def test_progress_is_called_per_frame() -> None:
    calls: list[tuple[int, int]] = []
    SCENE.render(cams(5), aovs="depth", progress=lambda done, total: calls.append((done, total)))
    assert calls == [(k, 5) for k in range(1, 6)]


def test_progress_exception_stops_the_render() -> None:
    def fail(done: int, total: int) -> None:
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        SCENE.render(cams(3), aovs="depth", progress=fail)


def test_render_iter_yields_what_render_gives() -> None:
    cameras = cams(5)
    whole = SCENE.render(cameras, aovs="depth,primid")
    seen = []
    for k, (camera, out) in enumerate(SCENE.render_iter(iter(cameras), aovs="depth,primid", batch=2)):
        assert camera is cameras[k]
        assert np.array_equal(out["depth"], whole["depth"][k])
        assert np.array_equal(out["primid"], whole["primid"][k])
        seen.append(k)
    assert seen == list(range(5))


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_render_iter_memory_stays_flat_over_1000_cameras() -> None:
    def camera_stream():
        for k in range(1000):
            yield aperture.Camera(eye=(np.sin(k) * 4, 0.3, np.cos(k) * 4), at=(0, 0, 0), size=(64, 48))

    total = 0.0
    first = None
    for k, (_, out) in enumerate(SCENE.render_iter(camera_stream(), aovs="all")):
        total += float(np.isfinite(out["depth"]).sum())
        if k == 99:
            gc.collect()
            first = rss_bytes()
    gc.collect()
    growth = rss_bytes() - first
    # All 1000 frames of every AOV kept would be 1000 * 64 * 48 * 72 bytes = 221 MB.
    assert growth < 20e6, f"RSS grew by {growth / 1e6:.1f} MB over 900 cameras"
    assert total > 1000 * 100


def test_write_and_read_round_trip(tmp_path) -> None:
    out = SCENE.render(cams(1)[0], aovs="depth,normal,primid")
    for name, ext in [("depth", "npy"), ("normal", "npy"), ("primid", "npy"), ("depth", "pfm"), ("normal", "pfm")]:
        path = tmp_path / f"{name}.{ext}"
        aperture.write(path, out[name])
        back = aperture.read(path)
        assert np.array_equal(back.view(np.uint32), out[name].view(np.uint32)), path
        if ext == "npy":  # NumPy's own loader, independent of ours
            assert np.array_equal(np.load(path).view(np.uint32), out[name].view(np.uint32))
    with pytest.raises(ValueError, match="normal"):
        aperture.write(tmp_path / "n.png", out["normal"])
    assert aperture.write(tmp_path / "d.png", out["depth"]) == 0
    with pytest.warns(UserWarning, match="did not fit"):
        assert aperture.write(tmp_path / "far.png", out["depth"] * 100.0) > 0


def test_params_give_the_same_camera_back() -> None:
    """Camera(**cam.params) is the same camera: the same pixels, for a few models."""
    for camera in [
        aperture.Camera.look_at(eye=(0.5, 1, 4), at=(0, 0, 0), fov=33, size=(20, 14)),
        aperture.Camera(type="fisheye", eye=(0, 0, 3), dir=(0, 0, -1), fisheye_fov=190, size=(16, 16)),
        aperture.Camera(type="calibrated", intrinsics=(30, 31, 10, 7), lens_model="OPENCV",
                        distortion=(0.1, 0.01, 0, 0), eye=(0, 0.2, 4), at=(0, 0, 0), size=(20, 14)),
    ]:
        again = aperture.Camera(**camera.params)
        assert again.params == camera.params
        a, b = SCENE.render(camera, aovs="depth"), SCENE.render(again, aovs="depth")
        assert np.array_equal(a["depth"], b["depth"]) and np.isfinite(a["depth"]).any()
        assert camera.describe() == again.describe() and camera.describe().startswith("camera ")
