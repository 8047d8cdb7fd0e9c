#!/usr/bin/python3
"""What the later rounds' zero-cost pre-test (--feasibility-later) costs and proves.

    tools/pretest_rounds.py LOG...      (the stderr of `shapematch -v match …`)

Each later round solves every changed part at zero cost first, cold, up to the cap; a later
round's seconds include those solves. Per log, over the later rounds of the finest level (those
over 300 s left out: a run paused or stopped in them): their seconds, the pre-tests' share, the
rounds the pre-test proved infeasible, and the feasible rounds' pre-test seconds (spent without
a verdict); then how many iterations the proofs took.
"""
import re
import sys

PRETEST = re.compile(r"at zero cost: (\w+) in (\d+) iterations \(([\d.]+) s\)")
PROVED = "proved infeasible at zero cost, no costed solve"
ROUND = re.compile(r"info level (\d+) round +(\d+): .* LP (\w+) in \d+ it.*\(([\d.]+) s\)$")


def rounds_of(path):
    rounds, pre, proved = [], 0.0, False
    proofs = []
    with open(path, errors="replace") as f:
        for line in f:
            m = PRETEST.search(line)
            if m:
                pre += float(m.group(3))
                if m.group(1) == "infeasible":
                    proofs.append(int(m.group(2)))
            if PROVED in line:
                proved = True
            m = ROUND.search(line.strip())
            if m:
                rounds.append((int(m.group(1)), int(m.group(2)), m.group(3), pre, proved, float(m.group(4))))
                pre, proved = 0.0, False
    finest = max((r[0] for r in rounds), default=0)
    return [r for r in rounds if r[0] == finest and r[1] > 1 and r[5] < 300.0], proofs


def main(paths):
    all_proofs = []
    for path in paths:
        rounds, proofs = rounds_of(path)
        all_proofs += proofs
        total = sum(r[5] for r in rounds)
        pre = sum(r[3] for r in rounds)
        feasible = [r for r in rounds if r[2] in ("optimal", "iteration_limit")]
        print(f"{path}: {len(rounds)} later rounds, {total:.0f} s, pre-tests {pre:.0f} s "
              f"({100.0 * pre / total if total else 0.0:.0f} %); proved infeasible {sum(r[4] for r in rounds)}, "
              f"infeasible otherwise {sum(not r[4] and r[2] not in ('optimal', 'iteration_limit') for r in rounds)}; "
              f"feasible {len(feasible)}, their pre-tests {sum(r[3] for r in feasible):.0f} s of "
              f"{sum(r[5] for r in feasible):.0f} s")
    if all_proofs:
        for cap in (1024, 2048, 4096):
            print(f"proofs within {cap} iterations: {sum(k <= cap for k in all_proofs)} of {len(all_proofs)}")
        print(f"slowest proof: {max(all_proofs)} iterations")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
