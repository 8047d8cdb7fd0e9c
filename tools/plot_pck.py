#!/usr/bin/python3
"""Plots the PCK curve written by `shapematch eval --pck-csv`: the fraction of ground-truth points
whose geodesic error (in units of sqrt(area of Y)) is at most the threshold, with its normalised
area under the curve in the legend.

Usage: /usr/bin/python3 tools/plot_pck.py PCK.csv OUT.png [LABEL]  (needs python3-matplotlib)
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")  # evaluation machines have no display
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path, png_path, label):
    with open(csv_path, newline="") as f:
        rows = [(float(r["threshold"]), float(r["fraction"])) for r in csv.DictReader(f)]
    if not rows:
        sys.exit(f"{csv_path}: no rows")
    thresholds, fractions = zip(*rows)
    width = thresholds[-1] - thresholds[0]
    area = sum((t1 - t0) * (f0 + f1) / 2 for (t0, f0), (t1, f1) in zip(rows, rows[1:]))
    auc = area / width if width > 0 else fractions[0]

    fig, ax = plt.subplots(figsize=(5.6, 4.2))
    ax.plot(thresholds, fractions, marker=".", label=f"{label} (AUC {auc:.3f})")
    ax.set_xlim(thresholds[0], thresholds[-1])
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("geodesic error / sqrt(area of Y)")
    ax.set_ylabel("fraction of correspondences")
    ax.set_title("Correspondence accuracy (PCK)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    # Written to a temporary name and renamed, like every output of shapematch.
    tmp = png_path + ".tmp"
    fig.savefig(tmp, format="png", dpi=120)
    os.replace(tmp, png_path)


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__.strip())
    main(sys.argv[1], sys.argv[2], sys.argv[3] if len(sys.argv) == 4 else "shapematch")
