"""LiDAR scans (docs/lidar.md) read back by the formats' own clients: laspy reads the LAS,
pypcd4 the PCD, NumPy the KITTI .bin and .label, all equal to the binary PLY of the same sweep;
ouster-sdk turns aperture's RANGE image into aperture's points (XYZLut, to its 1 mm quantum)
and destaggers it into aperture's destaggered image exactly; Scene.scan returns the PLY's
fields; bad specs and trajectories exit 1 before the scene loads. The clients skip the tests
they need when missing (scripts/venv.sh installs them)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import cli_error, run_cli

# The box room [-2, 3] x [-1.5, 2] x [-1, 1.25] around the sensor, walls labelled 1..6 (the
# face property "semantic") and a 7th square inside, at x = 1 (for returns).
LO, HI = (-2.0, -1.5, -1.0), (3.0, 2.0, 1.25)


def room_ply(path: Path) -> Path:
    (x0, y0, z0), (x1, y1, z1) = LO, HI
    quads = [
        ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], 1),
        ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], 2),
        ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], 3),
        ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], 4),
        ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], 5),
        ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], 6),
    ]
    vertices, faces = [], []
    for corners, label in quads:
        base = len(vertices)
        vertices += corners
        faces += [(base, base + 1, base + 2, label), (base, base + 2, base + 3, label)]
    lines = [
        "ply",
        "format ascii 1.0",
        f"element vertex {len(vertices)}",
        "property double x",
        "property double y",
        "property double z",
        f"element face {len(faces)}",
        "property list uchar int vertex_indices",
        "property uint semantic",
        "end_header",
    ]
    lines += [f"{x} {y} {z}" for x, y, z in vertices]
    lines += [f"3 {a} {b} {c} {label}" for a, b, c, label in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def read_ply(path: Path) -> dict[str, np.ndarray]:
    """A binary little-endian PLY's vertex element, parsed here from its header."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    types = {"uchar": "u1", "ushort": "u2", "uint": "<u4", "float": "<f4", "double": "<f8"}
    fields, count = [], 0
    for line in data[:end].decode().splitlines():
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            count = int(words[2])
        elif words and words[0] == "property":
            fields.append((words[2], types[words[1]]))
    assert "format binary_little_endian 1.0" in data[:end].decode()
    records = np.frombuffer(data, dtype=np.dtype(fields), count=count, offset=end)
    return {name: records[name] for name, _ in fields}


@pytest.fixture(scope="module")
def room(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return room_ply(tmp_path_factory.mktemp("room") / "room.ply")


def scan(cli: Path, room: Path, out: Path, *extra: str) -> None:
    done = run_cli(
        cli, "scan", "--mesh", str(room), "--lidar", "OS1-64", "--property", "semantic",
        "--label", "semantic", "--quiet", "--out", str(out), *extra,
    )
    assert done.returncode == 0, done.stderr


def test_las_pcd_and_kitti_equal_the_ply(cli: Path, room: Path, tmp_path: Path) -> None:
    laspy = pytest.importorskip("laspy")
    pypcd4 = pytest.importorskip("pypcd4")
    for ext in ("ply", "pcd", "las", "bin"):
        scan(cli, room, tmp_path / f"scan.{ext}")
    ply = read_ply(tmp_path / "scan.ply")
    n = len(ply["x"])
    assert n == 64 * 1024  # a closed room: every ray of the sweep hits
    assert set(np.unique(ply["semantic"])) <= {1, 2, 3, 4, 5, 6}

    las = laspy.read(tmp_path / "scan.las")
    assert las.header.version.major == 1 and las.header.version.minor == 4
    assert las.header.point_format.id == 6 and las.header.point_count == n
    for axis in "xyz":
        np.testing.assert_allclose(np.asarray(las[axis]), ply[axis].astype(np.float64), atol=0.5e-3 + 1e-6)
    np.testing.assert_array_equal(np.asarray(las.classification), ply["semantic"])
    np.testing.assert_array_equal(np.asarray(las.return_number), 1)
    np.testing.assert_allclose(np.asarray(las.gps_time), ply["time"].astype(np.float64) * 1e-9, atol=1e-12)
    expected_intensity = np.round(np.clip(ply["intensity"].astype(np.float64), 0, 1) * 65535)
    np.testing.assert_array_equal(np.asarray(las.intensity), expected_intensity)

    pcd = pypcd4.PointCloud.from_path(tmp_path / "scan.pcd")
    assert list(pcd.fields) == list(ply.keys())
    for name in ply:
        np.testing.assert_array_equal(pcd.numpy((name,))[:, 0].astype(ply[name].dtype), ply[name])

    kitti = np.fromfile(tmp_path / "scan.bin", dtype="<f4").reshape(-1, 4)
    np.testing.assert_array_equal(kitti[:, 0], ply["x"])
    np.testing.assert_array_equal(kitti[:, 1], ply["y"])
    np.testing.assert_array_equal(kitti[:, 2], ply["z"])
    np.testing.assert_array_equal(kitti[:, 3], ply["intensity"])
    labels = np.fromfile(tmp_path / "scan.label", dtype="<u4")
    np.testing.assert_array_equal(labels & 0xFFFF, ply["semantic"])
    np.testing.assert_array_equal(labels >> 16, ply["instance"])


def test_ranges_are_the_distance_to_the_room(cli: Path, room: Path, tmp_path: Path) -> None:
    scan(cli, room, tmp_path / "scan.ply", "--frame", "world")
    ply = read_ply(tmp_path / "scan.ply")
    p = np.stack([ply["x"], ply["y"], ply["z"]], axis=1)
    gap = np.min(np.abs(np.concatenate([p - np.array(LO), p - np.array(HI)], axis=1)), axis=1)
    assert np.max(gap) < 1e-4


def test_ouster_sdk_reads_aperture_range_images(cli: Path, room: Path, tmp_path: Path) -> None:
    pytest.importorskip("ouster.sdk")
    from ouster.sdk import core

    info = core.SensorInfo.from_default(core.LidarMode._1024x10)
    metadata = tmp_path / "os1.json"
    metadata.write_text(info.to_json_string())
    for out in ("scan.npz", "scan.ply"):
        done = run_cli(cli, "scan", "--mesh", str(room), "--lidar", str(metadata), "--quiet",
                       "--out", str(tmp_path / out))
        assert done.returncode == 0, done.stderr
    image = np.load(tmp_path / "scan.npz")
    RANGE = image["RANGE"]
    assert RANGE.dtype == np.uint32 and RANGE.shape == (info.format.pixels_per_column, info.format.columns_per_frame)
    assert np.all(RANGE > 0)
    xyz = core.XYZLut(info)(RANGE)  # metres, the sensor frame
    ply = read_ply(tmp_path / "scan.ply")
    ours = np.zeros_like(xyz)
    ours[ply["ring"], ply["column"]] = np.stack([ply["x"], ply["y"], ply["z"]], axis=1)
    err = np.linalg.norm(xyz - ours, axis=2)
    assert err.max() <= 1e-3, err.max()
    np.testing.assert_array_equal(core.destagger(info, RANGE), image["destaggered.RANGE"])
    np.testing.assert_array_equal(image["pixel_shift_by_row"], np.asarray(info.format.pixel_shift_by_row))


def test_scene_scan_returns_the_ply_fields(cli: Path, room: Path, tmp_path: Path) -> None:
    scan(cli, room, tmp_path / "scan.ply")
    ply = read_ply(tmp_path / "scan.ply")
    got = aperture.Scene(room).scan("OS1-64", fields=list(ply.keys()))
    assert list(got.keys()) == list(ply.keys())
    for name in ply:
        assert got[name].dtype == ply[name].dtype, name
        np.testing.assert_array_equal(got[name], ply[name])
    two = aperture.Scene(room).scan("OS1-64", sweeps=2, fields=["x", "sweep"])
    assert len(two["x"]) == 2 * len(ply["x"])
    np.testing.assert_array_equal(np.bincount(two["sweep"]), [len(ply["x"])] * 2)


def test_bad_input_writes_nothing(cli: Path, room: Path, tmp_path: Path) -> None:
    out = tmp_path / "s.ply"
    assert "did you mean 'OS1-64'" in cli_error(cli, "scan", "--mesh", str(room), "--lidar", "OS1-46", "--out", str(out))
    assert ".xyz" in cli_error(cli, "scan", "--mesh", str(room), "--lidar", "OS1-64", "--out", str(tmp_path / "s.xyz"))
    assert "{sweep}" in cli_error(cli, "scan", "--mesh", str(room), "--lidar", "OS1-64", "--sweeps", "2", "--out", str(out))
    assert "range image" in cli_error(cli, "scan", "--mesh", str(room), "--lidar", "OS1-64", "--returns", "all", "--out", str(tmp_path / "s.npz"))
    poses = tmp_path / "poses.txt"
    poses.write_text("0 0 0 0 0 0 0 1\n0.05 1 0 0 0 0 0 1\n")
    assert "outside the trajectory" in cli_error(cli, "scan", "--mesh", str(room), "--lidar", "OS1-64", "--trajectory", str(poses), "--out", str(out))
    assert list(tmp_path.glob("s.*")) == []


def test_bad_specs_and_trajectories_exit_1_before_loading_the_scene(cli: Path, tmp_path: Path) -> None:
    """Issue 42's bad input: a malformed spec, a beam table of the wrong length, non-increasing
    trajectory times are refused with the file and the field (or line) named, exit status 1,
    no output, before any work: the mesh given does not exist, and the error is not about it."""
    out = tmp_path / "s.ply"
    wrong = tmp_path / "wrong.json"
    wrong.write_text('{"sweep_rate_hz": 10, "columns": 4, "beams": {"elevation_deg": [-1, 0, 1], "azimuth_deg": [0, 0]}}')
    truncated = tmp_path / "truncated.json"
    truncated.write_text('{"sweep_rate_hz": 10, "columns": ')
    back = tmp_path / "back.txt"
    back.write_text("1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n")
    cases = [
        (["--lidar", str(wrong)], [str(wrong), "beams.azimuth_deg", "2 entries"]),
        (["--lidar", str(truncated)], [str(truncated), "not valid JSON"]),
        (["--lidar", "VLP-16", "--trajectory", str(back)], [f"{back} line 2", "must increase"]),
        (["--lidar", "VLP16"], ["did you mean 'VLP-16'"]),
    ]
    for args, words in cases:
        done = run_cli(cli, "scan", "--mesh", str(tmp_path / "no_such_mesh.ply"), *args, "--out", str(out))
        assert done.returncode == 1, (args, done.returncode, done.stderr)
        for word in words:
            assert word in done.stderr, (word, done.stderr)
        assert "no_such_mesh" not in done.stderr
        assert list(tmp_path.glob("s.*")) == []
