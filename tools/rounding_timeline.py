#!/usr/bin/python3
"""Where a level's rounding spent its time, and what each release around a part cost.

    tools/rounding_timeline.py [--level L] LOG...   (the stderr of `shapematch match …`, one
                                                     run's sittings appended to one file)

Per log, level (or only level L) and attempt (a level's LP after each widening is a new attempt):
its rounds by outcome (optimal, at the iteration cap, infeasible, search) with their seconds
summed; the fewest free variables reached and after how many round-seconds; then every release
(a search's around the rest, or a part that failed again after trims), with the free variables
before and after it, its size (of how many fixings, within how many LP steps, where the log says),
and the round-seconds until the next release or the attempt's end with the fewest free variables
reached in them; and the lines where the rounding was called stuck or gave up.

Round-seconds are the rounds' own seconds summed: a sitting's set-up, checkpoints and the pauses
between sittings are not in them. A run is counted as if uninterrupted: where a sitting went on
from a checkpoint, the rounds the last sitting made after it (made again, or discarded with an
attempt the checkpoint did not hold) are dropped. Rounds are numbered as the level's attempt
numbers them (older binaries began again at 1 after a checkpoint: numbered on here). A log of a
single level (no "level N" in its lines) is read as level 1.
"""
import re
import sys

ROUND = re.compile(
    r"info (?:level (\d+) )?round +(\d+): +(\d+) variables(?: in \d+ parts)?, "
    r"(?:LP (\w+) in \d+ it|searched: )(.*)\(([\d.]+) s[,)]")
ATTEMPT = re.compile(r"info level (\d+)/\d+: ")
SITTING = re.compile(r"info going on from a checkpoint after level (\d+) of")
RESUMED = re.compile(r"info level (\d+): going on from its checkpointed attempt(?:.*its rounding after round (\d+))?")
RELEASE = re.compile(r"released (\d+)(?: of (\d+))? fixings(?: within (\d+) LP steps)? around")
PROOF_RELEASE = re.compile(r"released (\d+) fixings that the proofs of the rest rest on")
STUCK = re.compile(r"(?:info|warning) level (\d+): .*(stuck|release-reach-cap|gave up|did not reach a binary)")


class Attempt:
    def __init__(self):
        self.rounds = []   # (number, variables, kind, seconds, release or None)
        self.events = []   # (number of rounds before it, text)
        self.offset = 0    # added to the log's round numbers
        self.resumed_at = None  # a checkpoint's round this attempt went on after (until its next round)

    def add(self, n, variables, kind, seconds, release):
        if self.resumed_at is not None:
            # Older binaries numbered the rounds after a checkpoint from 1 again.
            self.offset = self.resumed_at if n == 1 and self.resumed_at > 0 else 0
            self.resumed_at = None
        elif self.rounds and n + self.offset <= self.rounds[-1][0]:
            self.offset = self.rounds[-1][0]  # (numbered from 1 again: a stuck restart, before 3b8ad36)
        self.rounds.append((n + self.offset, variables, kind, seconds, release))

    def go_on_after(self, number):
        self.rounds = [r for r in self.rounds if r[0] <= number]
        self.events = [e for e in self.events if e[0] <= len(self.rounds)]
        self.resumed_at = number


def timeline(path, only):
    levels = {}  # level -> [Attempt]
    resumed = None  # (level, round) from "going on from its checkpointed attempt"
    pending_drop = None  # a new sitting's levels done: its next attempt's level begins again unless resumed
    with open(path, errors="replace") as f:
        for line in f:
            m = SITTING.search(line)
            if m:  # a new sitting: what it does not go on from is redone (below)
                resumed = None
                pending_drop = int(m.group(1))
                continue
            m = RESUMED.search(line)
            if m:
                resumed = (int(m.group(1)), int(m.group(2) or 0))
                continue
            m = ATTEMPT.search(line)
            if m:
                level = int(m.group(1))
                attempts = levels.setdefault(level, [])
                if resumed and resumed[0] == level:
                    if not attempts:
                        attempts.append(Attempt())
                    attempts[-1].go_on_after(resumed[1])
                    resumed = None
                else:
                    if pending_drop is not None and level > pending_drop:
                        attempts.clear()  # (the checkpoint held no attempt of it: the level begun again)
                    attempts.append(Attempt())
                pending_drop = None
                continue
            m = STUCK.search(line)
            if m:
                level = int(m.group(1))
                if level in levels and levels[level]:
                    a = levels[level][-1]
                    a.events.append((len(a.rounds), line.split(" level ", 1)[1].strip()[:200]))
                continue
            m = ROUND.search(line)
            if not m:
                continue
            level = int(m.group(1) or 1)
            attempts = levels.setdefault(level, [])
            if not attempts:
                attempts.append(Attempt())
            kind = "search" if m.group(4) is None else m.group(4)
            rel = RELEASE.search(m.group(5)) or PROOF_RELEASE.search(m.group(5))
            release = None
            if rel:
                g = rel.groups() + (None, None)
                release = (int(g[0]), g[1], g[2], rel.re is PROOF_RELEASE)
            attempts[-1].add(int(m.group(2)), int(m.group(3)), kind, float(m.group(6)), release)
    if only is not None:
        levels = {k: v for k, v in levels.items() if k == only}
    return levels


def show(path, levels):
    for level, attempts in sorted(levels.items()):
        attempts = [a for a in attempts if a.rounds or a.events]
        total = sum(r[3] for a in attempts for r in a.rounds)
        print(f"{path}, level {level}: {len(attempts)} attempt(s) with rounds, "
              f"{sum(len(a.rounds) for a in attempts)} rounds, {total / 3600:.2f} h of round-seconds")
        for k, a in enumerate(attempts, 1):
            secs = [r[3] for r in a.rounds]
            print(f"  attempt {k}: {len(a.rounds)} rounds, {sum(secs) / 3600:.2f} h")
            by = {}
            for r in a.rounds:
                c, s = by.get(r[2], (0, 0.0))
                by[r[2]] = (c + 1, s + r[3])
            for kind, (c, s) in sorted(by.items()):
                print(f"    {kind:16} {c:5} rounds  {s / 3600:6.2f} h")
            elapsed, fewest = 0.0, None
            for r in a.rounds:
                if fewest is None or r[1] < fewest[0]:
                    fewest = (r[1], elapsed, r[0])
                elapsed += r[3]
            if fewest:
                print(f"    fewest free variables {fewest[0]} at round {fewest[2]} (after {fewest[1] / 3600:.2f} h)")
            at = 0.0
            for i, r in enumerate(a.rounds):
                at += r[3]
                if not r[4]:
                    continue
                released, pool, depth, by_proofs = r[4]
                nxt = next((j for j in range(i + 1, len(a.rounds)) if a.rounds[j][4]), len(a.rounds))
                after = a.rounds[i + 1][1] if i + 1 < len(a.rounds) else "-"
                since = min((a.rounds[j][1] for j in range(i + 1, nxt)), default="-")
                span = sum(a.rounds[j][3] for j in range(i + 1, nxt))
                size = f"{released}" + (f" of {pool}" if pool else "") + \
                       (f" within {depth} LP steps" if depth else "") + (" (by proofs)" if by_proofs else "")
                print(f"    release at round {r[0]} ({at / 3600:.2f} h): {size}; free {r[1]} -> {after}; "
                      f"then {span / 3600:.2f} h, fewest since {since}")
            for n, what in a.events:
                print(f"    after {n} rounds: {what}")


def main(argv):
    only = None
    if len(argv) >= 2 and argv[0] == "--level":
        only = int(argv[1])
        argv = argv[2:]
    if not argv:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    for path in argv:
        show(path, timeline(path, only))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
