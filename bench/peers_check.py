#!/usr/bin/env python3
"""Checks that the three peers rendered the same image (run with the venv python of
bench/install-peers.sh; called by bench/peers.py --check).

Inputs: aperture's EXR (color AOV: R = eye-light |N.D|, A = coverage), the Embree viewer's PPM
(--shader eyelight writes |N.D|, 8-bit, to the green channel on front faces and to the red
one on back faces) and the .npy of
peers_mitsuba.py image (eye-light, coverage). Prints, for each peer against aperture, the share of
pixels whose coverage differs and the median / 99th percentile of |eye-light difference| over the
pixels both hit; writes a side-by-side PNG (aperture | viewer | Mitsuba, sRGB-encoded grey).
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


def srgb8(x):
    x = np.clip(x, 0.0, 1.0)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (255.0 * y + 0.5).astype(np.uint8)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--aperture", required=True, help="aperture EXR with the color AOV")
    ap.add_argument("--viewer", help="viewer PPM (--shader eyelight)")
    ap.add_argument("--mitsuba", help=".npy from peers_mitsuba.py image")
    ap.add_argument("--png", help="side-by-side PNG to write")
    ap.add_argument("--json", help="figures to write")
    args = ap.parse_args()

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
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
