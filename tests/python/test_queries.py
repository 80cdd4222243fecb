"""Scene.closest_points / distance / count_intersections / list_intersections /
signed_distance_grid and `aperture query` (issue 44; docs/queries.md): distances against a
NumPy brute force over every triangle and against Open3D's RaycastingScene, intersection counts
against a sphere's closed form, shapes, dtypes, ValueError naming the argument, NaN for points
that are not finite, the grid's layout, and the command line's .npz against Python."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import aperture

from conftest import cli_error, count_during, run_cli

SPHERE = "procedural:sphere?radius=1.5&segments=32&rings=16&cx=10&cy=-2"


def brute_force_distance(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest of (T, 3, 3) triangles: the plane where the
    foot of the perpendicular is inside, else the nearest edge."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    n = np.cross(b - a, c - a)
    n2 = np.einsum("ij,ij->i", n, n)
    out = np.empty(len(points))
    for k, p in enumerate(points):
        ap = p - a
        h = np.einsum("ij,ij->i", ap, n) / n2
        foot = p - h[:, None] * n
        inside = np.ones(len(a), dtype=bool)
        for u, v in ((a, b), (b, c), (c, a)):
            inside &= np.einsum("ij,ij->i", np.cross(v - u, foot - u), n) >= 0
        best = np.where(inside, np.abs(h) * np.sqrt(n2), np.inf)
        for u, v in ((a, b), (b, c), (c, a)):
            e = v - u
            t = np.clip(np.einsum("ij,ij->i", p - u, e) / np.einsum("ij,ij->i", e, e), 0, 1)
            best = np.minimum(best, np.linalg.norm(p - (u + t[:, None] * e), axis=1))
        out[k] = best.min()
    return out


def random_points(scene: aperture.Scene, n: int, seed: int) -> np.ndarray:
    lo, hi = (np.array(b) for b in scene.bounds)
    centre, half = (lo + hi) / 2, (hi - lo) * 1.5
    return centre + half * np.random.default_rng(seed).uniform(-1, 1, (n, 3))


def test_closest_points_match_brute_force_with_their_shapes_and_dtypes():
    scene = aperture.Scene(SPHERE)
    p = random_points(scene, 400, 1)
    r = scene.closest_points(p)
    assert set(r) == {"points", "distance", "primid", "barycentric", "geomid", "instance"}
    assert r["points"].shape == (400, 3) and r["points"].dtype == np.float64
    assert r["barycentric"].shape == (400, 3) and r["barycentric"].dtype == np.float64
    assert r["distance"].shape == (400,) and r["distance"].dtype == np.float64
    for key in ("primid", "geomid", "instance"):
        assert r[key].shape == (400,) and r[key].dtype == np.uint32
    tris = scene.triangles()
    np.testing.assert_allclose(r["distance"], brute_force_distance(tris, p), rtol=1e-9, atol=1e-12)
    # The point is where its triangle's barycentric weights put it, at that distance.
    at = np.einsum("ni,nij->nj", r["barycentric"], tris[r["primid"]])
    np.testing.assert_allclose(at, r["points"], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(p - r["points"], axis=1), r["distance"], rtol=1e-12)
    np.testing.assert_array_equal(scene.distance(p), r["distance"])


def test_float32_points_give_the_float64_answers():
    scene = aperture.Scene(SPHERE)
    p = random_points(scene, 100, 2).astype(np.float32)
    np.testing.assert_array_equal(scene.distance(p), scene.distance(p.astype(np.float64)))


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((4, 2)), r"distance: points must have shape \(N, 3\), not \(4, 2\)"),
        (np.zeros(3), r"distance: points must have shape \(N, 3\)"),
        (np.zeros((4, 3), dtype=np.int64), "distance: points must be float32 or float64, not int64"),
    ],
)
def test_wrong_points_are_value_errors_naming_the_argument(points, message):
    with pytest.raises(ValueError, match=message):
        aperture.Scene(SPHERE).distance(points)


def test_non_finite_points_give_nan_for_them_only():
    scene = aperture.Scene(SPHERE)
    p = random_points(scene, 5, 3)
    p[1, 0], p[3, 2] = np.nan, np.inf
    with pytest.warns(RuntimeWarning, match="2 of 5 points are not finite"):
        r = scene.closest_points(p)
    assert np.isnan(r["distance"][[1, 3]]).all() and np.isnan(r["points"][[1, 3]]).all()
    assert (r["primid"][[1, 3]] == 0xFFFFFFFF).all()
    assert np.isfinite(r["distance"][[0, 2, 4]]).all()
    assert scene.last_query == {"what": "closest_points", "points": 5, "non_finite": 2, "method": None}


def test_count_intersections_of_a_sphere():
    """Rays aimed within the inscribed sphere of the tessellation cross it twice, rays passing
    outside its circumscribed sphere never, rays from its centre once."""
    scene = aperture.Scene(SPHERE)
    centre, radius = np.array([10.0, -2.0, 0.0]), 1.5
    inscribed = radius * np.cos(np.pi / 32) * np.cos(np.pi / 32)
    rng = np.random.default_rng(4)
    d = rng.normal(size=(600, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    side = np.cross(d, rng.normal(size=(600, 3)))
    side /= np.linalg.norm(side, axis=1)[:, None]
    b = np.where(np.arange(600) % 2 == 0, 0.95 * inscribed * rng.uniform(size=600), radius * rng.uniform(1.01, 2, 600))
    origins = centre - 10 * d + b[:, None] * side
    counts = scene.count_intersections(origins.astype(np.float32), d)
    assert counts.dtype == np.uint32
    np.testing.assert_array_equal(counts, np.where(np.arange(600) % 2 == 0, 2, 0))
    np.testing.assert_array_equal(scene.count_intersections(np.tile(centre, (50, 1)), d[:50]), 1)
    hits = scene.list_intersections(origins, d)
    assert hits["ray_splits"].shape == (601,) and hits["ray_splits"].dtype == np.uint64
    np.testing.assert_array_equal(np.diff(hits["ray_splits"]), counts)
    np.testing.assert_array_equal(hits["ray_ids"], np.repeat(np.arange(600), counts))
    r = np.linalg.norm(origins[hits["ray_ids"]] + hits["t"][:, None] * d[hits["ray_ids"]] - centre, axis=1)
    assert (r > inscribed * (1 - 1e-5)).all() and (r < radius * (1 + 1e-5)).all()
    with pytest.raises(ValueError, match="count_intersections: origins has 600 rows, directions 2"):
        scene.count_intersections(origins, d[:2])
    with pytest.raises(ValueError, match=r"count_intersections: directions must have shape \(N, 3\)"):
        scene.count_intersections(origins, d[:, :2])


def test_signed_distance_grid_layout_and_file(tmp_path: Path, monkeypatch):
    """The grid's sample (i, j, k) is at (x[k], y[j], z[i]) with both bounds sampled: checked
    with the unsigned distance standing in for the signed one (the sign has its own tests)."""
    scene = aperture.Scene(SPHERE)

    def unsigned(points, method=None, threads=0):
        d = scene.distance(points)
        scene._last_query["method"] = "stand-in"
        return d

    monkeypatch.setattr(scene, "signed_distance", unsigned)
    bounds = ((8.0, -4.0, -2.0), (12.0, 0.0, 3.0))
    grid = scene.signed_distance_grid(bounds, (5, 4, 3), path=tmp_path / "sdf.npy")
    assert grid.shape == (3, 4, 5) and grid.dtype == np.float32
    assert scene.last_query["method"] == "stand-in"
    z, y, x = np.meshgrid(np.linspace(-2, 3, 3), np.linspace(-4, 0, 4), np.linspace(8, 12, 5), indexing="ij")
    want = scene.distance(np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)).reshape(3, 4, 5)
    np.testing.assert_array_equal(grid, want.astype(np.float32))
    np.testing.assert_array_equal(np.load(tmp_path / "sdf.npy"), grid)
    with pytest.raises(ValueError, match="resolution must be an int >= 2"):
        scene.signed_distance_grid(bounds, 1)
    with pytest.raises(ValueError, match="bounds must be"):
        scene.signed_distance_grid(((0, 0, 0), (0, 1, 1)), 4)
    with pytest.raises(ValueError, match="must end in .npy"):
        scene.signed_distance_grid(bounds, 4, path=tmp_path / "sdf.txt")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sdf.npy"]


@pytest.fixture(scope="module")
def o3d():
    return pytest.importorskip("open3d", reason="open3d (scripts/venv.sh installs open3d-cpu)")


def open3d_distance(o3d, scene: aperture.Scene, points: np.ndarray) -> np.ndarray:
    """Open3D's RaycastingScene.compute_distance over the scene's own world triangles."""
    tris = scene.triangles().reshape(-1, 3)
    rs = o3d.t.geometry.RaycastingScene()
    rs.add_triangles(
        o3d.core.Tensor(tris.astype(np.float32)),
        o3d.core.Tensor(np.arange(len(tris), dtype=np.uint32).reshape(-1, 3)),
    )
    return rs.compute_distance(o3d.core.Tensor(points.astype(np.float32))).numpy()


def test_distances_equal_open3d_on_a_sphere(o3d):
    scene = aperture.Scene(SPHERE)
    p = random_points(scene, 2000, 5).astype(np.float32).astype(np.float64)
    np.testing.assert_allclose(scene.distance(p), open3d_distance(o3d, scene, p), rtol=2e-5, atol=2e-5)


def test_distances_equal_open3d_on_the_bunny(o3d, shared_dir: Path):
    scene = aperture.Scene(shared_dir / "meshes" / "stanford" / "bun_zipper.ply")
    p = random_points(scene, 20000, 6).astype(np.float32).astype(np.float64)
    # Float precision: Open3D computes in float32 at coordinates of about 0.1.
    np.testing.assert_allclose(scene.distance(p), open3d_distance(o3d, scene, p), rtol=1e-5, atol=1e-7)


def test_query_command_writes_python_s_arrays(cli: Path, tmp_path: Path):
    p = random_points(aperture.Scene(SPHERE), 300, 7)
    np.save(tmp_path / "p.npy", p)
    out = tmp_path / "q.npz"
    done = run_cli(cli, "query", "--mesh", SPHERE, "--points", str(tmp_path / "p.npy"),
                   "--what", "closest,distance", "--out", str(out), "--quiet")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("points: 300 (")
    want = aperture.Scene(SPHERE).closest_points(p)
    with np.load(out) as q:
        assert set(q.files) == set(want)
        for key, value in want.items():
            np.testing.assert_array_equal(q[key], value, err_msg=key)


def test_query_command_errors_leave_no_file(cli: Path, tmp_path: Path):
    np.save(tmp_path / "p.npy", np.zeros((3, 3)))
    out = tmp_path / "q.npz"
    base = ["query", "--mesh", SPHERE, "--points", str(tmp_path / "p.npy"), "--out", str(out)]
    assert "unknown query 'distnce' (did you mean 'distance'?" in cli_error(cli, *base, "--what", "closest,distnce")
    assert "--out: '" in cli_error(cli, "query", "--mesh", SPHERE, "--points", str(tmp_path / "p.npy"),
                                   "--out", str(tmp_path / "q.txt"))
    assert str(tmp_path / "absent.npy") in cli_error(
        cli, "query", "--mesh", SPHERE, "--points", str(tmp_path / "absent.npy"), "--out", str(out))
    assert "--parity-directions 2 must be odd" in cli_error(cli, *base, "--what", "sign", "--parity-directions", "2")
    assert list(tmp_path.iterdir()) == [tmp_path / "p.npy"]
    done = run_cli(cli, "query", "--help")
    assert done.returncode == 0 and "--what" in done.stdout and "--sign-method" in done.stdout


def test_queries_release_the_gil():
    scene = aperture.Scene("procedural:sphere?radius=1&segments=256&rings=128")
    p = random_points(scene, 300000, 8)
    rays = np.tile([[0.0, 0.0, 5.0]], (200000, 1))
    dirs = np.tile([[0.0, 0.0, -1.0]], (200000, 1))
    for name, call in [("closest_points", lambda: scene.closest_points(p)),
                       ("count_intersections", lambda: scene.count_intersections(rays, dirs))]:
        seconds, during = count_during(call)
        assert seconds > 0.05, f"{name} too short ({seconds:.3f} s) to show anything"
        assert during > 10000, f"{name}: the counter advanced only {during} times in {seconds:.2f} s"


# ---- signed distance and occupancy: the sign is core/queries/inside.h's (tests there); these
# check that the Python and command-line outputs carry it, against a winding number computed
# here.

CUBE_VERTICES = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
# Two counter-clockwise (outward) triangles per face of [-1, 1]^3, vertex k = (x, y, z) bits 4, 2, 1.
CUBE_FACES = np.array([
    [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # x = -1, x = +1
    [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # y = -1, y = +1
    [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],  # z = -1, z = +1
], dtype=np.uint32)


def winding_numbers(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The exact generalized winding number: the sum of the triangles' signed solid angles
    (Van Oosterom and Strackee) over 4 pi."""
    out = np.empty(len(points))
    for k, p in enumerate(points):
        a, b, c = (triangles[:, i] - p for i in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        div = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la \
            + np.einsum("ij,ij->i", c, a) * lb
        out[k] = 2 * np.arctan2(det, div).sum() / (4 * np.pi)
    return out


def grid_off_the_surface(faces: np.ndarray) -> np.ndarray:
    """Points of a grid through the cube's face planes, edges and vertices (coordinates in
    -1.5, -1, ..., 1.5), without those on its surface."""
    v = np.array([-1.5, -1.0, -0.5, 0.0, 0.25, 1.0, 1.5])
    p = np.stack(np.meshgrid(v, v, v, indexing="ij"), axis=-1).reshape(-1, 3)
    tris = CUBE_VERTICES[faces]
    on_surface = brute_force_distance(tris, p) == 0
    return p[~on_surface]


def test_signed_distance_and_occupancy_on_a_closed_cube():
    scene = aperture.Scene(vertices=CUBE_VERTICES, faces=CUBE_FACES)
    p = grid_off_the_surface(CUBE_FACES)
    inside = winding_numbers(CUBE_VERTICES[CUBE_FACES], p) > 0.5
    assert 0 < inside.sum() < len(p)
    sd = scene.signed_distance(p)
    assert scene.last_query["method"] == "parity"
    np.testing.assert_array_equal(sd < 0, inside)
    np.testing.assert_allclose(np.abs(sd), scene.distance(p), rtol=0, atol=0)
    occ = scene.occupancy(p)
    assert occ.dtype == np.uint8
    np.testing.assert_array_equal(occ, inside)
    np.testing.assert_array_equal(scene.occupancy(p, method="winding"), inside)
    assert scene.last_query["method"] == "winding"
    with pytest.raises(ValueError, match="unknown inside method 'windng'.*did you mean 'winding'"):
        scene.occupancy(p, method="windng")


def test_an_open_cube_defaults_to_the_winding_number():
    faces = CUBE_FACES[:10]  # without its top (z = +1)
    scene = aperture.Scene(vertices=CUBE_VERTICES, faces=faces)
    p = grid_off_the_surface(faces)
    w = winding_numbers(CUBE_VERTICES[faces], p)
    clear = np.abs(w - 0.5) > 0.05
    occ = scene.occupancy(p)
    assert scene.last_query["method"] == "winding"
    np.testing.assert_array_equal(occ[clear], (w > 0.5)[clear])


def test_query_command_stores_the_sign_method(cli: Path, tmp_path: Path):
    scene = aperture.Scene(SPHERE)
    p = random_points(scene, 200, 9)
    np.save(tmp_path / "p.npy", p)
    out = tmp_path / "q.npz"
    done = run_cli(cli, "query", "--mesh", SPHERE, "--points", str(tmp_path / "p.npy"),
                   "--what", "sign,occupancy", "--sign-method", "winding", "--out", str(out), "--quiet")
    assert done.returncode == 0, done.stderr
    with np.load(out) as q:
        assert str(q["sign_method"]) == "winding"
        np.testing.assert_array_equal(q["signed_distance"], scene.signed_distance(p, method="winding"))
        np.testing.assert_array_equal(q["occupancy"], q["signed_distance"] < 0)
        assert "winding_number" in q.files


def test_signed_distance_against_open3d_on_a_closed_sphere(o3d):
    """Open3D's compute_signed_distance on the same closed mesh: equal magnitudes to float
    precision; where the signs differ, aperture's is the exact winding number's."""
    scene = aperture.Scene(SPHERE)
    p = random_points(scene, 2000, 10).astype(np.float32).astype(np.float64)
    tris = scene.triangles().reshape(-1, 3)
    rs = o3d.t.geometry.RaycastingScene()
    rs.add_triangles(o3d.core.Tensor(tris.astype(np.float32)),
                     o3d.core.Tensor(np.arange(len(tris), dtype=np.uint32).reshape(-1, 3)))
    theirs = rs.compute_signed_distance(o3d.core.Tensor(p.astype(np.float32))).numpy()
    ours = scene.signed_distance(p)
    assert scene.last_query["method"] == "parity"
    np.testing.assert_allclose(np.abs(ours), np.abs(theirs), rtol=2e-5, atol=2e-5)
    differ = np.flatnonzero((ours < 0) != (theirs < 0))
    if len(differ):
        w = winding_numbers(scene.triangles(), p[differ])
        np.testing.assert_array_equal(ours[differ] < 0, w > 0.5)
    inside = winding_numbers(scene.triangles(), p) > 0.5
    np.testing.assert_array_equal(ours < 0, inside)
