"""Regenerates docs/gallery/ from the current build: every picture is one `aperture render`
command, run here and written under its picture in docs/gallery/README.md.

    .venv/bin/python docs/gallery/make_gallery.py [--aperture build/apps/aperture]
        [--shared ../shared] [--out docs/gallery]

1. The lecture's cameras (perspective, shifted, orthographic, oblique, thin lens, panoramas) and
   a few calibrated lens models on the shared meshes (the dragon, the bathroom interior).
2. A glTF scene written by this script (bench/gltf_writer.py: a textured ground, a mesh
   instanced three times, vertex colours, two materials) and its depth, normal, instance,
   material, uv and albedo side by side.
Previews are the command line's own (`--preview`); uv, which has no preview rule, is written as
.npy and painted here as (u, v, 0).
"""
import argparse
import os
import shlex
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, 'bench'))
from gltf_writer import GlbWriter, png_bytes  # noqa: E402

SIZE = '480,360'


def lecture_shots(shared):
    dragon = f'{shared}/meshes/stanford/dragon_vrip.ply'
    bath = f'{shared}/meshes/scenes/contemporary-bathroom_flat.ply'
    crown = f'{shared}/meshes/scenes/crown_flat.ply'
    tilt = ['--eye', '0,5.5,24', '--at', '0,11,-10', '--fov', '50']
    look = ['--eye', '0,0.12,0.45', '--at', '0,0.12,0', '--up', '0,1,0']
    inside = ['--eye', '0.00724,0.9124,-0.22758', '--dir', '-0.751879,0.015471,-0.659119',
              '--up', '0.0116337,0.99988,0.0101985']
    normal = ['--aov', 'normal']
    return [
        ('perspective', 'perspective, fov 30°', [
            '--mesh', dragon, *look, '--fov', '30', *normal]),
        ('shifted', 'perspective with a lens shift (0.25, 0): the dragon moves left, no rotation', [
            '--mesh', dragon, *look, '--fov', '30', '--shift', '0.25,0', *normal]),
        ('tilted', 'the crown, camera tilted up: converging verticals', [
            '--mesh', crown, *tilt, *normal]),
        ('architectural', '`--architectural`: the tilt becomes a lens shift, verticals stay parallel', [
            '--mesh', crown, *tilt, '--architectural', *normal]),
        ('orthographic', 'orthographic, viewport 0.3 × 0.225', [
            '--mesh', dragon, '--camera', 'orthographic', *look, '--viewport', '0.3,0.225',
            *normal]),
        ('oblique', 'oblique, shear angles (20°, 10°)', [
            '--mesh', dragon, '--camera', 'oblique', *look, '--viewport', '0.3,0.225',
            '--oblique-angles', '20,10', *normal]),
        ('thinlens', 'thin lens R = 0.01 focused on the head, 64 spp (colour)', [
            '--mesh', dragon, '--camera', 'thinlens', '--eye', '0.15,0.15,0.3', '--at',
            '-0.05,0.12,0', '--fov', '30', '--aperture', '0.01', '--focus', '0.3', '--spp', '64',
            '--aov', 'color']),
        ('equirect', 'equirect: the whole bathroom from one point', [
            '--mesh', bath, '--camera', 'equirect', *inside, *normal]),
        ('fisheye', 'equidistant fisheye, 180°', [
            '--mesh', bath, '--camera', 'fisheye', *inside, *normal]),
        ('opencv_fisheye', 'calibrated OPENCV_FISHEYE (k1..k4 = 0.1, 0.01, 0, 0), fx = fy = 150', [
            '--mesh', bath, *inside, '--intrinsics', '150,150,240,180', '--lens-model',
            'OPENCV_FISHEYE', '--distortion', '0.1,0.01,0,0', *normal]),
        ('full_opencv', 'calibrated FULL_OPENCV, strong barrel (k1 = −0.3)', [
            '--mesh', bath, *inside, '--intrinsics', '300,300,240,180', '--lens-model',
            'FULL_OPENCV', '--distortion', '-0.3,0.08,0,0,0,0,0,0', *normal]),
    ]


def box(size=(1, 1, 1)):
    """A box with its own texture coordinates per face and per-vertex colours by position."""
    sx, sy, sz = (s / 2 for s in size)
    faces = [((1, 0, 0), (0, 0, -1), (0, 1, 0)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((0, 1, 0), (1, 0, 0), (0, 0, -1)), ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
             ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (-1, 0, 0), (0, 1, 0))]
    pos, uv, idx = [], [], []
    for n, u, v in faces:
        base = len(pos)
        for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = np.array(n, float) + a * np.array(u, float) + b * np.array(v, float)
            pos.append(p * (sx, sy, sz))
            uv.append(((a + 1) / 2, (1 - b) / 2))
        idx += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    pos = np.asarray(pos, np.float32)
    colors = np.concatenate([(pos - pos.min(0)) / np.ptp(pos, 0), np.ones((len(pos), 1))], 1)
    return pos, np.asarray(uv, np.float32), np.asarray(idx, np.uint32), colors.astype(np.float32)


def checker(n=8, texels=8):
    cells = (np.add.outer(np.arange(n * texels) // texels, np.arange(n * texels) // texels) % 2)
    return np.where(cells[..., None] == 1, (230, 180, 60), (40, 60, 120)).astype(np.uint8)


def gltf_scene(path):
    w = GlbWriter()
    tex = w.png_texture(checker(), nearest=True)
    tiles = w.material('tiles', texture=tex)
    paint = w.material('paint', base_color=(0.9, 0.3, 0.2, 1))
    ground = np.array([(-4, 0, -4), (4, 0, -4), (4, 0, 4), (-4, 0, 4)], np.float32)
    g = w.mesh('ground', ground, [(0, 2, 1), (0, 3, 2)],
               uv=np.array([(0, 0), (2, 0), (2, 2), (0, 2)], np.float32), material=tiles)
    pos, uv, idx, colors = box()
    crate = w.mesh('crate', pos, idx, uv=uv, material=tiles)
    block = w.mesh('block', pos, idx, uv=uv, colors=colors, material=paint)
    crates = [w.node(f'crate_{k}', mesh=crate, translation=(x, 0.5, z),
                     rotation=(0, np.sin(a / 2), 0, np.cos(a / 2)))
              for k, (x, z, a) in enumerate(((-1.6, 0.4, 0.3), (0, -1.2, 0.9), (1.7, 0.6, -0.4)))]
    stack = w.node('stack', mesh=block, translation=(0, 1.5, 0), scale=(0.6, 2, 0.6))
    w.node('crates', children=crates, translation=(0, 0, 0))
    w.node('ground', mesh=g)
    w.node('tower', children=[stack], matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.2, 0, 1.8, 1])
    w.write(path)


def run(aperture, args, env=None):
    cmd = [aperture, 'render', '--size', SIZE, '--quiet', *args]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        sys.exit(f'failed: {shlex.join(cmd)}\n{done.stderr}')
    return cmd


def shown(cmd, out, shared, work):
    """The command as a reader types it: paths relative to the project, no --quiet."""
    words = [c.replace(shared, '../shared').replace(out, 'docs/gallery').replace(work, '/tmp/gallery')
             for c in cmd if c != '--quiet']
    words[0] = 'aperture'
    return shlex.join(words)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--aperture', default=os.path.join(ROOT, 'build/apps/aperture'))
    ap.add_argument('--shared', default=os.path.join(os.path.dirname(ROOT), 'shared'))
    ap.add_argument('--out', default=HERE)
    args = ap.parse_args()
    shared = os.path.abspath(args.shared)
    out = os.path.abspath(args.out)
    work = tempfile.mkdtemp(prefix='aperture_gallery_')
    lines = ['# Gallery', '',
             'Made by `docs/gallery/make_gallery.py` from the current build; the command under each '
             'picture made it (`--out` is where its EXR went; `/tmp/gallery` stands for the script\'s '
             'working folder, where it also writes the GLB).', '', '## Cameras and lenses', '',
             '| | |', '|---|---|']
    cells = []
    for name, caption, flags in lecture_shots(shared):
        cmd = run(args.aperture, [*flags, '--out', f'{work}/{name}.exr',
                                  '--preview', f'{out}/{name}.png'])
        cells.append(f'![]({name}.png)<br>{caption}<br>`{shown(cmd, out, shared, work)}`')
    for k in range(0, len(cells), 2):
        pair = cells[k:k + 2] + [''] * (2 - len(cells[k:k + 2]))
        lines.append(f'| {pair[0]} | {pair[1]} |')

    scene = f'{work}/crates.glb'
    gltf_scene(scene)
    view = ['--mesh', scene, '--eye', '4.5,3.8,6', '--at', '0,0.8,0', '--fov', '40']
    lines += ['', '## A glTF scene, AOV by AOV', '',
              'A GLB written by the script (`gltf_scene` in make_gallery.py): a textured crate mesh '
              'placed by three nodes, a block with vertex colours under a matrix node, a ground '
              'with the same checker texture (nearest filter).', '', '| | | |', '|---|---|---|']
    cells = []
    for aov in ('depth', 'normal', 'instance', 'material', 'uv', 'albedo'):
        if aov == 'uv':
            cmd = run(args.aperture, [*view, '--aov', 'uv', '--out', f'{work}/uv.npy'])
            uvs = np.load(f'{work}/uv.npy')
            rgb = np.clip(np.concatenate([uvs % 1.0, np.zeros(uvs.shape[:2] + (1,))], 2), 0, 1)
            with open(f'{out}/glb_uv.png', 'wb') as f:
                f.write(png_bytes((rgb * 255 + 0.5).astype(np.uint8)))
        else:
            cmd = run(args.aperture, [*view, '--aov', aov, '--out', f'{work}/{aov}.exr',
                                      '--preview', f'{out}/glb_{aov}.png'])
        cells.append(f'![](glb_{aov}.png)<br>{aov}<br>`{shown(cmd, out, shared, work)}`')
    for k in range(0, len(cells), 3):
        lines.append('| ' + ' | '.join(cells[k:k + 3]) + ' |')
    with open(f'{out}/README.md', 'w') as f:
        f.write('\n'.join(lines) + '\n')
    print(f'wrote {out}/README.md and {len(lecture_shots(shared)) + 6} pictures')


if __name__ == '__main__':
    main()
