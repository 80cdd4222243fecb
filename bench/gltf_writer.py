"""A small glTF 2.0 binary (.glb) writer for benchmarks and the gallery, independent of aperture.

    w = GlbWriter()
    tex = w.png_texture(rgb_uint8_array, nearest=True)
    mat = w.material('checker', base_color=(1, 1, 1, 1), texture=tex)
    mesh = w.mesh('ground', positions, indices, uv=uv, colors=None, material=mat)
    w.node('ground_1', mesh=mesh, translation=(0, 0, 0))
    w.write('scene.glb')

Positions float32 (N, 3), indices uint32 (T, 3), uv float32 (N, 2) with (0, 0) at the image's
top-left (glTF), colors float32 (N, 4) linear RGBA. Every node is a root of scene 0 unless it is
given as another node's child.
"""
import json
import struct
import zlib

import numpy as np


def png_bytes(rgb):
    """An 8-bit RGB PNG of `rgb` (H, W, 3) uint8, filter 0 on every row."""
    h, w, _ = rgb.shape
    raw = b''.join(b'\0' + rgb[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return (struct.pack('>I', len(data)) + kind + data +
                struct.pack('>I', zlib.crc32(kind + data) & 0xFFFFFFFF))

    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(raw, 6)) + chunk(b'IEND', b''))


class GlbWriter:
    def __init__(self):
        self.gltf = {'asset': {'version': '2.0', 'generator': 'aperture bench/gltf_writer.py'},
                     'bufferViews': [], 'accessors': [], 'meshes': [], 'nodes': []}
        self.blob = bytearray()
        self.children = set()

    def _view(self, data, target=None):
        self.blob += b'\0' * (-len(self.blob) % 4)
        view = {'buffer': 0, 'byteOffset': len(self.blob), 'byteLength': len(data)}
        if target:
            view['target'] = target
        self.blob += data
        self.gltf['bufferViews'].append(view)
        return len(self.gltf['bufferViews']) - 1

    def _accessor(self, array, kind, component, target, bounds=False):
        array = np.ascontiguousarray(array)
        acc = {'bufferView': self._view(array.tobytes(), target), 'componentType': component,
               'count': int(array.shape[0]) if kind != 'SCALAR' else int(array.size),
               'type': kind}
        if bounds:
            acc['min'] = array.min(0).astype(float).tolist()
            acc['max'] = array.max(0).astype(float).tolist()
        self.gltf['accessors'].append(acc)
        return len(self.gltf['accessors']) - 1

    def png_texture(self, rgb, nearest=False, wrap=10497):
        """A texture of the RGB image, embedded; returns its index."""
        g = self.gltf
        g.setdefault('images', []).append({'bufferView': self._view(png_bytes(rgb)),
                                           'mimeType': 'image/png'})
        g.setdefault('samplers', []).append({'magFilter': 9728 if nearest else 9729,
                                             'wrapS': wrap, 'wrapT': wrap})
        g.setdefault('textures', []).append({'source': len(g['images']) - 1,
                                             'sampler': len(g['samplers']) - 1})
        return len(g['textures']) - 1

    def material(self, name, base_color=(1, 1, 1, 1), texture=None):
        pbr = {'baseColorFactor': list(map(float, base_color))}
        if texture is not None:
            pbr['baseColorTexture'] = {'index': texture}
        self.gltf.setdefault('materials', []).append({'name': name, 'pbrMetallicRoughness': pbr})
        return len(self.gltf['materials']) - 1

    def mesh(self, name, positions, indices, uv=None, colors=None, normals=None, material=None):
        """A mesh of one triangle primitive; returns its index."""
        attrs = {'POSITION': self._accessor(np.asarray(positions, '<f4'), 'VEC3', 5126, 34962,
                                            bounds=True)}
        if normals is not None:
            attrs['NORMAL'] = self._accessor(np.asarray(normals, '<f4'), 'VEC3', 5126, 34962)
        if uv is not None:
            attrs['TEXCOORD_0'] = self._accessor(np.asarray(uv, '<f4'), 'VEC2', 5126, 34962)
        if colors is not None:
            attrs['COLOR_0'] = self._accessor(np.asarray(colors, '<f4'), 'VEC4', 5126, 34962)
        prim = {'attributes': attrs,
                'indices': self._accessor(np.asarray(indices, '<u4').ravel(), 'SCALAR', 5125,
                                          34963)}
        if material is not None:
            prim['material'] = material
        self.gltf['meshes'].append({'name': name, 'primitives': [prim]})
        return len(self.gltf['meshes']) - 1

    def node(self, name, mesh=None, camera=None, translation=None, rotation=None, scale=None,
             matrix=None, children=()):
        n = {'name': name}
        for key, value in (('mesh', mesh), ('camera', camera), ('translation', translation),
                           ('rotation', rotation), ('scale', scale), ('matrix', matrix)):
            if value is not None:
                n[key] = value if isinstance(value, int) else [float(x) for x in value]
        if children:
            n['children'] = list(children)
            self.children.update(children)
        self.gltf['nodes'].append(n)
        return len(self.gltf['nodes']) - 1

    def perspective_camera(self, name, yfov, aspect=None, znear=0.01, zfar=None):
        cam = {'yfov': float(yfov), 'znear': float(znear)}
        if aspect is not None:
            cam['aspectRatio'] = float(aspect)
        if zfar is not None:
            cam['zfar'] = float(zfar)
        self.gltf.setdefault('cameras', []).append({'name': name, 'type': 'perspective',
                                                    'perspective': cam})
        return len(self.gltf['cameras']) - 1

    def write(self, path):
        g = dict(self.gltf)
        g['scenes'] = [{'nodes': [k for k in range(len(g['nodes'])) if k not in self.children]}]
        g['scene'] = 0
        blob = bytes(self.blob) + b'\0' * (-len(self.blob) % 4)
        g['buffers'] = [{'byteLength': len(blob)}]
        text = json.dumps(g, separators=(',', ':')).encode()
        text += b' ' * (-len(text) % 4)
        with open(path, 'wb') as f:
            f.write(struct.pack('<III', 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(blob)))
            f.write(struct.pack('<II', len(text), 0x4E4F534A) + text)
            f.write(struct.pack('<II', len(blob), 0x004E4942) + blob)
