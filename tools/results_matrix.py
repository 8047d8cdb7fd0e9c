#!/usr/bin/python3
"""Every test pair at a glance: reads the rows of docs/results.md's full-resolution table and
writes, for each test pair of the data sets, the newest row of each setting (WKS on or off,
feature weight mu, curvature radius R) as one line of a Markdown table, then how many pairs the
defaults have covered.

    tools/results_matrix.py [--update] [RESULTS_MD] [DATASETS]
        (defaults: docs/results.md, ../shared/datasets)

With --update the table between the markers `<!-- matrix begin -->` and `<!-- matrix end -->` in
RESULTS_MD is replaced; otherwise it is printed. Only the data sets' pair lists are read.
Only the table after the heading "### Every run" is read. A row's setting is read from its first
cell: "R = …" or `--curvature-radius …` (else 0.05 from the thirty-fourth session on, when it
became the default, 0 before) and "μ = …" (else 10 from the forty-fourth on, 1 before); its
session is the last number of its session cell (where it finished).
"""
import os
import re
import statistics
import sys

BEGIN, END = "<!-- matrix begin -->", "<!-- matrix end -->"
# (WKS, R, mu) per column, the defaults first.
COLUMNS = [
    (("on", "0.05", "10"), "WKS, μ = 10, R = 0.05 (the defaults)"),
    (("on", "0.05", "1"), "WKS, μ = 1, R = 0.05"),
    (("off", "0.05", "1"), "no WKS, R = 0.05"),
    (("on", "0", "1"), "WKS, μ = 1, R = 0"),
    (("off", "0", "1"), "no WKS, R = 0"),
]
DEFORMATION_TRANSFER = [
    "deformation transfer cat 0002–0009",
    "deformation transfer cat 0001–0005",
    "deformation transfer horse 1–4",
    "deformation transfer horse gallop 0001–0017",
]


def ordinal(n):
    suffix = "th" if 11 <= n % 100 <= 13 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def test_pairs(datasets):
    def read(path):
        with open(path) as f:
            return [line.split() for line in f if line.strip()]

    pairs = [("FAUST_r", f"FAUST_r {a[-3:]}–{b[-3:]}")
             for a, b in read(os.path.join(datasets, "faust_r_bcicp", "test_pairs_included.txt"))]
    pairs += [("TOSCA_r", f"TOSCA_r {a}–{b}")
              for a, b in read(os.path.join(datasets, "tosca_r_bcicp", "isometric", "test_pairs_included.txt"))]
    pairs += [("deformation transfer", p) for p in DEFORMATION_TRANSFER]
    return pairs


def table_rows(text):
    if "### Every run" in text:
        text = text.split("### Every run", 1)[1]
    for line in text.split("\n"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("| ") or len(cells) != 10 or not re.search(r"\d+", cells[2]):
            continue
        yield cells


def newest_rows(text, names):
    best = {}
    for cells in table_rows(text):
        first, wks, session = cells[0], cells[1], int(re.findall(r"\d+", cells[2])[-1])
        name = next((n for n in names if first.startswith(n) and first[len(n):len(n) + 1] in ("", ",", " ")), None)
        error = re.match(r"\**([\d.]+)", cells[8])
        flips = re.match(r"(\d+) \((\d+)\)", cells[9])
        if name is None or error is None or flips is None:
            continue
        stated_r = re.search(r"(?:R = |curvature-radius )(\d+(?:\.\d+)?)", first)
        r = format(float(stated_r.group(1)), "g") if stated_r else "0.05" if session >= 34 else "0"
        stated_mu = re.search(r"μ = (\d+(?:\.\d+)?)", first)
        mu = format(float(stated_mu.group(1)), "g") if stated_mu else "10" if session >= 44 else "1"
        if wks == "off":
            mu = "1"  # no features: μ weighs nothing (the column stands for every μ)
        key = (name, (wks, r, mu))
        if key not in best or session >= best[key]["session"]:
            best[key] = {"session": session, "error": float(error.group(1)), "vertex": int(flips.group(1)),
                         "point": int(flips.group(2))}
    return best


def matrix(text, datasets):
    pairs = test_pairs(datasets)
    best = newest_rows(text, [name for _, name in pairs])
    out = ["| pair | " + " | ".join(title for _, title in COLUMNS) + " |",
           "|---" * (len(COLUMNS) + 1) + "|"]
    for _, name in pairs:
        cells = []
        for setting, _ in COLUMNS:
            row = best.get((name, setting))
            cells.append("" if row is None else
                         f"{row['error']:.4f} · {row['vertex']} ({row['point']}) · {ordinal(row['session'])}")
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    out.append("")
    defaults = COLUMNS[0][0]
    for group in ("FAUST_r", "TOSCA_r", "deformation transfer"):
        names = [name for g, name in pairs if g == group]
        rows = [best[(n, defaults)] for n in names if (n, defaults) in best]
        if not rows:
            continue
        errors = [r["error"] for r in rows]
        out.append(f"- {group} at the defaults: {len(rows)} of {len(names)} pairs, mean error "
                   f"{statistics.mean(errors):.4f}, largest {max(errors):.4f}, "
                   f"{sum(r['error'] <= 0.03 for r in rows)} at or under 0.03, point maps flipping "
                   f"{sum(r['point'] for r in rows)} faces in all.")
    return "\n".join(out)


def main(argv):
    update = "--update" in argv
    args = [a for a in argv if a != "--update"]
    results = args[0] if args else "docs/results.md"
    datasets = args[1] if len(args) > 1 else "../shared/datasets"
    with open(results) as f:
        text = f.read()
    table = matrix(text, datasets)
    if not update:
        print(table)
        return 0
    if BEGIN not in text or END not in text:
        print(f"{results}: no {BEGIN} … {END} markers", file=sys.stderr)
        return 1
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(results, "w") as f:
        f.write(head + BEGIN + "\n" + table + "\n" + END + tail)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
