#!/usr/bin/env python3
"""Pareto plot of an `aperture tradeoff` CSV: cost (frame + EXR write, ms) against error
(RMSE of color vs the 256-spp reference), one point per setting, the non-dominated settings
(the CSV's `pareto` column) marked and labelled.

    /usr/bin/python3 bench/pareto.py bench/tradeoff/crown-thinlens.csv -o bench/plots/tradeoff-crown-thinlens.png

Needs matplotlib (Debian python3-matplotlib, installed by bench/install-peers.sh).
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--title")
    a = ap.parse_args()
    rows = list(csv.DictReader(open(a.csv)))
    fig, ax = plt.subplots(figsize=(9, 5.5))
    knobs = sorted({r["knob"] for r in rows})
    for knob in knobs:
        pts = [r for r in rows if r["knob"] == knob]
        ax.scatter([1e3 * float(r["cost_s"]) for r in pts], [float(r["rmse"]) for r in pts],
                   label=knob, s=28, alpha=0.8)
    front = sorted((r for r in rows if r["pareto"] == "1"), key=lambda r: float(r["cost_s"]))
    ax.plot([1e3 * float(r["cost_s"]) for r in front], [float(r["rmse"]) for r in front],
            "k--", lw=1, label="Pareto frontier")
    for r in front:
        ax.annotate(f'{r["knob"]} {r["value"]}', (1e3 * float(r["cost_s"]), float(r["rmse"])),
                    fontsize=7, xytext=(4, 4), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cost per frame: render + EXR write (ms, log)")
    ax.set_ylabel("RMSE of color against the 256-spp reference (log)")
    ax.set_title(a.title or os.path.splitext(os.path.basename(a.csv))[0])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    fig.savefig(a.out, dpi=110)
    print(f"pareto: wrote {a.out}")


if __name__ == "__main__":
    main()
