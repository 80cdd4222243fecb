"""aperture.distributed.Renderer in this process, on a local Dask cluster (2 worker processes)
and on a local Ray (2 CPUs): its files equal, byte for byte, those `aperture batch` writes for
the same cameras (the command line is the independent path: its job parser, view path and
writer threads), the scene is built once per worker, and a worker killed (Dask) or a task that
raises (Ray) leaves every file once, equal to batch's, and no temporary.

Dask and Ray each start once, in a class-scoped fixture torn down after its class, so the two
never run at once; the Ray tests skip with the reason where ray cannot be imported."""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import aperture
from aperture import distributed
from conftest import run_cli

SCENE = "procedural:default"
SIZE = (32, 24)
AOVS = ["depth", "distance", "normal", "primid"]
# One file per AOV, in the dataset formats batch writes (16-bit PNG, PFM, NPY; not TIFF, whose
# DateTime tag records when it was written, so that two writes of it are never the same bytes).
FORMATS = {"depth": "png", "distance": "pfm", "normal": "npy", "primid": "npy"}
N = 16


def camera_keywords(k: int) -> dict:
    """Camera k of N on a ring around the default scene, looking at its centre."""
    angle = 2 * np.pi * k / N
    eye = [float(9 * np.sin(angle)), float(2 + 0.25 * k), float(9 * np.cos(angle))]
    return dict(eye=eye, at=[0.0, 0.5, 0.0], fov=40.0 + k)


def cameras() -> list[aperture.Camera]:
    out = []
    for k in range(N):
        c = aperture.Camera(size=SIZE, **camera_keywords(k))
        c.name = f"view{k:02d}"
        out.append(c)
    return out


def patterns(root: Path) -> dict[str, str]:
    return {aov: str(root / aov / f"{{name}}.{FORMATS[aov]}") for aov in AOVS}


def expected_files(root: Path) -> set[str]:
    return {f"{aov}/view{k:02d}.{FORMATS[aov]}" for aov in AOVS for k in range(N)}


def files_under(root: Path) -> set[str]:
    """Every file under root (temporaries included), relative."""
    return {str(p.relative_to(root)) for p in root.rglob("*") if p.is_file()}


@pytest.fixture(scope="module")
def batch_files(cli: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The files `aperture batch` writes for the N cameras, one dataset file per AOV."""
    root = tmp_path_factory.mktemp("batch")
    job = {
        "scene": {"meshes": [{"path": SCENE}]},
        "cameras": [{"name": f"view{k:02d}", **camera_keywords(k)} for k in range(N)],
        "aovs": ",".join(AOVS),
        "size": list(SIZE),
        "outputs": [{"aov": aov, "path": f"out/{aov}/{{camera}}.{FORMATS[aov]}"} for aov in AOVS],
    }
    (root / "job.json").write_text(json.dumps(job))
    done = run_cli(cli, "batch", str(root / "job.json"), "--quiet", "--summary", str(root / "summary.json"))
    assert done.returncode == 0, done.stderr
    assert files_under(root / "out") == expected_files(root)
    return root / "out"


def assert_equals_batch(root: Path, batch_files: Path) -> None:
    """Every file once (nothing else, no temporary), each equal to batch's byte for byte."""
    assert files_under(root) == expected_files(root)
    for name in sorted(expected_files(root)):
        assert (root / name).read_bytes() == (batch_files / name).read_bytes(), name


def renderer(root: Path, **options) -> distributed.Renderer:
    scene = aperture.Scene(SCENE)
    return distributed.Renderer(scene, aovs=AOVS, outputs=patterns(root), threads=1, **options)


def batches(size: int = 4) -> list[dict[str, list]]:
    """The cameras as tables of `size` rows, dicts of columns."""
    rows = distributed.camera_rows(cameras())
    return [{k: [r[k] for r in rows[i : i + size]] for k in rows[0]} for i in range(0, N, size)]


# In this process.


def test_arrays_equal_scene_render() -> None:
    scene = aperture.Scene(SCENE)
    reference = scene.render(cameras(), aovs=AOVS)
    out = distributed.Renderer(scene, aovs=AOVS)(batches(N)[0])
    assert list(out["name"]) == [f"view{k:02d}" for k in range(N)]
    for aov in AOVS:
        assert np.array_equal(out[aov].view(np.uint32), reference[aov].view(np.uint32)), aov


def test_every_kind_of_batch(tmp_path: Path) -> None:
    """Columns, a pandas DataFrame, a pyarrow Table, rows and Camera objects give the same
    arrays; the result is of the batch's kind."""
    pandas = pytest.importorskip("pandas")
    pyarrow = pytest.importorskip("pyarrow")
    scene = aperture.Scene(SCENE)
    r = distributed.Renderer(scene, aovs="depth")
    columns = batches(4)[1]
    reference = scene.render(cameras()[4:8], aovs="depth")["depth"]
    rows = distributed.camera_rows(cameras()[4:8])
    frame = pandas.DataFrame(rows)
    table = pyarrow.Table.from_pylist(rows)
    ray_like = {k: np.array(v) for k, v in columns.items()}  # Ray's numpy batches: (4, 3) eyes
    for got in (r(columns)["depth"], r(table)["depth"], r(ray_like)["depth"]):
        assert np.array_equal(got, reference)
    out = r(frame)
    assert isinstance(out, pandas.DataFrame) and list(out["name"]) == [f"view{k:02d}" for k in range(4, 8)]
    assert np.array_equal(np.stack(list(out["depth"])), reference)
    for batch in (rows, cameras()[4:8]):
        out = r(batch)
        assert isinstance(out, list) and [o["name"] for o in out] == [f"view{k:02d}" for k in range(4, 8)]
        assert np.array_equal(np.stack([o["depth"] for o in out]), reference)


def test_missing_cells_keep_the_defaults() -> None:
    """A table of cameras that set different keywords: an empty cell (None, NaN) is the default."""
    pandas = pytest.importorskip("pandas")
    a = aperture.Camera(eye=(0, 2, 9), at=(0, 0.5, 0), size=SIZE)
    b = aperture.Camera(eye=(3, 2, 9), at=(0, 0.5, 0), size=SIZE, fov=30, type="thinlens", aperture=0.02)
    rows = distributed.camera_rows([a, b])
    assert rows[0]["aperture"] is None and set(rows[0]) == set(rows[1])
    scene = aperture.Scene(SCENE)
    reference = scene.render([a, b], aovs="depth")["depth"]
    r = distributed.Renderer(scene, aovs="depth")
    assert np.array_equal(r(pandas.DataFrame(rows))["depth"].tolist(), reference.tolist())
    assert np.array_equal(r(rows)[1]["depth"], reference[1])


def test_files_equal_batch_and_are_kept_on_resume(tmp_path: Path, batch_files: Path) -> None:
    r = renderer(tmp_path)
    out = [r(b) for b in batches()]
    assert all(o["rendered"].all() for o in out)
    assert str(out[0]["depth"][0]) == str(tmp_path / "depth" / "view00.png")
    assert_equals_batch(tmp_path, batch_files)
    stamps = {p: (p.stat().st_ino, p.stat().st_mtime_ns) for p in tmp_path.rglob("*.*")}
    # One file lost: only its camera renders again, and only that file is written.
    lost = tmp_path / "normal" / "view05.npy"
    lost.unlink()
    again = [r(b) for b in batches()]
    assert [list(o["rendered"]) for o in again] == [[False] * 4, [False, True, False, False], [False] * 4, [False] * 4]
    assert_equals_batch(tmp_path, batch_files)
    for p, stamp in stamps.items():
        if p != lost:
            assert (p.stat().st_ino, p.stat().st_mtime_ns) == stamp, f"{p} was rewritten"


def test_temporaries_of_dead_processes_are_removed(tmp_path: Path, batch_files: Path) -> None:
    """What a worker killed while writing leaves (".NAME.tmp-PID-N"): removed before the file is
    written when PID is gone; one of a live process (this one) is kept."""
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(gone.stdout)
    (tmp_path / "depth").mkdir()
    dead = tmp_path / "depth" / f".view00.png.tmp-{dead_pid}-0.png"
    live = tmp_path / "depth" / f".view01.png.tmp-{os.getpid()}-7.png"
    other = tmp_path / "depth" / f".notours.png.tmp-{dead_pid}-0.png"
    for p in (dead, live, other):
        p.write_bytes(b"partial")
    r = renderer(tmp_path)
    for b in batches():
        r(b)
    assert not dead.exists()
    assert live.exists() and other.exists()
    live.unlink()
    other.unlink()
    assert_equals_batch(tmp_path, batch_files)


def test_a_temporary_of_a_pid_beyond_any_process_counts_as_dead(tmp_path: Path) -> None:
    """A PID that cannot be a process (2**40, beyond pid_t) is gone, as for batch --resume: the
    temporary is removed and the camera renders."""
    (tmp_path / "depth").mkdir()
    impossible = tmp_path / "depth" / f".view02.png.tmp-{2**40}-0.png"
    impossible.write_bytes(b"partial")
    out = renderer(tmp_path)(batches()[0])
    assert out["rendered"].all()
    assert not impossible.exists()
    assert (tmp_path / "depth" / "view02.png").exists()


def test_a_pickled_renderer_builds_once_per_process(tmp_path: Path) -> None:
    r = renderer(tmp_path)
    data = pickle.dumps(r)
    assert len(data) < 4000, "the renderer travels as the scene's specification"
    distributed.forget_scenes()  # as on a worker, where the scene was never built
    before = distributed.scene_builds()
    for b in batches():
        pickle.loads(data)(b)  # a fresh copy per task, as Dask sends it
    assert distributed.scene_builds() == before + 1
    # A worker whose cameras' files all exist builds nothing (as batch --resume).
    distributed.forget_scenes()
    pickle.loads(data)(batches()[0])
    assert distributed.scene_builds() == before + 1
    (tmp_path / "depth" / "view00.png").unlink()
    pickle.loads(data)(batches()[0])
    assert distributed.scene_builds() == before + 2


@pytest.mark.parametrize(
    "outputs,message",
    [
        ("out/{name}.png", r"put \{aov\} in it"),
        ("out/{aov}/{name}.exr", r"EXR records its render time"),
        ("out/{aov}/{name}.jpg", r"unknown extension"),
        ("out/{aov}/{camera}.png", r"unknown placeholder"),
        ({"color": "out/{name}.png"}, r"not among aovs"),
    ],
)
def test_bad_outputs_are_refused(outputs, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        distributed.Renderer(aperture.Scene(SCENE), aovs=["depth", "normal"], outputs=outputs)


def test_bad_names_are_refused(tmp_path: Path) -> None:
    r = distributed.Renderer(aperture.Scene(SCENE), aovs="depth", outputs=str(tmp_path / "{name}.png"))
    row = dict(eye=(0, 2, 9), at=(0, 0, 0), size=SIZE)
    for name in ("../up", "/abs", ""):
        with pytest.raises(ValueError, match="cannot name a file"):
            r([{**row, "name": name}])
    with pytest.raises(ValueError, match="would both write"):
        r([{**row, "name": "a"}, {**row, "name": "a"}])
    with pytest.raises(ValueError, match="unknown parameter 'fovv'"):
        r([{**row, "name": "a", "fovv": 3}])


# A local Dask cluster of 2 worker processes.


class TestDask:
    @pytest.fixture(scope="class")
    def client(self):
        distributed_module = pytest.importorskip("distributed", reason="dask.distributed cannot be imported")
        cluster = distributed_module.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
        )
        client = distributed_module.Client(cluster)
        try:
            yield client
        finally:
            client.close()
            cluster.close()

    @staticmethod
    def builds(client) -> dict[str, int]:
        return client.run(distributed.scene_builds)

    def test_client_map_equals_batch_and_builds_once_per_worker(self, client, tmp_path: Path, batch_files: Path) -> None:
        before = self.builds(client)
        r = renderer(tmp_path)
        futures = client.map(r, batches(2), pure=False)  # 8 tasks on 2 workers
        results = client.gather(futures)
        assert sum(len(o["name"]) for o in results) == N
        assert_equals_batch(tmp_path, batch_files)
        after = self.builds(client)
        grown = {w: after[w] - before.get(w, 0) for w in after}
        # 8 tasks on 2 workers: a build per task would show more than one on some worker.
        assert all(g in (0, 1) for g in grown.values()), grown
        assert sum(grown.values()) >= 1

    def test_bag_map_partitions_equals_batch(self, client, tmp_path: Path, batch_files: Path) -> None:
        import dask.bag

        rows = distributed.camera_rows(cameras())
        out = dask.bag.from_sequence(rows, npartitions=4).map_partitions(renderer(tmp_path)).compute()
        assert sorted(o["name"] for o in out) == [f"view{k:02d}" for k in range(N)]
        assert all(Path(o["depth"]).is_file() for o in out)
        assert_equals_batch(tmp_path, batch_files)

    def test_a_killed_worker(self, client, tmp_path: Path, batch_files: Path) -> None:
        """The first task to get there writes one camera's files and kills its worker (os._exit);
        Dask runs the task again elsewhere: it keeps that camera's files and writes the rest."""
        marker = tmp_path.parent / f"{tmp_path.name}.killed"
        r = renderer(tmp_path, _fail_once=("exit", str(marker)))
        results = client.gather(client.map(r, batches(4), pure=False))
        assert marker.exists(), "a worker should have been killed"
        assert sum(len(o["name"]) for o in results) == N
        assert sum(int(o["rendered"].sum()) for o in results) == N - 1, "the killed task's first camera is kept"
        assert_equals_batch(tmp_path, batch_files)


# A local Ray of 2 CPUs.


class TestRay:
    @pytest.fixture(scope="class")
    def ray(self, tmp_path_factory: pytest.TempPathFactory):
        ray = pytest.importorskip("ray", reason="ray cannot be imported (pip install 'aperture[ray]')")
        log = tmp_path_factory.mktemp("ray") / "builds.log"
        # Ray's processes inherit this environment: each scene build appends a line to `log`.
        os.environ["APERTURE_SCENE_BUILD_LOG"] = str(log)
        try:
            ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
            context = ray.data.DataContext.get_current()
            context.enable_progress_bars = False
            yield ray, log
        finally:
            ray.shutdown()
            del os.environ["APERTURE_SCENE_BUILD_LOG"]

    @staticmethod
    def run(ray, root: Path, **options) -> list[dict]:
        scene = aperture.Scene(SCENE)
        dataset = ray.data.from_items(distributed.camera_rows(cameras()))
        return dataset.map_batches(
            distributed.Renderer,
            fn_constructor_kwargs=dict(scene=scene, aovs=AOVS, outputs=patterns(root), threads=1, **options),
            compute=ray.data.ActorPoolStrategy(size=2),  # 2 actors (concurrency=2 before Ray 2.51)
            batch_size=4,
            num_cpus=1,
        ).take_all()

    def test_map_batches_equals_batch_and_builds_once_per_actor(self, ray, tmp_path: Path, batch_files: Path) -> None:
        ray_module, log = ray
        log.write_text("")
        rows = self.run(ray_module, tmp_path)
        assert sorted(r["name"] for r in rows) == [f"view{k:02d}" for k in range(N)]
        assert_equals_batch(tmp_path, batch_files)
        pids = [line.split()[1] for line in log.read_text().splitlines()]
        assert 1 <= len(pids) <= 2 and len(set(pids)) == len(pids), pids

    def test_a_task_that_raises_once(self, ray, tmp_path: Path, batch_files: Path) -> None:
        ray_module, _ = ray
        context = ray_module.data.DataContext.get_current()
        retry = context.actor_task_retry_on_errors
        context.actor_task_retry_on_errors = True
        marker = tmp_path.parent / f"{tmp_path.name}.raised"
        try:
            rows = self.run(ray_module, tmp_path, _fail_once=("raise", str(marker)))
        finally:
            context.actor_task_retry_on_errors = retry
        assert marker.exists(), "a task should have raised"
        assert sorted(r["name"] for r in rows) == [f"view{k:02d}" for k in range(N)]
        assert_equals_batch(tmp_path, batch_files)
