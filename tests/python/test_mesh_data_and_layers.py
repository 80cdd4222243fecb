"""Mesh data AOVs (face./vertex. properties, shading normals, normal frames) and layered hits
from Python equal the command line's EXR bit for bit, and frames of one size rendered together
come back as one block per AOV without a copy."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import aperture
from conftest import assert_same_bits, run_cli

EYE, AT = (0.3, 0.4, 3.0), (0.0, 0.0, -0.5)


def write_layered_ply(path: Path) -> None:
    """A 2x2 grid of quads at z = 0 (object_id 10..13, normals tilted by x) in front of one big
    quad at z = -1 (object_id 20): two surfaces along most rays. `label` per vertex."""
    verts, faces = [], []

    def vertex(x: float, y: float, z: float) -> int:
        n = np.array([0.3 * x, 0.0, 1.0])
        n /= np.linalg.norm(n)
        verts.append((x, y, z, *n, len(verts) % 7))
        return len(verts) - 1

    for cell in range(4):
        x0, y0 = -1.0 + (cell % 2), -1.0 + (cell // 2)
        quad = [vertex(x0, y0, 0), vertex(x0 + 1, y0, 0), vertex(x0 + 1, y0 + 1, 0), vertex(x0, y0 + 1, 0)]
        faces.append((quad, 10 + cell))
    back = [vertex(-3, -3, -1), vertex(3, -3, -1), vertex(3, 3, -1), vertex(-3, 3, -1)]
    faces.append((back, 20))
    lines = ["ply", "format ascii 1.0", f"element vertex {len(verts)}", "property float x",
             "property float y", "property float z", "property float nx", "property float ny",
             "property float nz", "property int label", f"element face {len(faces)}",
             "property list uchar int vertex_indices", "property int object_id", "end_header"]
    lines += [" ".join(repr(float(c)) for c in v[:6]) + f" {v[6]}" for v in verts]
    lines += [f"{len(q)} " + " ".join(map(str, q)) + f" {i}" for q, i in faces]
    path.write_text("\n".join(lines) + "\n")


def vec(v: tuple[float, ...]) -> str:
    return ",".join(repr(float(x)) for x in v)


AOVS = "depth,normal,shading-normal,primid,face.object_id,vertex.label"


@pytest.mark.parametrize("frame", ["world", "opencv"])
def test_mesh_data_and_layers_equal_the_cli(tmp_path: Path, cli: Path, frame: str) -> None:
    mesh = tmp_path / "layered.ply"
    write_layered_ply(mesh)
    out = tmp_path / "cli.exr"
    done = run_cli(cli, "render", "--quiet", "--mesh", str(mesh), "--aov", AOVS, "--layers", "3",
                   "--normal-frame", frame, "--eye", vec(EYE), "--at", vec(AT), "--fov", "50",
                   "--size", "48x40", "--out", str(out))
    assert done.returncode == 0, done.stderr
    reference = aperture.read_exr(out)

    # No aovs= up front: the first render needing properties and normals loads them.
    scene = aperture.Scene(mesh)
    camera = aperture.Camera(eye=EYE, at=AT, fov=50, size=(48, 40))
    mine = scene.render(camera, aovs=AOVS, layers=3, normal_frame=frame)
    assert_same_bits(mine, reference)
    # The scene really shows what the test is about: both ids, two layers, tilted normals.
    ids = set(np.unique(mine["face.object_id"]).tolist())
    assert {10, 11, 12, 13, 20} <= ids
    assert mine["layers.depth"].shape == (3, 40, 48)
    assert np.isfinite(mine["layers.depth"][1]).sum() > 100
    assert not np.isfinite(mine["layers.depth"][2]).any()
    hit = np.isfinite(mine["depth"])
    assert np.abs(mine["shading-normal"][hit] - mine["normal"][hit]).max() > 0.05


def test_stacked_frames_equal_single_renders(tmp_path: Path) -> None:
    """Cameras of one size render into one block per AOV, (N, H, W[, C]) and (N, K, H, W) for
    layers; each frame equals that camera rendered alone, bit for bit."""
    mesh = tmp_path / "layered.ply"
    write_layered_ply(mesh)
    scene = aperture.Scene(mesh, aovs=AOVS)
    cams = [aperture.Camera(eye=(0.3 * k - 0.6, 0.4, 3.0), at=AT, fov=50, size=(36, 28)) for k in range(5)]
    together = scene.render(cams, aovs=AOVS + ",color", layers=2)
    assert together["normal"].shape == (5, 28, 36, 3)
    assert together["layers.primid"].shape == (5, 2, 28, 36)
    for k, cam in enumerate(cams):
        alone = scene.render(cam, aovs=AOVS + ",color", layers=2)
        assert_same_bits({name: together[name][k] for name in alone}, alone)
    assert not np.array_equal(together["depth"][0], together["depth"][4]), "the cameras differ"


def test_stacked_frames_are_not_copied() -> None:
    """The arrays of N frames of one size are the framebuffer itself: in a fresh process the
    peak resident memory grows by about one copy of the frames (a copy after rendering would
    hold two at once)."""
    # VmHWM (the peak resident set of this process image): ru_maxrss would carry over the
    # parent's peak across exec on Linux.
    script = textwrap.dedent("""
        import aperture
        def peak():
            for line in open("/proc/self/status"):
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
        scene = aperture.Scene("procedural:sphere?radius=1")
        cams = [aperture.Camera(eye=(0, 0, 4 + 0.01 * k), at=(0, 0, 0), size=(512, 512))
                for k in range(48)]
        scene.render(cams[:1], aovs="depth,normal")  # warm-up: code, allocator, BVH
        before = peak()
        out = scene.render(cams, aovs="depth,normal")
        frames = sum(a.nbytes for a in out.values())
        print(frames, peak() - before)
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    frames, growth = (int(x) for x in done.stdout.split())
    assert frames == 48 * 512 * 512 * 16
    assert growth < 1.4 * frames, f"peak memory grew by {growth} bytes for {frames} bytes of frames"
    assert growth > 0.8 * frames, "the frames should be resident once"
