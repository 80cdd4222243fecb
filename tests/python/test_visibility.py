"""Scene.face_visibility / point_visibility and `aperture visibility` (issue 15): face pixels
equal the bincount of the primid renders on a real mesh with distorted calibrated cameras,
the command line's .npz equals Python's arrays, the CSR pairs are each other's transpose, the
COLMAP track summary, the GIL, and bad inputs leave no output."""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

import numpy as np
import pytest

import aperture

from conftest import cli_error, count_during, run_cli

# (model, width, height, params in COLMAP's order): a pinhole, a strong radial OPENCV lens
# and a fisheye, each used by one image.
SENSORS = [
    ("PINHOLE", 160, 120, [150.0, 150.0, 80.0, 60.0]),
    ("OPENCV", 160, 120, [140.0, 142.0, 81.0, 59.0, -0.25, 0.08, 0.001, -0.002]),
    ("OPENCV_FISHEYE", 160, 120, [70.0, 70.0, 80.0, 60.0, 0.05, -0.01, 0.002, 0.0]),
]
EYES = [(-0.02, 0.11, 0.35), (0.30, 0.15, 0.05), (-0.2, 0.3, -0.25), (0.0, 0.11, 0.30)]
TARGET = np.array([-0.017, 0.11, 0.0])


def world_to_camera(eye: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """R (rows: the OpenCV axes x right, y down, z forward, in world coordinates) and t = -R c
    of a camera at `eye` looking at the bunny with world +y up."""
    c = np.array(eye, dtype=float)
    z = (TARGET - c) / np.linalg.norm(TARGET - c)
    x = np.cross([0.0, -1.0, 0.0], z)  # x = y × z with y pointing down
    x /= np.linalg.norm(x)
    r = np.stack([x, np.cross(z, x), z])
    return r, -r @ c


def quaternion(r: np.ndarray) -> list[float]:
    """COLMAP's QW QX QY QZ of rotation matrix r (Shepperd's method: the largest of w, x, y,
    z is computed from the diagonal, the others from the off-diagonal sums)."""
    t = np.trace(r)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = [s / 4, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4]
    return [float(v) for v in q]


def write_colmap_model(folder: Path, points: np.ndarray | None = None,
                       tracks: list[list[int]] | None = None) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    cams = [f"{k + 1} {m} {w} {h} " + " ".join(repr(p) for p in params)
            for k, (m, w, h, params) in enumerate(SENSORS)]
    (folder / "cameras.txt").write_text("\n".join(cams) + "\n")
    lines = []
    for k, eye in enumerate(EYES):
        r, t = world_to_camera(eye)
        q = quaternion(r)
        sensor = k % len(SENSORS) + 1
        lines.append(f"{10 + k} " + " ".join(repr(float(v)) for v in [*q, *t]) + f" {sensor} view{k}.jpg")
        lines.append("")
    (folder / "images.txt").write_text("\n".join(lines) + "\n")
    if points is not None:
        rows = []
        for p, (xyz, track) in enumerate(zip(points, tracks or [[] for _ in points])):
            obs = " ".join(f"{image_id} {p}" for image_id in track)
            x, y, z = (float(v) for v in xyz)
            rows.append(f"{p + 1} {x!r} {y!r} {z!r} 128 128 128 0.5 {obs}".rstrip())
        (folder / "points3D.txt").write_text("\n".join(rows) + "\n")


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("visibility") / "sparse"
    write_colmap_model(folder)
    return folder


@pytest.fixture(scope="module")
def full_bunny(shared_dir: Path) -> Path:
    return shared_dir / "meshes" / "stanford" / "bun_zipper.ply"


def csr_rows(indptr: np.ndarray, indices: np.ndarray) -> list[list[int]]:
    return [indices[indptr[r]: indptr[r + 1]].tolist() for r in range(len(indptr) - 1)]


def test_face_pixels_equal_the_bincount_of_the_primid_renders(full_bunny: Path, model: Path) -> None:
    scene = aperture.Scene(full_bunny)
    cams = aperture.load_cameras(model)
    assert [c.name for c in cams] == [f"view{k}.jpg" for k in range(len(EYES))]
    vis = scene.face_visibility(cams)
    faces = scene.triangle_count
    prim = np.concatenate([scene.render(c, aovs="primid")["primid"].ravel() for c in cams])
    expected = np.bincount(prim[prim != 0xFFFFFFFF], minlength=faces)
    assert vis["face_pixels"].dtype == np.uint64 and vis["face_pixels"].shape == (faces,)
    np.testing.assert_array_equal(vis["face_pixels"], expected)
    # Each camera alone too (a bincount summed over the wrong axis or camera would differ).
    for c in cams:
        one = scene.face_visibility(c)
        p = scene.render(c, aovs="primid")["primid"].ravel()
        np.testing.assert_array_equal(one["face_pixels"], np.bincount(p[p != 0xFFFFFFFF], minlength=faces))
    # A face with pixels in a camera is (nearly always) seen by it; the other way round is not
    # required (sub-pixel faces). Most faces with pixels must be counted as seen.
    seen = vis["face_view_count"] > 0
    assert seen[expected > 0].mean() > 0.97
    assert (vis["face_view_count"][seen] >= 1).all()


def test_the_ray_methods_give_the_same_arrays(full_bunny: Path, model: Path) -> None:
    # The default traces only the rays that can change the answer (front_only: not those that
    # meet a face from behind); "all-rays" traces one per projected face. Same arrays, both
    # sides, on the distorted calibrated cameras.
    scene = aperture.Scene(full_bunny)
    cams = aperture.load_cameras(model)
    for front_only in (False, True):
        needed = scene.face_visibility(cams, front_only=front_only)
        every = scene.face_visibility(cams, front_only=front_only, method="all-rays")
        assert needed.keys() == every.keys()
        for key in needed:
            assert needed[key].dtype == every[key].dtype
            np.testing.assert_array_equal(needed[key], every[key], err_msg=key)
        assert needed["face_view_count"].sum() > 1000
    with pytest.raises(ValueError, match="'rays'.*'needed-rays' or 'all-rays'"):
        scene.face_visibility(cams, method="rays")


def test_csr_pairs_are_transposes_and_counts_agree(full_bunny: Path, model: Path) -> None:
    scene = aperture.Scene(full_bunny)
    cams = aperture.load_cameras(model)
    vis = scene.face_visibility(cams)
    per_camera = csr_rows(vis["camera_faces_indptr"], vis["camera_faces_indices"])
    per_face = csr_rows(vis["face_cameras_indptr"], vis["face_cameras_indices"])
    assert len(per_camera) == len(cams) and len(per_face) == scene.triangle_count
    pairs_a = {(c, f) for c, fs in enumerate(per_camera) for f in fs}
    pairs_b = {(c, f) for f, cs in enumerate(per_face) for c in cs}
    assert pairs_a == pairs_b and len(pairs_a) == len(vis["camera_faces_indices"])
    np.testing.assert_array_equal(vis["face_view_count"], np.diff(vis["face_cameras_indptr"]))
    for rows in (per_camera, per_face):
        assert all(r == sorted(r) for r in rows)
    # best view: one of the cameras that see the face, -1 where none does.
    best = vis["best_view"]
    assert best.dtype == np.int32
    for f, cs in enumerate(per_face):
        assert (best[f] in cs) if cs else best[f] == -1
    # front_only keeps a subset of each camera's faces.
    front = scene.face_visibility(cams, front_only=True)
    front_pairs = {(c, f) for c, fs in enumerate(csr_rows(front["camera_faces_indptr"],
                                                          front["camera_faces_indices"])) for f in fs}
    assert front_pairs < pairs_a


def test_the_command_line_writes_what_python_returns(cli: Path, full_bunny: Path, model: Path,
                                                     tmp_path: Path) -> None:
    out = tmp_path / "vis.npz"
    done = run_cli(cli, "visibility", "--mesh", str(full_bunny), "--cameras", str(model),
                   "--out", str(out), "--out", str(tmp_path / "vis.ply"), "--quiet")
    assert done.returncode == 0, done.stderr
    # The zip (core/npz.cpp): every member stored, as np.savez writes them, and its
    # CRC-32 right by Python's zipfile.
    with zipfile.ZipFile(out) as z:
        assert z.testzip() is None
        assert {(i.filename, i.compress_type) for i in z.infolist()} == {
            (f"{name}.npy", zipfile.ZIP_STORED) for name in np.load(out).files}
    archive = np.load(out)
    vis = aperture.Scene(full_bunny).face_visibility(aperture.load_cameras(model))
    assert set(archive.files) == set(vis) | {"camera_names"}
    assert archive["camera_names"].tolist() == [f"view{k}.jpg" for k in range(len(EYES))]
    for name, array in vis.items():
        assert archive[name].dtype == array.dtype, name
        np.testing.assert_array_equal(archive[name], array, err_msg=name)
    # --image selects and orders the cameras as batch does.
    out2 = tmp_path / "two.npz"
    done = run_cli(cli, "visibility", "--mesh", str(full_bunny), "--cameras", str(model),
                   "--image", "view2.jpg", "--image", "view0.jpg", "--out", str(out2), "--quiet")
    assert done.returncode == 0, done.stderr
    two = np.load(out2)
    assert two["camera_names"].tolist() == ["view2.jpg", "view0.jpg"]
    rows = csr_rows(vis["camera_faces_indptr"], vis["camera_faces_indices"])
    assert csr_rows(two["camera_faces_indptr"], two["camera_faces_indices"]) == [rows[2], rows[0]]


def test_points_on_the_command_line_and_in_python(cli: Path, full_bunny: Path, tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    # Points around the bunny's centre: some inside the scan's volume, some in front of it.
    points = TARGET + rng.uniform(-0.06, 0.06, size=(400, 3))
    tracks = [[10 + k for k in range(len(EYES)) if (p + k) % 2 == 0] for p in range(len(points))]
    folder = tmp_path / "sparse"
    write_colmap_model(folder, points, tracks)
    np.save(tmp_path / "points.npy", points)
    cams = aperture.load_cameras(folder)
    scene = aperture.Scene(full_bunny)
    vis = scene.point_visibility(points, cams)
    assert vis["point_cameras_indptr"].shape == (len(points) + 1,)
    per_point = csr_rows(vis["point_cameras_indptr"], vis["point_cameras_indices"])
    n_seen = sum(len(r) for r in per_point)
    assert 0 < n_seen < len(points) * len(cams)  # some hidden behind the scan, some not
    # A larger tolerance can only let more points through.
    loose = scene.point_visibility(points, cams, tol=0.5)
    assert len(loose["point_cameras_indices"]) >= n_seen
    for source in (tmp_path / "points.npy", folder / "points3D.txt"):
        out = tmp_path / f"p-{source.suffix[1:]}.npz"
        done = run_cli(cli, "visibility", "--mesh", str(full_bunny), "--cameras", str(folder),
                       "--points", str(source), "--out", str(out), "--quiet")
        assert done.returncode == 0, done.stderr
        archive = np.load(out)
        for name in ("point_cameras_indptr", "point_cameras_indices"):
            np.testing.assert_array_equal(archive[name], vis[name], err_msg=f"{source}: {name}")
    # The COLMAP track summary. Every point lies within 0.11 of the bunny's centre, well inside
    # every camera's field (the narrowest, the pinhole, covers ±0.18 at 0.35), so no observation
    # is outside and one that is not seen is occluded.
    observations = [(p, k) for p, track in enumerate(tracks) for k in (i - 10 for i in track)]
    seen = sum(1 for p, k in observations if k in per_point[p])
    m = re.search(r"track observations: (\d+) in the selected images: (\d+) occluded by the mesh, "
                  r"(\d+) seen, (\d+) outside", done.stdout)
    assert m, done.stdout
    total, occluded, seen_cli, outside = map(int, m.groups())
    assert total == len(observations) and seen_cli == seen
    assert outside == 0 and occluded == total - seen


def test_face_and_point_visibility_release_the_gil(full_bunny: Path, model: Path) -> None:
    scene = aperture.Scene(full_bunny)
    cams = aperture.load_cameras(model) * 40
    points = TARGET + np.random.default_rng(3).uniform(-0.06, 0.06, size=(200000, 3))
    for name, call in [("face_visibility", lambda: scene.face_visibility(cams)),
                       ("point_visibility", lambda: scene.point_visibility(points, cams))]:
        seconds, during = count_during(call)
        assert seconds > 0.05, f"{name} too short ({seconds:.3f} s) to show anything"
        assert during > 10000, f"{name}: the counter advanced only {during} times in {seconds:.2f} s"


def test_bad_inputs_give_clear_errors_and_no_output(cli: Path, bunny: Path, model: Path,
                                                    tmp_path: Path) -> None:
    out = tmp_path / "bad.npz"
    base = ["visibility", "--mesh", str(bunny), "--out", str(out)]
    msg = cli_error(cli, *base, "--cameras", str(tmp_path / "missing"))
    assert "missing" in msg
    msg = cli_error(cli, *base, "--cameras", str(model), "--image", "view9.jpg")
    assert "view9.jpg" in msg and "did you mean" in msg
    bad_points = tmp_path / "bad.npy"
    np.save(bad_points, np.zeros((5, 2)))
    msg = cli_error(cli, *base, "--cameras", str(model), "--points", str(bad_points))
    assert "bad.npy" in msg
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "cameras.txt").write_text((model / "cameras.txt").read_text())
    (empty / "images.txt").write_text("# no images\n")
    msg = cli_error(cli, *base, "--cameras", str(empty))
    assert "no images" in msg
    msg = cli_error(cli, *base, "--cameras", str(model), "--occlusion-tolerance", "1")
    assert "--occlusion-tolerance" in msg
    msg = cli_error(cli, "visibility", "--mesh", str(bunny), "--cameras", str(model),
                    "--out", str(tmp_path / "only.ply"), "--points", str(bad_points))
    assert "--points" in msg and ".npz" in msg
    msg = cli_error(cli, "visibility", "--mesh", str(bunny), "--cameras", str(model),
                    "--out", str(tmp_path / "x.txt"))
    assert ".npz" in msg
    assert not out.exists() and not (tmp_path / "only.ply").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], list(tmp_path.iterdir())
    with pytest.raises(ValueError, match="shape"):
        aperture.Scene(bunny).point_visibility(np.zeros((3, 2)), aperture.load_cameras(model))
