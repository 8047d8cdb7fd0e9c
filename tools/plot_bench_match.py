#!/usr/bin/python3
"""Plots the CSV of `shapematch bench match` (scaling mode): wall time and peak memory of whole
match runs against faces per shape, log-log. A dashed line marks the target of the
coarse-to-fine issue, doubling the faces costs 2.5x the time (slope log2 2.5 = 1.32); runs that
were killed at the time limit are crosses (their time and memory are lower bounds, so they are not
joined to the line).

Usage: /usr/bin/python3 tools/plot_bench_match.py BENCH_MATCH.csv OUT.png  (needs python3-matplotlib)
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")  # benchmark machines have no display
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter  # noqa: E402

TARGET_SLOPE = math.log2(2.5)


def faces_of(row):
    """Faces per shape: the mean of both meshes as matched, else the count asked for (a run that
    was killed never reported its meshes); None for an unfinished `full` run."""
    if row["faces_x"] and row["faces_y"]:
        return (int(row["faces_x"]) + int(row["faces_y"])) / 2
    return int(row["faces_requested"]) if row["faces_requested"].isdigit() else None


def main(csv_path, png_path):
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    ok = [r for r in rows if r["status"] == "ok" and r["seconds"]]
    late = [r for r in rows if r["status"] == "timed out" and faces_of(r) is not None]

    fig, (ax_time, ax_mem) = plt.subplots(1, 2, figsize=(10, 4.2))
    for ax, column, label in ((ax_time, "seconds", "wall seconds of `match`"),
                              (ax_mem, "peak_rss_mb", "peak memory (MiB)")):
        if ok:
            ax.plot([faces_of(r) for r in ok], [float(r[column]) for r in ok], marker="o", label="ok")
        if late:
            ax.plot([faces_of(r) for r in late], [float(r[column]) for r in late], linestyle="none", marker="x",
                    markersize=10, markeredgewidth=2, color="tab:red", label="timed out")
        ax.set_xscale("log")
        ax.set_yscale("log")
        # Plain numbers at 1, 2, 5 per decade: a benchmark spans one or two decades, where
        # powers of ten alone leave an axis without labels.
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("faces per shape")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)

    if ok:
        # Through the smallest run, across every size measured.
        n0, t0 = faces_of(ok[0]), float(ok[0]["seconds"])
        xs = [faces_of(r) for r in ok + late]
        lo, hi = min(xs), max(xs)
        if lo == hi:
            lo, hi = lo / 2, hi * 2
        ax_time.plot([lo, hi], [t0 * (lo / n0) ** TARGET_SLOPE, t0 * (hi / n0) ** TARGET_SLOPE], linestyle="--",
                     color="gray", label="target: 2.5x time per doubling")
    # The sizes measured as the x ticks: they are what a reader looks up.
    sizes = sorted({faces_of(r) for r in ok + late})
    for ax in (ax_time, ax_mem):
        if sizes:
            ax.set_xticks(sizes)
    ax_time.set_title("time")
    ax_mem.set_title("memory")
    for ax in (ax_time, ax_mem):
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.suptitle("shapematch match: scaling with mesh size")
    fig.tight_layout()
    # Written to a temporary name and renamed, like every output of shapematch.
    tmp = png_path + ".tmp"
    fig.savefig(tmp, format="png", dpi=120)
    os.replace(tmp, png_path)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip())
    main(sys.argv[1], sys.argv[2])
