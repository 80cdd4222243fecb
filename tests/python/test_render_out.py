"""render(out=...) writes into the caller's arrays and returns those very objects; fresh arrays
and given arrays are written whole (misses included) by the render; wrong arrays are a ValueError
naming the AOV; render_iter reuses its buffers between batches unless reuse=False."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import assert_same_bits, bits

AOVS = "depth,normal,primid"
EVERY = "color,depth,distance,normal,position,primid,geomid,shading-normal"
SPHERE = aperture.Scene("procedural:sphere?radius=1.5")


def views(n: int, size: tuple[int, int] = (40, 24), radius: float = 4.0) -> list[aperture.Camera]:
    """n cameras around the origin, each seeing the object and background (misses)."""
    return [
        aperture.Camera(eye=(np.sin(k) * radius, 0.4, np.cos(k) * radius), at=(0, 0, 0), size=size) for k in range(n)
    ]


def filled_like(result: dict[str, np.ndarray], pattern: int) -> dict[str, np.ndarray]:
    """Arrays shaped and typed like `result`, every value set to the bits `pattern` (a NaN for
    floats): a value the render leaves unwritten keeps it."""
    out = {}
    for name, a in result.items():
        b = np.empty_like(a)
        bits(b)[...] = pattern
        out[name] = b
    return out


@pytest.fixture(scope="module")
def bunny_scene(bunny: Path) -> aperture.Scene:
    return aperture.Scene(str(bunny))


def test_eight_views_into_out_equal_fresh_arrays_and_are_the_same_objects(bunny_scene) -> None:
    lo, hi = np.array(bunny_scene.bounds[0]), np.array(bunny_scene.bounds[1])
    centre, radius = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    cameras = [
        aperture.Camera(
            eye=tuple(centre + radius * np.array([np.sin(k), 0.3, np.cos(k)])), at=tuple(centre), fov=40, size=(96, 64)
        )
        for k in range(8)
    ]
    fresh = bunny_scene.render(cameras, aovs=AOVS)
    assert fresh["depth"].shape == (8, 64, 96)
    miss = np.isinf(fresh["depth"])
    assert 0 < miss.sum() < miss.size, "the views must show both the bunny and misses"
    for pattern in (0x7FC00001, 0x12345678):  # a NaN, then an ordinary bit pattern
        out = filled_like(fresh, pattern)
        result = bunny_scene.render(cameras, aovs=AOVS, out=out)
        for name in out:
            assert result[name] is out[name], name
        assert_same_bits(result, fresh, same_order=True)
    assert np.all(fresh["primid"][miss] == 0xFFFFFFFF) and np.all(fresh["normal"][miss] == 0)


def test_every_value_is_written_whatever_the_arrays_held_before() -> None:
    """Two renders into arrays holding different garbage agree bit for bit with each other and
    with fresh arrays, for every AOV of the frame loop, several packet widths and spp 2: no
    value escapes unwritten. Fresh arrays are checked over several calls too (reused memory)."""
    cameras = views(3, size=(37, 21))  # sizes that cut blocks and tiles at the edges
    for packet in (1, 8, 16):
        for spp in (None, 2):
            fresh = SPHERE.render(cameras, aovs=EVERY, packet=packet, spp=spp, tile=8)
            again = SPHERE.render(cameras, aovs=EVERY, packet=packet, spp=spp, tile=8)
            assert_same_bits(again, fresh, same_order=True)
            for pattern in (0xFFFFFFFF, 0x7F800001, 0):
                out = filled_like(fresh, pattern)
                result = SPHERE.render(cameras, aovs=EVERY, packet=packet, spp=spp, tile=8, out=out)
                assert_same_bits(result, fresh, same_order=True)
    assert np.isinf(fresh["depth"]).any() and np.isfinite(fresh["depth"]).any()


def test_one_camera_and_a_subset_of_the_aovs() -> None:
    camera = views(1)[0]
    fresh = SPHERE.render(camera, aovs=AOVS)
    depth = np.full((24, 40), np.nan, dtype=np.float32)
    result = SPHERE.render(camera, aovs=AOVS, out={"depth": depth})
    assert result["depth"] is depth
    assert list(result) == list(fresh)
    assert_same_bits(result, fresh, same_order=True)


def test_layered_hits_render_beside_given_arrays() -> None:
    cameras = views(2)
    fresh = SPHERE.render(cameras, aovs="depth,primid", layers=2)
    out = filled_like({"depth": fresh["depth"]}, 0x7FC00000)
    result = SPHERE.render(cameras, aovs="depth,primid", layers=2, out=out)
    assert result["depth"] is out["depth"]
    assert_same_bits(result, fresh, same_order=True)


@pytest.mark.parametrize(
    ("name", "array", "message"),
    [
        ("depth", np.zeros((2, 24, 41), np.float32), r"out\['depth'\] has shape \(2, 24, 41\)"),
        ("depth", np.zeros((24, 40), np.float32), r"out\['depth'\] has shape \(24, 40\)"),
        ("depth", np.zeros((2, 24, 40), np.float64), r"out\['depth'\] .*dtype float64"),
        ("normal", np.zeros((2, 24, 40, 3), np.float16), r"out\['normal'\] .*dtype float16"),
        ("normal", np.zeros((2, 24, 40), np.float32), r"out\['normal'\] has shape \(2, 24, 40\)"),
        ("primid", np.zeros((2, 24, 40), np.int32), r"out\['primid'\] .*dtype int32"),
        ("primid", np.zeros((2, 24, 40), np.float32), r"out\['primid'\] .*uint32"),
        ("depth", np.zeros((2, 40, 24), np.float32).transpose(0, 2, 1), r"out\['depth'\].*C-contiguous"),
        ("depth", np.zeros((2, 24, 80), np.float32)[:, :, ::2], r"out\['depth'\]"),
        ("depth", [[0.0]], r"out\['depth'\] is a .*list.*not a NumPy array"),
        ("dept", np.zeros((2, 24, 40), np.float32), r"out\['dept'\] is not an AOV of this render.*depth"),
    ],
)
def test_a_wrong_array_is_a_value_error_naming_the_aov(name: str, array, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SPHERE.render(views(2), aovs=AOVS, out={name: array})


def test_read_only_overlapping_layered_and_mixed_sizes_are_refused() -> None:
    depth = np.zeros((2, 24, 40), np.float32)
    depth.flags.writeable = False
    with pytest.raises(ValueError, match=r"out\['depth'\] is read-only"):
        SPHERE.render(views(2), aovs=AOVS, out={"depth": depth})
    shared = np.zeros((2, 24, 40), np.uint32)
    with pytest.raises(ValueError, match=r"out\['depth'\] and out\['primid'\] share memory"):
        SPHERE.render(views(2), aovs="depth,primid", out={"depth": shared.view(np.float32), "primid": shared})
    layered = np.zeros((2, 2, 24, 40), np.float32)
    with pytest.raises(ValueError, match=r"out\['layers.depth'\]: layered hits"):
        SPHERE.render(views(2), aovs="depth", layers=2, out={"layers.depth": layered})
    with pytest.raises(ValueError, match=r"out= needs one camera or cameras of one size"):
        SPHERE.render([views(1)[0], views(1, (8, 8))[0]], aovs="depth", out={})


def data_pointer(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


def test_render_iter_reuses_its_buffers_and_gives_what_fresh_renders_give() -> None:
    cameras = views(7)
    batches = [cameras[0:3], cameras[3:6], cameras[6:7]]
    pointers: list[list[int]] = []
    kept = []
    for k, (camera, out) in enumerate(SPHERE.render_iter(cameras, aovs=AOVS, batch=3)):
        assert camera is cameras[k]
        batch, slot = divmod(k, 3)
        alone = SPHERE.render(batches[batch], aovs=AOVS)
        for name in out:
            assert np.array_equal(bits(out[name]), bits(alone[name][slot])), (k, name)
        if slot == 0:
            pointers.append([])
        pointers[-1].append(data_pointer(out["depth"]))
        kept.append(out["depth"])
    # Every batch writes the first batch's memory: frame k of each batch at the same address.
    assert pointers[1] == pointers[0] and pointers[2] == pointers[0][:1]
    # ... so a frame kept from the first batch now holds the last batch's frame.
    assert np.array_equal(bits(kept[0]), bits(SPHERE.render(cameras[6], aovs=AOVS)["depth"]))


def test_render_iter_without_reuse_keeps_every_batch() -> None:
    cameras = views(6)
    kept = [(out["depth"], data_pointer(out["depth"])) for _, out in SPHERE.render_iter(cameras, aovs=AOVS, batch=3, reuse=False)]
    assert len({p for _, p in kept}) == 6
    whole = SPHERE.render(cameras, aovs=AOVS)
    for k, (depth, _) in enumerate(kept):
        assert np.array_equal(bits(depth), bits(whole["depth"][k])), k


def test_render_iter_reuse_with_layers_and_mixed_sizes() -> None:
    cameras = views(3) + views(2, size=(16, 12))
    for k, (camera, out) in enumerate(SPHERE.render_iter(cameras, aovs="depth", layers=2, batch=2)):
        alone = SPHERE.render(camera, aovs="depth", layers=2)
        assert out["depth"].shape == (camera.height, camera.width)
        assert np.array_equal(bits(out["depth"]), bits(alone["depth"])), k
        assert np.array_equal(bits(out["layers.depth"]), bits(alone["layers.depth"])), k
