"""Scene(vertices=, faces=) equals Scene(path) for the same mesh written as PLY: every AOV bit
for bit, for float32 and float64 positions (a PLY's float and double properties)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import uv_sphere


def bumpy_sphere(rings: int = 24, segments: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere with random radial bumps, far from the origin (so anchoring matters)."""
    return uv_sphere(rings, segments, bumps=0.05, centre=(1000.25, -3.5, 2.0))


def write_ply(path: Path, v: np.ndarray, f: np.ndarray) -> None:
    """Binary little-endian PLY: x y z as float or double (by v's dtype), uint32 index lists."""
    kind = "double" if v.dtype == np.float64 else "float"
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(v)}\nproperty {kind} x\nproperty {kind} y\nproperty {kind} z\n"
        f"element face {len(f)}\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<u4", 3)])
    faces["n"], faces["i"] = 3, f
    with open(path, "wb") as out:
        out.write(header.encode())
        out.write(np.ascontiguousarray(v, dtype=v.dtype.newbyteorder("<")).tobytes())
        out.write(faces.tobytes())


CAMERAS = [
    aperture.Camera(eye=(1000.25, 0.5, 6.0), at=(1000.25, -3.5, 2.0), fov=30, size=(64, 48)),
    aperture.Camera(type="equirect", eye=(1000.25, -3.5, 2.0), size=(32, 16)),
]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_arrays_render_like_the_ply(tmp_path: Path, dtype: type) -> None:
    v, f = bumpy_sphere()
    v = v.astype(dtype)
    ply = tmp_path / "mesh.ply"
    write_ply(ply, v, f)
    from_file = aperture.Scene(ply).render(CAMERAS[0], aovs="all")
    from_arrays = aperture.Scene(vertices=v, faces=f).render(CAMERAS[0], aovs="all")
    assert np.isfinite(from_file["depth"]).sum() > 500
    for name, ref in from_file.items():
        assert np.array_equal(from_arrays[name].view(np.uint32), ref.view(np.uint32)), name
    inside_file = aperture.Scene(ply).render(CAMERAS[1], aovs="depth,normal,primid")
    inside_arrays = aperture.Scene(vertices=v, faces=f).render(CAMERAS[1], aovs="depth,normal,primid")
    for name, ref in inside_file.items():
        assert np.array_equal(inside_arrays[name].view(np.uint32), ref.view(np.uint32)), name


def test_reversed_winding_is_caught(tmp_path: Path) -> None:
    """The comparison sees a difference in the faces: reversed winding flips the normals."""
    v, f = bumpy_sphere()
    ply = tmp_path / "mesh.ply"
    write_ply(ply, v.astype(np.float32), f)
    ref = aperture.Scene(ply).render(CAMERAS[0], aovs="normal")["normal"]
    flipped = aperture.Scene(vertices=v.astype(np.float32), faces=f[:, ::-1]).render(CAMERAS[0], aovs="normal")
    assert not np.array_equal(flipped["normal"], ref)


def test_array_layouts_are_accepted_or_refused_by_name() -> None:
    v, f = bumpy_sphere(rings=4, segments=6)
    # Fortran order, int32 faces, Python lists: converted.
    aperture.Scene(vertices=np.asfortranarray(v), faces=f.astype(np.int32))
    aperture.Scene(vertices=v.tolist(), faces=f.tolist())
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        aperture.Scene(vertices=v[:, :2], faces=f)
    with pytest.raises(ValueError, match="out of range"):
        aperture.Scene(vertices=v, faces=f + len(v))
    with pytest.raises(ValueError, match="faces must be integers"):
        aperture.Scene(vertices=v, faces=f.astype(np.float32))


def test_a_scattered_mesh_in_chunks_reports_its_own_order() -> None:
    """bvh_chunk (issue 13): a mesh larger than a chunk whose faces are in random order is put
    in spatial order and built in chunks, yet every AOV and the face visibility equal the one-BVH
    build of the same arrays (primIDs keep the order given)."""
    v, f = bumpy_sphere(rings=100, segments=200)  # 39,600 triangles
    f = f[np.random.default_rng(13).permutation(len(f))]
    whole = aperture.Scene(vertices=v, faces=f, bvh_chunk=0)
    chunked = aperture.Scene(vertices=v, faces=f, bvh_chunk=4096)
    for camera in CAMERAS:
        a, b = chunked.render(camera, aovs="all", layers=2), whole.render(camera, aovs="all", layers=2)
        assert np.isfinite(b["depth"]).sum() > 500
        assert a.keys() == b.keys()
        for name, ref in b.items():
            assert np.array_equal(a[name].view(np.uint32), ref.view(np.uint32)), name
    va, vb = chunked.face_visibility(CAMERAS[:1]), whole.face_visibility(CAMERAS[:1])
    assert (vb["face_view_count"] > 0).sum() > 500
    for name, ref in vb.items():
        assert np.array_equal(va[name], ref), name
    with pytest.raises(ValueError, match="bvh_chunk 5: must be 0"):
        aperture.Scene(vertices=v, faces=f, bvh_chunk=5)
