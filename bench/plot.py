#!/usr/bin/env python3
"""Turns `aperture bench --sweep packet --json` and `--sweep threads --json` outputs into one PNG:
Mrays/s against packet width (left) and Mrays/s and parallel efficiency against threads (right).
Median per point, min..max as error bars. Needs Debian's python3-matplotlib
(bench/install-peers.sh).

    B=build/apps/aperture; M=../shared/meshes/stanford/dragon_vrip.ply
    CAM="--eye 0,0.12,0.45 --at 0,0.12,0 --fov 30 --size 1024,1024 --aov color"
    $B bench --mesh $M $CAM --sweep packet  --json out/dragon_packet.json
    $B bench --mesh $M $CAM --sweep threads --json out/dragon_threads.json
    python3 bench/plot.py --packet out/dragon_packet.json --threads out/dragon_threads.json

Several files per option give one line each (labelled by mesh, or LABEL=FILE).
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def load(spec, key):
    label, _, path = spec.rpartition("=")
    with open(path) as f:
        j = json.load(f)
    if key not in j:
        sys.exit(f"plot: {path} has no '{key}' (was it written by aperture bench --sweep "
                 f"{key.split('_')[1]} --json?)")
    c = j.get("config", {})
    if not label:
        meshes = str(c.get("meshes", "scene"))
        label = os.path.splitext(os.path.basename(meshes.split(",")[0]))[0] or meshes
    return label, j[key], c


def errs(rows):
    med = [r["mrays_per_s_median"] for r in rows]
    lo = [m - r["mrays_per_s"]["min"] for m, r in zip(med, rows)]
    hi = [r["mrays_per_s"]["max"] - m for m, r in zip(med, rows)]
    return med, [lo, hi]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--packet", nargs="*", default=[], metavar="[LABEL=]JSON")
    ap.add_argument("--threads", nargs="*", default=[], metavar="[LABEL=]JSON")
    ap.add_argument("-o", "--out", default=os.path.join(HERE, "plots", "sweeps.png"))
    ap.add_argument("--title", default="aperture: Mrays/s against packet width and threads")
    args = ap.parse_args()
    if not args.packet and not args.threads:
        ap.error("give --packet and/or --threads JSON files")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = int(bool(args.packet)) + int(bool(args.threads))
    fig, axes = plt.subplots(1, panels, figsize=(6.2 * panels, 4.4), squeeze=False)
    axes = list(axes[0])
    subtitle = set()

    if args.packet:
        ax = axes.pop(0)
        for spec in args.packet:
            label, rows, c = load(spec, "sweep_packet")
            rows = sorted(rows, key=lambda r: r["packet_width"])
            x = [r["packet_width"] for r in rows]
            med, e = errs(rows)
            ax.errorbar(x, med, yerr=e, marker="o", capsize=3, label=label)
            subtitle.add(f"{c.get('width')}x{c.get('height')}, AOVs {c.get('aovs')}, {c.get('threads')} threads, "
                         f"Embree {c.get('isa')}")
        ax.set_xscale("log", base=2)
        ax.set_xticks([1, 4, 8, 16], labels=["1", "4", "8", "16"])
        ax.set_xlabel("rays per Embree call (packet width)")
        ax.set_ylabel("Mrays/s (median; bars: min..max)")
        ax.set_ylim(bottom=0)
        ax.grid(True, alpha=0.3)
        ax.legend()
        ax.set_title("packet width")

    if args.threads:
        ax = axes.pop(0)
        eff_ax = ax.twinx()
        for i, spec in enumerate(args.threads):
            label, rows, c = load(spec, "sweep_threads")
            rows = sorted(rows, key=lambda r: r["threads"])
            x = [r["threads"] for r in rows]
            med, e = errs(rows)
            color = f"C{i}"
            ax.errorbar(x, med, yerr=e, marker="o", capsize=3, color=color, label=f"{label} Mrays/s")
            eff_ax.plot(x, [100 * r["parallel_efficiency"] for r in rows], ls="--", marker="s",
                        color=color, alpha=0.7, label=f"{label} efficiency")
            subtitle.add(f"{c.get('width')}x{c.get('height')}, AOVs {c.get('aovs')}, packet {c.get('packet_width')}, "
                         f"Embree {c.get('isa')}")
        ax.set_xlabel("worker threads")
        ax.set_xticks(sorted({r["threads"] for s in args.threads for r in load(s, "sweep_threads")[1]}))
        ax.set_ylabel("Mrays/s (median; bars: min..max)")
        ax.set_ylim(bottom=0)
        eff_ax.set_ylabel("parallel efficiency, % (dashed)")
        eff_ax.set_ylim(0, 110)
        ax.grid(True, alpha=0.3)
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = eff_ax.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, loc="lower right", fontsize="small")
        ax.set_title("threads")

    fig.suptitle(args.title + "\n" + "; ".join(sorted(subtitle)), fontsize="medium")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"plot: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
