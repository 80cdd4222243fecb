#!/usr/bin/env python3
"""Turns `aperture bench --sweep packet --json` and `--sweep threads --json` outputs into one PNG:
Mrays/s against packet width (left) and Mrays/s and parallel efficiency against threads (right).
Median per point, min..max as error bars. Needs Debian's python3-matplotlib
(bench/install-peers.sh).

`--scaling FILE` instead plots `aperture bench --scaling --json FILE` (bench/scaling.sh): bytes
per triangle (peak RSS, the --max-memory estimate, Embree, mesh) and Mrays/s of the frame loop
and of the bare baseline against triangles, one line style per BVH (default solid, compact
dashed):

    python3 bench/plot.py --scaling bench/results/scaling.json -o bench/plots/scaling.png

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


def plot_scaling(path, out, title):
    """Two panels against triangles (log): bytes/triangle, and Mrays/s with the ratio."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with open(path) as f:
        j = json.load(f)
    if "rows" not in j:
        sys.exit(f"plot: {path} has no 'rows' (was it written by aperture bench --scaling --json?)")
    c = j.get("config", {})
    fig, (mem, speed) = plt.subplots(1, 2, figsize=(12.4, 4.6))
    for i, bvh in enumerate(sorted({r["bvh"] for r in j["rows"]})):
        rows = sorted((r for r in j["rows"] if r["bvh"] == bvh), key=lambda r: r["triangles"])
        x = [r["triangles"] for r in rows]
        ls = "--" if rows[0]["compact"] else "-"
        per = lambda key: [r[key] / r["triangles"] for r in rows]
        mem.plot(x, [r["peak_rss_bytes_per_triangle"] for r in rows], ls, marker="o", color="C0",
                 label=f"peak RSS ({bvh})")
        mem.plot(x, per("estimate_bytes"), ls, marker="x", color="C1", label=f"--max-memory estimate ({bvh})")
        mem.plot(x, [r["embree_bytes_per_triangle"] for r in rows], ls, marker="s", color="C2",
                 label=f"Embree ({bvh})")
        mem.plot(x, [r["mesh_bytes_per_triangle"] for r in rows], ls, marker=".", color="C3",
                 label=f"mesh buffers ({bvh})")
        speed.plot(x, [r["mrays_per_s"] for r in rows], ls, marker="o", color="C0", label=f"frame loop ({bvh})")
        speed.plot(x, [r["baseline_mrays_per_s"] for r in rows], ls, marker="s", color="C2",
                   label=f"bare rtcIntersect16 ({bvh})")
    mem.axhline(100, color="grey", lw=0.8, ls=":")
    mem.text(mem.get_xlim()[0], 101, " target at 1e8: 100 B/tri", fontsize="small", color="grey", va="bottom")
    for ax in (mem, speed):
        ax.set_xscale("log")
        ax.set_xlabel("triangles (procedural:spheres)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="x-small")
    mem.set_yscale("log")
    mem.set_ylabel("bytes per triangle")
    mem.set_title("memory (peak RSS: each size in its own process)")
    speed.set_ylabel("Mrays/s (median of timed frames)")
    speed.set_ylim(bottom=0)
    speed.set_title("throughput")
    fig.suptitle(f"{title}\n{c.get('cpu', '?')}; {c.get('threads')} threads, Embree {c.get('isa')}, "
                 f"{c.get('width')}x{c.get('height')}, AOVs {c.get('aovs')}", fontsize="medium")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"plot: wrote {out}")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--packet", nargs="*", default=[], metavar="[LABEL=]JSON")
    ap.add_argument("--threads", nargs="*", default=[], metavar="[LABEL=]JSON")
    ap.add_argument("-o", "--out", default=os.path.join(HERE, "plots", "sweeps.png"))
    ap.add_argument("--scaling", metavar="JSON", help="an aperture bench --scaling --json output")
    ap.add_argument("--title", default=None)
    args = ap.parse_args()
    if args.scaling:
        out = args.out if args.out != ap.get_default("out") else os.path.join(HERE, "plots", "scaling.png")
        return plot_scaling(args.scaling, out, args.title or "aperture: scaling to 1e8 triangles")
    if not args.packet and not args.threads:
        ap.error("give --packet and/or --threads JSON files, or --scaling JSON")
    args.title = args.title or "aperture: Mrays/s against packet width and threads"

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
