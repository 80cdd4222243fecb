"""aperture's pinhole rays built in NumPy, for the peers that trace rays they are handed (Open3D's
RaycastingScene in bench/peers_open3d.py and bench/python_open3d.py).

The one owner, on the Python side, of aperture's perspective camera (docs/cameras.md):
  frame   W = -normalize(view), U = normalize(up x W), V = W x U (view = at - eye, or --dir);
  plane   at distance 1: --fov-axis y: vh = 2 tan(fov/2), vw = vh W/H; x: vw = 2 tan(fov/2),
          vh = vw H/W;
  pixel   (i, j) = row i, column j, centre at raster (j + 1/2, i + 1/2), spp 1:
          u = ((j + 1/2)/W - 1/2) vw,  v = -((i + 1/2)/H - 1/2) vh;
  ray     origin = eye, direction = normalize(u U + v V - W), computed in float64 and then
          rounded to float32 (Open3D takes float32 rays; t is then the distance from the eye).
aperture computes its directions in its own code path, so a few rays may differ in the last
float bit: the checks compare triangles and distances with a tolerance, not bit for bit.
"""
import math

import numpy as np


def camera_frame(eye, up, at=None, view=None):
    """(U, V, W) in float64 from eye and at (or a view direction) and up."""
    eye, up = np.asarray(eye, dtype=np.float64), np.asarray(up, dtype=np.float64)
    view = np.asarray(at, dtype=np.float64) - eye if view is None else np.asarray(view, dtype=np.float64)
    w = -view / np.linalg.norm(view)
    u = np.cross(up, w)
    u /= np.linalg.norm(u)
    return u, np.cross(w, u), w


def viewport(fov_deg, fov_axis, width, height):
    """(vw, vh): the image plane's extent at distance 1 for a fov spanning fov_axis ("x" or "y")."""
    extent = 2.0 * math.tan(math.radians(fov_deg) / 2.0)
    if fov_axis == "y":
        return extent * width / height, extent
    if fov_axis == "x":
        return extent, extent * height / width
    raise ValueError(f"peer_rays: fov axis {fov_axis!r}: expected 'x' or 'y'")


def pinhole_rays(eye, up, fov_deg, width, height, at=None, view=None, fov_axis="y"):
    """Rays (H, W, 6) float32, [ox oy oz dx dy dz], through aperture's pixel centres."""
    u, v, w = camera_frame(eye, up, at=at, view=view)
    vw, vh = viewport(fov_deg, fov_axis, width, height)
    pu = ((np.arange(width) + 0.5) / width - 0.5) * vw
    pv = -((np.arange(height) + 0.5) / height - 0.5) * vh
    d = pu[None, :, None] * u + pv[:, None, None] * v - w
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    rays = np.empty((height, width, 6), dtype=np.float32)
    rays[..., :3] = np.asarray(eye, dtype=np.float64)
    rays[..., 3:] = d
    return rays


def orbit(eye, at, n):
    """n eyes on the circle through `eye` around the vertical (y) axis through `at`: the dragon
    orbit of bench/python_batch.py and bench/python_wall.py."""
    r = math.hypot(eye[0] - at[0], eye[2] - at[2])
    return [(at[0] + r * math.sin(2 * math.pi * k / n), eye[1], at[2] + r * math.cos(2 * math.pi * k / n)) for k in range(n)]
