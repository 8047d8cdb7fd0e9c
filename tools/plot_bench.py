#!/usr/bin/python3
"""Plots the CSV of `shapematch bench lp` like Fig. 4 of Windheuser et al. 2011: LP solve time
against the number of variables, log-log, one line per solver; runs that hit their time limit
are marked "timed out" (their time is a lower bound, so they are not joined to the line).

Usage: /usr/bin/python3 tools/plot_bench.py BENCH.csv OUT.png  (needs python3-matplotlib)
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")  # benchmark machines have no display
import matplotlib.pyplot as plt  # noqa: E402

TIMED_OUT = {"time_limit", "killed"}


def main(csv_path, png_path):
    by_solver = {}
    with open(csv_path, newline="") as f:
        for row in csv.DictReader(f):
            by_solver.setdefault(row["solver"], []).append(row)

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    marked_timeout = False
    for i, (solver, rows) in enumerate(by_solver.items()):
        color = colors[i % len(colors)]
        solved = [(int(r["variables"]), float(r["seconds"])) for r in rows if r["status"] == "optimal"]
        late = [(int(r["variables"]), float(r["seconds"])) for r in rows if r["status"] in TIMED_OUT]
        if solved:
            ax.plot(*zip(*solved), marker="o", color=color, label=solver)
        if late:
            ax.plot(*zip(*late), linestyle="none", marker="x", markersize=10, markeredgewidth=2, color=color,
                    label=None if solved else solver)
            for n, t in late:
                ax.annotate("timed out", (n, t), textcoords="offset points", xytext=(6, 4), fontsize=8, color=color)
            marked_timeout = True
    if marked_timeout:
        ax.plot([], [], linestyle="none", marker="x", color="black", label="timed out")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("variables")
    ax.set_ylabel("seconds to solve the LP relaxation")
    ax.set_title("Matching LP: solve time against size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    # Written to a temporary name and renamed, like every output of shapematch.
    tmp = png_path + ".tmp"
    fig.savefig(tmp, format="png", dpi=120)
    os.replace(tmp, png_path)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip())
    main(sys.argv[1], sys.argv[2])
