"""Scene.scan traces the Scene's own BVH, so it honours every option the Scene was built with:
a GLB of two scenes (rooms of different sizes) scanned through ``Scene(glb, gltf_scene=1)``
equals ``aperture scan --gltf-scene 1`` and differs from scene 0's; a Scene of arrays equals
the command's scan of the same triangles as a PLY; all returns equal the command's; face
properties a Scene lacks are loaded (files) or refused naming the property (arrays)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import run_cli
from test_gltf_trimesh import Glb, f32
from test_scan_formats import read_ply, room_ply

# A unit cube's corners and its 12 triangles (wound outwards; a scan does not mind).
CUBE = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
CUBE_FACES = [
    (0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
    (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3),
]
# Scene k of the GLB: the cube scaled to a room of these half sizes around the origin.
ROOMS = [(2.0, 1.5, 1.0), (3.0, 2.5, 1.25)]


def rooms_glb(path: Path) -> Path:
    g = Glb()
    positions = g.accessor(f32([c for corner in CUBE for c in corner]), "VEC3")
    indices = g.accessor(np.array(CUBE_FACES, dtype="<u4").ravel(), "SCALAR", indices=True)
    doc = {
        "scene": 0,
        "scenes": [{"nodes": [0]}, {"nodes": [1]}],
        "nodes": [{"name": f"room{k}", "scale": list(size), "mesh": 0} for k, size in enumerate(ROOMS)],
        "meshes": [{"name": "cube", "primitives": [{"attributes": {"POSITION": positions}, "indices": indices}]}],
    }
    return g.write(path, doc)


def assert_same_fields(got: dict[str, np.ndarray], want: dict[str, np.ndarray]) -> None:
    assert list(got.keys()) == list(want.keys())
    for name in want:
        assert got[name].dtype == want[name].dtype, name
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)


def test_gltf_scene_scan_equals_the_command(cli: Path, tmp_path: Path) -> None:
    glb = rooms_glb(tmp_path / "rooms.glb")
    medians = []
    for k in (0, 1):
        want = read_ply(scan_to(cli, glb, tmp_path / f"s{k}.ply", "--gltf-scene", str(k)))
        got = aperture.Scene(glb, gltf_scene=k).scan("VLP-16", fields=list(want.keys()))
        assert_same_fields(got, want)
        size = np.array(ROOMS[k])
        # Every point lies on the room's walls (sensor frame = world: a static sensor at the origin).
        xyz = np.stack([got["x"], got["y"], got["z"]], axis=1).astype(np.float64)
        gap = np.min(np.abs(np.abs(xyz) - size), axis=1)
        assert gap.max() < 1e-4
        medians.append(np.median(got["range"]))
    assert medians[1] > 1.1 * medians[0]  # scene 1's room is the larger


def scan_to(cli: Path, mesh: Path, out: Path, *extra: str) -> Path:
    done = run_cli(cli, "scan", "--mesh", str(mesh), "--lidar", "VLP-16", "--quiet", "--out", str(out), *extra)
    assert done.returncode == 0, done.stderr
    return out


def test_array_scene_scan_equals_the_command(cli: Path, tmp_path: Path) -> None:
    room = room_ply(tmp_path / "room.ply")
    want = read_ply(scan_to(cli, room, tmp_path / "scan.ply"))
    ply = aperture.Scene(room)
    triangles = ply.triangles().reshape(-1, 3)
    vertices = np.ascontiguousarray(triangles, dtype=np.float64)
    faces = np.arange(len(vertices), dtype=np.uint32).reshape(-1, 3)
    got = aperture.Scene(vertices=vertices, faces=faces).scan("VLP-16", fields=list(want.keys()))
    assert_same_fields(got, want)
    with pytest.raises(ValueError, match="'semantic'"):
        aperture.Scene(vertices=vertices, faces=faces).scan("VLP-16", fields=["x", "semantic"])


def test_all_returns_and_properties_equal_the_command(cli: Path, tmp_path: Path) -> None:
    room = room_ply(tmp_path / "room.ply")
    want = read_ply(scan_to(cli, room, tmp_path / "all.ply", "--returns", "all", "--property", "semantic"))
    assert "return_number" in want and "semantic" in want
    # A Scene built without the property: the scan loads it (the files again, once).
    got = aperture.Scene(room).scan("VLP-16", returns="all", fields=list(want.keys()))
    assert_same_fields(got, want)
    # Built with it up front, the same.
    got = aperture.Scene(room, aovs=["face.semantic"]).scan("VLP-16", returns="all", fields=list(want.keys()))
    assert_same_fields(got, want)
    with pytest.raises(ValueError, match="nosuch"):
        aperture.Scene(room).scan("VLP-16", fields=["x", "nosuch"])


@pytest.mark.parametrize("returns", ["first", "all"])
def test_field_subsets_equal_the_full_scans_columns(tmp_path: Path, returns: str) -> None:
    # fields= computes only the fields asked for: each subset's columns are bit for bit those
    # of the scan that computes every field.
    scene = aperture.Scene(room_ply(tmp_path / "room.ply"), aovs=["face.semantic"])
    full = scene.scan("VLP-16", returns=returns, sweeps=2, fields=None)
    every = scene.scan("VLP-16", returns=returns, sweeps=2, fields=[*full.keys(), "semantic"])
    subsets = [["x", "intensity"], ["range", "semantic", "ring"], ["azimuth", "time", "sweep"], ["z", "instance"]]
    if returns == "all":
        subsets.append(["returns", "primid", "return_number"])
    for names in subsets:
        got = scene.scan("VLP-16", returns=returns, sweeps=2, fields=names)
        assert list(got.keys()) == names
        for name in names:
            want = every[name] if name == "semantic" else full[name]
            assert got[name].dtype == want.dtype, name
            assert got[name].tobytes() == want.tobytes(), name
