#!/usr/bin/python3
"""Where a level's rounding spent its time, and what each release around a part cost.

    tools/rounding_timeline.py [--level L] LOG...   (the stderr of `shapematch match …`, one
                                                     run's sittings appended to one file)

Per log and level (or only level L): its rounds by outcome (optimal, at the iteration cap,
infeasible, search) with their seconds summed; the fewest free variables reached and after how
many round-seconds; then every release (a search's around the rest, or a part that failed again
after trims), with the free variables before and after it, its size (of how many fixings, within
how many LP steps, where the log says), and what came after it: the round-seconds until the
next release or the end, and the fewest free variables reached in them. Round-seconds are the
rounds' own seconds summed (a sitting's set-up, checkpoints and pauses between sittings are not
in them), so runs that were paused compare fairly. A new attempt of the level (a widening)
starts its rounds' count again; its rounds are counted on in the same table.
"""
import re
import sys

ROUND = re.compile(
    r"info level (\d+) round +(\d+): +(\d+) variables(?: in \d+ parts)?, "
    r"(?:LP (\w+) in \d+ it|searched: )(.*)\(([\d.]+) s[,)]")
RELEASE = re.compile(r"released (\d+)(?: of (\d+))? fixings(?: within (\d+) LP steps)? around")
PROOF_RELEASE = re.compile(r"released (\d+) fixings that the proofs of the rest rest on")
STUCK = re.compile(r"info level (\d+): .*(stuck|release-reach-cap)")


def timeline(path, only):
    levels = {}
    with open(path, errors="replace") as f:
        for line in f:
            m = ROUND.search(line)
            if not m:
                s = STUCK.search(line)
                if s and (only is None or int(s.group(1)) == only):
                    lv = levels.setdefault(int(s.group(1)), new_level())
                    lv["events"].append((lv["seconds"], "stuck: " + line.split("info ", 1)[1].strip()[:160]))
                continue
            level, variables, status, rest, seconds = int(m.group(1)), int(m.group(3)), m.group(4), m.group(5), float(m.group(6))
            if only is not None and level != only:
                continue
            lv = levels.setdefault(level, new_level())
            kind = "search" if status is None else status
            count, secs = lv["by"].get(kind, (0, 0.0))
            lv["by"][kind] = (count + 1, secs + seconds)
            before = lv["seconds"]
            lv["seconds"] += seconds
            lv["rounds"] += 1
            if variables < lv["fewest"][0]:
                lv["fewest"] = (variables, before)
            if lv["releases"]:
                r = lv["releases"][-1]
                if r["after"] is None:
                    r["after"] = variables
                r["fewest_since"] = min(r["fewest_since"], variables)
            rel = RELEASE.search(rest) or PROOF_RELEASE.search(rest)
            if rel:
                groups = rel.groups() + (None,) * (3 - len(rel.groups()))
                lv["releases"].append({
                    "round": lv["rounds"], "at": lv["seconds"], "before": variables, "after": None,
                    "released": int(groups[0]), "pool": groups[1], "depth": groups[2],
                    "by_proofs": rel.re is PROOF_RELEASE, "fewest_since": float("inf")})
    return levels


def new_level():
    return {"by": {}, "seconds": 0.0, "rounds": 0, "fewest": (float("inf"), 0.0), "releases": [], "events": []}


def show(path, levels):
    for level, lv in sorted(levels.items()):
        print(f"{path}, level {level}: {lv['rounds']} rounds, {lv['seconds'] / 3600:.2f} h of round-seconds")
        for kind, (count, secs) in sorted(lv["by"].items()):
            print(f"  {kind:16} {count:5} rounds  {secs / 3600:6.2f} h")
        fewest, at = lv["fewest"]
        if lv["rounds"]:
            print(f"  fewest free variables {fewest} after {at / 3600:.2f} h")
        ends = [r["at"] for r in lv["releases"][1:]] + [lv["seconds"]]
        for r, end in zip(lv["releases"], ends):
            size = f"{r['released']}" + (f" of {r['pool']}" if r["pool"] else "") + \
                   (f" within {r['depth']} LP steps" if r["depth"] else "") + (" (by proofs)" if r["by_proofs"] else "")
            after = r["after"] if r["after"] is not None else "-"
            since = r["fewest_since"] if r["fewest_since"] != float("inf") else "-"
            print(f"  release at round {r['round']} ({r['at'] / 3600:.2f} h): {size}; free {r['before']} -> {after}; "
                  f"then {(end - r['at']) / 3600:.2f} h, fewest since {since}")
        for at, what in lv["events"]:
            print(f"  at {at / 3600:.2f} h: {what}")


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
