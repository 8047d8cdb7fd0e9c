#!/usr/bin/python3
"""How often the LP after a greedy rounding round is infeasible, by what that round's filter kept.

    tools/greedy_rounds.py LOG...      (the stderr of `shapematch -v match …`)

A greedy round (more free variables than --greedy-above) fixes only candidates that stand away
from the LP's undecided part: first variables in (0.1, 0.9), then, where under a quarter of the
batch is left, (0.3, 0.7); where none is left then, the largest candidate of each undecided
region, at most the --greedy-fallback share (the whole batch with a share of 1). For each such
round followed by another round of its level, this counts the rounds by that outcome and by
whether the round's own LP was optimal or stopped at its cap, and how many of them the next LP
found infeasible.
"""
import re
import sys

FILTER = re.compile(r"rounding: (\d+) of (\d+) candidates stand away from variables in \(([\d.]+),")
ROUND = re.compile(r"info level (\d+) round +(\d+):.*LP (\w+) in")


def tally(paths):
    counts = {}
    for path in paths:
        with open(path, errors="replace") as f:
            lines = f.read().split("\n")
        rounds = [(i, ROUND.search(line)) for i, line in enumerate(lines)]
        rounds = [(i, m) for i, m in rounds if m]
        for k in range(len(rounds) - 1):
            start = rounds[k - 1][0] if k > 0 else 0
            end, this = rounds[k]
            filters = [FILTER.search(line) for line in lines[start:end]]
            filters = [m for m in filters if m]
            if not filters:
                continue
            kept, band = int(filters[-1].group(1)), filters[-1].group(3)
            outcome = "none stood away" if kept == 0 else f"stood away from ({band}, {1 - float(band):g})"
            after = rounds[k + 1][1]
            if after.group(1) != this.group(1) or int(after.group(2)) != int(this.group(2)) + 1:
                continue
            key = (outcome, "optimal" if this.group(3) == "optimal" else "at its cap")
            total, infeasible = counts.get(key, (0, 0))
            counts[key] = (total + 1, infeasible + (after.group(3) == "infeasible"))
    return counts


def main(paths):
    if not paths:
        print(__doc__, file=sys.stderr)
        return 2
    print("| the round's candidates | its LP | rounds | next LP infeasible |")
    print("|---|---|---|---|")
    for (outcome, lp), (total, infeasible) in sorted(tally(paths).items()):
        print(f"| {outcome} | {lp} | {total} | {infeasible} ({100 * infeasible / total:.0f} %) |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
