"""glTF scenes checked against trimesh (a real client: `pip install trimesh`): GLB files written
here by a small writer of their own (struct + json, independent of aperture's loader and of its
C++ test writer) hold the issue 41 test scene: nested nodes with TRS and matrix transforms, one
mesh placed by three nodes, two materials, vertex colours, a mesh of two primitives (indexed
and not), an unnamed node and a camera. trimesh's flattened world-space triangles equal
aperture's `Scene.triangles()` to float precision, in the same count (matched one to one);
`Scene.ids` names the file's nodes, meshes and materials; the surface AOVs come back as arrays;
the file's camera loads as a Camera."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np
import trimesh

import aperture

# ---- a minimal GLB writer ----


class Glb:
    """Accessors over one binary buffer, then the GLB container (JSON chunk, BIN chunk)."""

    def __init__(self) -> None:
        self.bin = bytearray()
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def accessor(self, values: np.ndarray, kind: str, indices: bool = False) -> int:
        array = np.ascontiguousarray(values)
        component = {np.dtype("<f4"): 5126, np.dtype("<u2"): 5123, np.dtype("<u4"): 5125}[array.dtype]
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append(
            {"buffer": 0, "byteOffset": len(self.bin), "byteLength": array.nbytes, "target": 34963 if indices else 34962}
        )
        self.bin += array.tobytes()
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[kind]
        entry = {"bufferView": len(self.views) - 1, "componentType": component, "count": array.size // width, "type": kind}
        if kind == "VEC3" and not indices:  # POSITION needs min and max
            rows = array.reshape(-1, 3)
            entry["min"] = rows.min(0).tolist()
            entry["max"] = rows.max(0).tolist()
        self.accessors.append(entry)
        return len(self.accessors) - 1

    def write(self, path: Path, doc: dict) -> Path:
        while len(self.bin) % 4:
            self.bin.append(0)
        doc = dict(doc, asset={"version": "2.0"}, bufferViews=self.views, accessors=self.accessors)
        doc["buffers"] = [{"byteLength": len(self.bin)}]
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(self.bin), 0x004E4942) + self.bin
        path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
        return path


def f32(values: list[float]) -> np.ndarray:
    return np.array(values, dtype="<f4")


def quaternion(axis: tuple[float, float, float], angle: float) -> list[float]:
    a = np.array(axis) / np.linalg.norm(axis) * math.sin(angle / 2)
    return [*a.tolist(), math.cos(angle / 2)]


NODE_NAMES = ["root", "quad_a", "quad_b", "group", "quad_c", "tri", "camera", None]


def issue41_glb(path: Path) -> Path:
    g = Glb()
    quad = g.accessor(f32([-0.5, -0.5, 0, 0.5, -0.5, 0, 0.5, 0.5, 0, -0.5, 0.5, 0]), "VEC3")
    quad_uv = g.accessor(f32([0, 1, 1, 1, 1, 0, 0, 0]), "VEC2")
    quad_colors = g.accessor(f32([1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 1]), "VEC4")
    quad_indices = g.accessor(np.array([0, 1, 2, 0, 2, 3], dtype="<u2"), "SCALAR", indices=True)
    flap = g.accessor(f32([0.5, -0.5, 0, 0.9, 0, 0.3, 0.5, 0.5, 0]), "VEC3")  # not indexed
    tri = g.accessor(f32([0, 0, 0, 1, 0, 0, 0, 1, 0.25]), "VEC3")
    tri_indices = g.accessor(np.array([0, 1, 2], dtype="<u4"), "SCALAR", indices=True)
    turned = [0.0] * 16
    c, s = math.cos(0.4), math.sin(0.4)
    # Column-major: a turn about x by 0.4 rad, then a move by (1.5, 0.25, -0.5).
    turned[0], turned[5], turned[6], turned[9], turned[10], turned[15] = 1, c, s, -s, c, 1
    turned[12:15] = [1.5, 0.25, -0.5]
    nodes = [
        {"translation": [0.1, -0.2, 0.3], "rotation": quaternion((0, 1, 0), 0.3), "scale": [1.0, 2.0, 0.5], "children": [1, 2, 3]},
        {"translation": [-1.5, 0, 0], "mesh": 0},
        {"matrix": turned, "mesh": 0},
        {"rotation": quaternion((1, 1, 0), 0.7), "children": [4]},
        {"scale": [0.5, 1.5, 2.0], "mesh": 0},
        {"translation": [0, 2.0, 0.5], "mesh": 1},
        {"translation": [0, 0.5, 6.0], "camera": 0},
        {"translation": [2.0, -1.0, 0], "rotation": quaternion((0, 0, 1), 1.1), "mesh": 1},
    ]
    for node, name in zip(nodes, NODE_NAMES):
        if name is not None:
            node["name"] = name
    doc = {
        "scene": 0,
        "scenes": [{"nodes": [0, 5, 6, 7]}],
        "nodes": nodes,
        "meshes": [
            {
                "name": "quad",
                "primitives": [
                    {"attributes": {"POSITION": quad, "TEXCOORD_0": quad_uv, "COLOR_0": quad_colors}, "indices": quad_indices, "material": 0},
                    {"attributes": {"POSITION": flap}, "material": 1},
                ],
            },
            {"name": "tri", "primitives": [{"attributes": {"POSITION": tri}, "indices": tri_indices, "material": 1}]},
        ],
        "materials": [
            {"name": "checker", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1]}},
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}}],
    }
    return g.write(path, doc)


def trimesh_triangles(path: Path) -> np.ndarray:
    """trimesh's world-space triangles of every mesh node, (T, 3, 3) float64."""
    scene = trimesh.load(str(path), force="scene")
    return np.asarray(scene.to_geometry().triangles, dtype=np.float64)


def match(ours: np.ndarray, theirs: np.ndarray) -> np.ndarray:
    """For each of our triangles the index of the closest of theirs (largest coordinate
    difference, corners in order), asserting a one-to-one match to float precision."""
    assert ours.shape == theirs.shape, (ours.shape, theirs.shape)
    flat_ours, flat_theirs = ours.reshape(len(ours), 9), theirs.reshape(len(theirs), 9)
    distance = np.abs(flat_ours[:, None, :] - flat_theirs[None, :, :]).max(-1)
    nearest = distance.argmin(1)
    scale = max(1.0, float(np.abs(flat_theirs).max()))
    assert distance[np.arange(len(ours)), nearest].max() <= 4e-7 * scale
    assert sorted(nearest.tolist()) == list(range(len(theirs))), "not one to one"
    return nearest


def test_triangles_equal_trimesh(tmp_path: Path) -> None:
    for name in ("scene.glb",):
        path = issue41_glb(tmp_path / name)
        scene = aperture.Scene(path)
        ours = scene.triangles()
        assert ours.dtype == np.float64 and ours.shape == (11, 3, 3)  # 3 quads x 3 + 2 triangles
        assert len(ours) == scene.triangle_count
        match(ours, trimesh_triangles(path))


def trs_matrix(node: dict) -> np.ndarray:
    """A node's local matrix, composed here: T · R · S, or its column-major matrix."""
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = r * np.array(node.get("scale", [1, 1, 1]))[None, :]
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def test_triangle_order_is_node_order(tmp_path: Path) -> None:
    # Objects in node order, depth first (quad_a, quad_b, quad_c: the indexed primitive's two
    # triangles, then the other's; tri; the unnamed node's tri), worked out here from the file's
    # JSON: each mesh's corners through the composed node matrices.
    path = issue41_glb(tmp_path / "scene.glb")
    ours = aperture.Scene(path).triangles()
    raw = path.read_bytes()
    (length,) = struct.unpack_from("<I", raw, 12)
    doc = json.loads(raw[20 : 20 + length])
    binary = raw[20 + length + 8 :]

    def floats(accessor: int) -> np.ndarray:
        a = doc["accessors"][accessor]
        v = doc["bufferViews"][a["bufferView"]]
        dtype = {5126: "<f4", 5123: "<u2", 5125: "<u4"}[a["componentType"]]
        width = {"SCALAR": 1, "VEC3": 3}[a["type"]]
        return np.frombuffer(binary, dtype=dtype, count=a["count"] * width, offset=v["byteOffset"]).reshape(-1, width)

    def corners(mesh: int) -> np.ndarray:
        out = []
        for prim in doc["meshes"][mesh]["primitives"]:
            positions = floats(prim["attributes"]["POSITION"]).astype(np.float64)
            index = floats(prim["indices"]).ravel() if "indices" in prim else np.arange(len(positions))
            out.append(positions[index].reshape(-1, 3, 3))
        return np.concatenate(out)

    expected = []

    def walk(k: int, parent: np.ndarray) -> None:
        node = doc["nodes"][k]
        world = parent @ trs_matrix(node)
        if "mesh" in node:
            c = corners(node["mesh"])
            expected.append(np.einsum("ij,tcj->tci", world[:3, :3], c) + world[:3, 3])
        for child in node.get("children", []):
            walk(child, world)

    for root in doc["scenes"][0]["nodes"]:
        walk(root, np.eye(4))
    want = np.concatenate(expected)
    assert ours.shape == want.shape
    np.testing.assert_allclose(ours, want, rtol=0, atol=4e-7 * max(1.0, float(np.abs(want).max())))
    # A wrong order would be caught: the same triangles, objects swapped, are far apart.
    assert np.abs(ours - np.concatenate(expected[::-1])).max() > 0.1


def test_ids_name_the_file(tmp_path: Path) -> None:
    path = issue41_glb(tmp_path / "scene.glb")
    ids = aperture.Scene(path).ids
    assert ids["instance"] == [n if n is not None else f"node_{k}" for k, n in enumerate(NODE_NAMES)]
    assert ids["mesh"] == ["quad", "tri"]
    assert ids["material"] == ["checker", "red"]


def test_surface_aovs_are_arrays(tmp_path: Path) -> None:
    path = issue41_glb(tmp_path / "scene.glb")
    scene = aperture.Scene(path)
    camera = aperture.Camera(size=(48, 32), eye=(0.0, 0.5, 8.0), at=(0.0, 0.5, 0.0))
    out = scene.render(camera, aovs=["instance", "mesh", "material", "uv", "albedo", "depth"])
    assert out["instance"].dtype == np.uint32 and out["instance"].shape == (32, 48)
    assert out["material"].dtype == np.uint32 and out["material"].shape == (32, 48)
    assert out["uv"].dtype == np.float32 and out["uv"].shape == (32, 48, 2)
    assert out["albedo"].dtype == np.float32 and out["albedo"].shape == (32, 48, 4)
    hit = np.isfinite(out["depth"])
    assert hit.any() and (~hit).any()
    assert set(np.unique(out["instance"][hit]).tolist()) <= {1, 2, 4, 5, 7}
    assert (out["instance"][~hit] == 0xFFFFFFFF).all()
    # Two cameras of one size: (N, H, W[, C]).
    both = scene.render([camera, camera], aovs=["instance", "uv"])
    assert both["instance"].shape == (2, 32, 48) and both["uv"].shape == (2, 32, 48, 2)


def test_gltf_camera_loads(tmp_path: Path) -> None:
    path = issue41_glb(tmp_path / "scene.glb")
    (camera,) = aperture.load_cameras(path, height=60)
    assert camera.name == "camera" and camera.type == "perspective"
    assert (camera.width, camera.height) == (90, 60)  # width from aspectRatio 1.5
    assert camera.params["fov"] == np.float64(0.9 * 180 / math.pi)
    assert camera.params["eye"] == (0.0, 0.5, 6.0)
    out = aperture.Scene(path).render(camera, aovs=["depth"])
    assert np.isfinite(out["depth"]).any()
