"""Issue 41, item 5: glTF at scale, side by side with binary PLY in one run.

1. A 10M-triangle height field (2237 x 2237 vertices, 9,999,392 triangles, spatial order) written
   as an uncompressed GLB and as a binary PLY with the same float32 positions and uint32 indices.
   Each round loads both with `aperture bench` (a fresh process each, files in the page cache
   after round 0, which is not counted) and the table gives the median load speed (file bytes over
   the loader's wall time) and the peak resident bytes per triangle of the process (VmHWM, which
   includes the BVH build) and of the mesh buffers alone.
2. A GLB of 10,000 nodes over 100 meshes (a 320-triangle sphere each): the log line of the build
   says how many triangles were stored (each mesh once) and how many instances place them.

    .venv/bin/python bench/gltf_scale.py [--aperture build/apps/aperture] [--rounds 5]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

from gltf_writer import GlbWriter


def heightfield(n):
    x = np.linspace(-1.0, 1.0, n, dtype=np.float32)
    X, Y = np.meshgrid(x, x)
    Z = (0.05 * np.sin(7 * X) * np.cos(5 * Y)).astype(np.float32)
    verts = np.stack([X.ravel(), Z.ravel(), Y.ravel()], axis=1).astype('<f4')
    i = np.arange(n - 1, dtype=np.uint32)
    r, c = np.meshgrid(i, i, indexing='ij')
    a = (r * n + c).ravel()
    b, d = a + 1, a + n
    e = d + 1
    # Two triangles per cell, interleaved so that consecutive triangles are neighbours.
    tris = np.stack([np.stack([a, d, b], 1), np.stack([b, d, e], 1)], 1).reshape(-1, 3)
    return verts, tris.astype('<u4')


def sphere(rings=10, segments=16):
    verts = [(0.0, 1.0, 0.0)]
    for r in range(1, rings):
        t = np.pi * r / rings
        for s in range(segments):
            p = 2 * np.pi * s / segments
            verts.append((np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)))
    verts.append((0.0, -1.0, 0.0))
    tris = []
    for s in range(segments):
        tris.append((0, 1 + (s + 1) % segments, 1 + s))
    for r in range(rings - 2):
        for s in range(segments):
            a, b = 1 + r * segments + s, 1 + r * segments + (s + 1) % segments
            c, d = a + segments, b + segments
            tris += [(a, b, d), (a, d, c)]
    last = len(verts) - 1
    base = 1 + (rings - 2) * segments
    for s in range(segments):
        tris.append((base + s, base + (s + 1) % segments, last))
    return np.asarray(verts, '<f4'), np.asarray(tris, '<u4')


def mesh_glb(path, meshes, nodes):
    """meshes: [(verts, tris)], nodes: [(mesh, translation)]."""
    w = GlbWriter()
    for m, (verts, tris) in enumerate(meshes):
        w.mesh(f'mesh_{m}', verts, tris)
    for k, (m, t) in enumerate(nodes):
        w.node(f'node_{k}', mesh=m, translation=t)
    w.write(path)


def write_ply(path, verts, tris):
    faces = np.empty(len(tris), dtype=[('n', 'u1'), ('v', '<u4', 3)])
    faces['n'] = 3
    faces['v'] = tris
    with open(path, 'wb') as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 f"element face {len(faces)}\nproperty list uchar uint vertex_indices\n"
                 "end_header\n").encode())
        verts.tofile(f)
        faces.tofile(f)


def bench(aperture, mesh, out):
    run = subprocess.run([aperture, 'bench', '--mesh', mesh, '--frames', '1', '--warmup', '0',
                          '--builds', '1', '--size', '64,64', '--json', out],
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f'{mesh}: aperture bench failed:\n{run.stderr}')
    return json.load(open(out)), run.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--aperture', default='build/apps/aperture')
    ap.add_argument('--rounds', type=int, default=5)
    ap.add_argument('--dir', default=os.path.join(tempfile.gettempdir(), 'gltf_scale'))
    args = ap.parse_args()
    os.makedirs(args.dir, exist_ok=True)
    glb, ply = os.path.join(args.dir, 'field.glb'), os.path.join(args.dir, 'field.ply')
    verts, tris = heightfield(2237)
    if not os.path.exists(glb):
        mesh_glb(glb, [(verts, tris)], [(0, (0.0, 0.0, 0.0))])
    if not os.path.exists(ply):
        write_ply(ply, verts, tris)
    triangles = len(tris)
    del verts, tris

    rows = {'glb': [], 'ply': []}
    for rnd in range(args.rounds + 1):  # round 0 warms the page cache and is not counted
        for name, path in (('glb', glb), ('ply', ply)):
            result, _ = bench(args.aperture, path, os.path.join(args.dir, f'{name}.json'))
            if rnd:
                rows[name].append(result)
    print(f'{triangles:,} triangles; GLB {os.path.getsize(glb):,} bytes, '
          f'PLY {os.path.getsize(ply):,} bytes; {args.rounds} rounds, medians')
    print('| file | load MB/s | mesh bytes/tri | peak RSS bytes/tri | peak RSS after load and build |')
    print('|---|---:|---:|---:|---:|')
    for name in ('glb', 'ply'):
        r = rows[name]
        speed = statistics.median(x['load_mb_per_s'] for x in r)
        mesh = statistics.median(x['memory']['mesh_bytes'] for x in r) / triangles
        peak = statistics.median(x['memory']['peak_rss_bytes'] for x in r)
        print(f'| {name} | {speed:.0f} | {mesh:.1f} | {peak / triangles:.1f} | {peak / 1e6:.0f} MB |')

    many = os.path.join(args.dir, 'many_nodes.glb')
    verts, tris = sphere()
    meshes = [(verts * (1 + 0.01 * m), tris) for m in range(100)]
    nodes = [(k % 100, (3.0 * (k % 100), 0.0, 3.0 * (k // 100))) for k in range(10000)]
    mesh_glb(many, meshes, nodes)
    _, log = bench(args.aperture, many, os.path.join(args.dir, 'many.json'))
    built = [line for line in log.splitlines() if 'built BVH' in line]
    print(f'10,000 nodes over 100 meshes of {len(tris)} triangles:')
    print(built[-1] if built else log)
    m = re.search(r'(\d+) triangles \((\d+) stored, (\d+) instances', built[-1] if built else '')
    if m:
        print(f'stored {int(m.group(2)):,} = {int(m.group(2)) // len(tris)} meshes x {len(tris)}; '
              f'{int(m.group(3)):,} instances')


if __name__ == '__main__':
    main()
