# Issue 13, item 3: a large file whose triangle order is scattered in space. Writes a
# 7072 x 7072-vertex height field (99,998,082 triangles, binary PLY, 1.9 GB) with its faces in a
# random order (seed 13). Needs numpy (the project's .venv has it):
#   .venv/bin/python bench/make_scattered_heightfield.py /tmp/big/shuffled_1e8.ply
import numpy as np, sys
n = 7072  # vertices per side: 2 * 7071^2 = 99,998,082 triangles
x = np.linspace(-1.0, 1.0, n, dtype=np.float32)
X, Y = np.meshgrid(x, x)
Z = (0.05 * np.sin(7 * X) * np.cos(5 * Y)).astype(np.float32)
verts = np.stack([X.ravel(), Z.ravel(), Y.ravel()], axis=1).astype('<f4')
del X, Y, Z
i = np.arange(n - 1, dtype=np.int32)
r, c = np.meshgrid(i, i, indexing='ij')
a = (r * n + c).ravel(); b = a + 1; d = a + n; e = d + 1
del r, c
tris = np.concatenate([np.stack([a, d, b], 1), np.stack([b, d, e], 1)])
del a, b, d, e
rng = np.random.default_rng(13)
tris = tris[rng.permutation(len(tris))]
faces = np.empty(len(tris), dtype=[('n', 'u1'), ('v', '<i4', 3)])
faces['n'] = 3; faces['v'] = tris
del tris
with open(sys.argv[1], 'wb') as f:
    f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\n"
             "property float x\nproperty float y\nproperty float z\n"
             f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
    verts.tofile(f); faces.tofile(f)
print(len(verts), len(faces))
