#!/usr/bin/env python3
"""Checks that the peers rendered the same image as aperture (run with the venv python of
bench/install-peers.sh; called by bench/peers.py --check).

Eye-light peers. Inputs: aperture's EXR (color AOV: R = eye-light |N.D|, A = coverage), the Embree
viewer's PPM (--shader eyelight writes |N.D|, 8-bit, to the green channel on front faces and to
the red one on back faces) and the .npy of peers_mitsuba.py image (eye-light, coverage). Prints,
for each against aperture, the share of pixels whose coverage differs and the median / 99th
percentile of |eye-light difference| over the pixels both hit; writes a side-by-side PNG
(aperture | viewer | Mitsuba, sRGB-encoded grey). Figures only: there is no pass mark.

Open3D, traced on aperture's own rays (bench/peer_rays.py). Inputs: aperture's geometry AOVs as
.npy (`aperture render --aov A --out STEM_A.npy` for A = distance, normal, primid, geomid) and the
.npz of peers_open3d.py image, and the mesh. Passes when both report the same triangle (primid
and geomid, misses included) on >= 99.9 % of pixels and, where they do and it is a hit, the
distances agree within 1e-4 relative; the unit normals' dot products are reported. Exits 1 when it
fails. A different primid whose triangle has the same three vertex positions counts as the same
triangle: the crown holds coincident copies (0.56 % of its pixels show one), and which copy a BVH
reports is a tie; the strict share of equal primids is reported too.
"""
import argparse
import json
import sys

import numpy as np


def read_aperture(path):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    b = mi.Bitmap(path)
    names = [b.struct_()[i].name for i in range(b.channel_count())]
    a = np.array(b)
    return a[..., names.index("R")].astype(np.float64), a[..., names.index("A")] > 0.5


def read_viewer(path):
    from PIL import Image
    v = np.asarray(Image.open(path)).astype(np.float64) / 255.0
    # eyelight writes |N.D| to green where the ray hits a front face, to red on a back face.
    e = v[..., 0] + v[..., 1]
    return e, e > 0.0


def compare(ref, ref_hit, img, hit):
    both = ref_hit & hit
    diff = np.abs(ref[both] - img[both]) if both.any() else np.zeros(1)
    return {
        "coverage_mismatch": float((ref_hit != hit).mean()),
        "eyelight_absdiff_median": float(np.median(diff)),
        "eyelight_absdiff_p99": float(np.percentile(diff, 99)),
    }


# Open3D on aperture's rays: the pass marks of issue 13 item 6.
SAME_TRIANGLE_MIN = 0.999
DISTANCE_REL_MAX = 1e-4


def read_aperture_geometry(stem):
    """aperture's distance (H, W), normal (H, W, 3), primid and geomid (H, W) from STEM_<aov>.npy."""
    return {a: np.load(f"{stem}_{a}.npy") for a in ("distance", "normal", "primid", "geomid")}


def corners(vertices, triangles, ids):
    """The three vertex positions of each triangle in ids, in a canonical (sorted) order: (n, 3, 3)."""
    x = vertices[triangles[ids]]
    order = np.lexsort((x[..., 2], x[..., 1], x[..., 0]), axis=-1)
    return np.take_along_axis(x, order[..., None], axis=1)


def compare_open3d(ours, theirs, mesh):
    """Same triangle, distance and normal of aperture's geometry AOVs and Open3D's cast_rays; mesh:
    (vertices, triangles), to recognise coincident copies of a triangle."""
    miss = np.uint32(0xFFFFFFFF)
    strict = (ours["primid"] == theirs["primid"]) & (ours["geomid"] == theirs["geomid"])
    tie = ~strict & (ours["geomid"] == theirs["geomid"]) & (ours["primid"] != miss) & (theirs["primid"] != miss)
    copies = np.zeros(tie.sum(), dtype=bool)
    if tie.any():
        vertices, triangles = mesh
        copies = (corners(vertices, triangles, ours["primid"][tie]) ==
                  corners(vertices, triangles, theirs["primid"][tie])).all(axis=(1, 2))
    same = strict.copy()
    same[tie] = copies
    hit = same & (ours["primid"] != miss)
    t_ours, t_theirs = ours["distance"][hit].astype(np.float64), theirs["t_hit"][hit].astype(np.float64)
    rel = np.abs(t_ours - t_theirs) / t_theirs if hit.any() else np.zeros(1)
    dots = (ours["normal"][hit].astype(np.float64) * theirs["normal"][hit]).sum(-1) if hit.any() else np.ones(1)
    res = {
        "same_triangle": float(same.mean()),
        "same_primid": float(strict.mean()),
        "hits_compared": int(hit.sum()),
        "distance_rel_max": float(rel.max()),
        "distance_rel_median": float(np.median(rel)),
        "normal_dot_min": float(dots.min()),
    }
    res["ok"] = res["same_triangle"] >= SAME_TRIANGLE_MIN and res["distance_rel_max"] <= DISTANCE_REL_MAX
    return res


def srgb8(x):
    x = np.clip(x, 0.0, 1.0)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (255.0 * y + 0.5).astype(np.uint8)


def check_eyelight(args):
    """The viewer's and Mitsuba's eye-light against aperture's color AOV; writes the PNG."""
    ref, ref_hit = read_aperture(args.aperture)
    panels, res = [ref], {}
    if args.viewer:
        v, vh = read_viewer(args.viewer)
        if v.shape != ref.shape:
            sys.exit(f"peers_check: viewer image is {v.shape}, aperture's {ref.shape}")
        res["viewer"] = compare(ref, ref_hit, v, vh)
        panels.append(v)
    if args.mitsuba:
        m = np.load(args.mitsuba).astype(np.float64)
        if m.shape[:2] != ref.shape:
            sys.exit(f"peers_check: Mitsuba image is {m.shape[:2]}, aperture's {ref.shape}")
        res["mitsuba"] = compare(ref, ref_hit, m[..., 0], m[..., 1] > 0.5)
        panels.append(m[..., 0])
    for peer, r in res.items():
        print(f"{peer:8s} vs aperture: coverage differs on {100 * r['coverage_mismatch']:.3f}% of pixels; "
              f"|eye-light diff| median {r['eyelight_absdiff_median']:.2e}, p99 {r['eyelight_absdiff_p99']:.2e}")
    if args.png:
        from PIL import Image
        gap = np.full((ref.shape[0], 8), 0.25)
        row = [panels[0]]
        for p in panels[1:]:
            row += [gap, p]
        img = Image.fromarray(srgb8(np.concatenate(row, axis=1)), mode="L")
        scale = min(1.0, 1536.0 / img.width)
        if scale < 1.0:
            img = img.resize((int(img.width * scale), int(img.height * scale)), Image.BILINEAR)
        img.save(args.png)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--aperture", help="aperture EXR with the color AOV (for --viewer, --mitsuba)")
    ap.add_argument("--aperture-geometry", metavar="STEM",
                    help="aperture's STEM_distance.npy, STEM_normal.npy, STEM_primid.npy, STEM_geomid.npy")
    ap.add_argument("--viewer", help="viewer PPM (--shader eyelight)")
    ap.add_argument("--mitsuba", help=".npy from peers_mitsuba.py image")
    ap.add_argument("--open3d", help=".npz from peers_open3d.py image (needs --aperture-geometry, --mesh)")
    ap.add_argument("--mesh", help="the mesh both traced (read with Open3D, for coincident triangles)")
    ap.add_argument("--png", help="side-by-side PNG to write")
    ap.add_argument("--json", help="figures to write")
    args = ap.parse_args()
    if (args.viewer or args.mitsuba) and not args.aperture:
        ap.error("--viewer and --mitsuba need --aperture")
    if not (bool(args.open3d) == bool(args.aperture_geometry) == bool(args.mesh)):
        ap.error("--open3d, --aperture-geometry and --mesh go together")

    res = {}
    if args.aperture:
        res.update(check_eyelight(args))
    if args.open3d:
        import open3d as o3d
        from peers_open3d import read_mesh
        res["open3d"] = compare_open3d(read_aperture_geometry(args.aperture_geometry), np.load(args.open3d),
                                       read_mesh(o3d, args.mesh))
        r = res["open3d"]
        print(f"open3d   vs aperture: same triangle on {100 * r['same_triangle']:.3f}% of pixels "
              f"(pass >= {100 * SAME_TRIANGLE_MIN:g}%; same primid {100 * r['same_primid']:.3f}%); "
              f"over {r['hits_compared']} hits |distance diff| / distance "
              f"max {r['distance_rel_max']:.1e} (pass <= {DISTANCE_REL_MAX:g}), median "
              f"{r['distance_rel_median']:.1e}; normal dot min {r['normal_dot_min']:.6f}: "
              + ("ok" if r["ok"] else "FAILED"))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2)
    return 0 if res.get("open3d", {}).get("ok", True) else 1


if __name__ == "__main__":
    sys.exit(main())
