#!/usr/bin/env bash
# PDHG's work in `match -v` logs: one Markdown row per log with the number of PDHG solves, their
# iterations, their column-iterations (Σ columns × iterations, in 10⁹; bytes moved per iteration
# grow with the columns) and their seconds. Iteration totals taken from the info lines mix in
# Clp's simplex pivots (parts under RoundingOptions::exact_below, 30 000 columns), a pivot costing
# far less than a PDHG iteration (though 146 697 of them once took 5 minutes): compare these.
#   tools/pdhg_work.sh LOG...
set -euo pipefail
[ $# -gt 0 ] || { echo "usage: tools/pdhg_work.sh LOG..." >&2; exit 2; }
printf '| log | PDHG solves | iterations | column-iterations (10⁹) | PDHG seconds |\n|---|---|---|---|---|\n'
for log in "$@"; do
  [ -r "$log" ] || { echo "pdhg_work: cannot read $log" >&2; exit 1; }
  # "pdhg-…: ROWS x COLS, …" opens a solve; "pdhg-…: STATUS after N iterations … (S s)" ends it.
  awk -v name="$log" '
    / debug pdhg-[a-z0-9-]+: [0-9]+ x [0-9]+,/ {
      for (i = 1; i <= NF; ++i) if ($i == "x") { cols = $(i + 1); sub(/,$/, "", cols) }
    }
    / debug pdhg-[a-z0-9-]+: [a-z_]+ after [0-9]+ iterations/ {
      for (i = 1; i <= NF; ++i) if ($i == "after") it = $(i + 1)
      s = $(NF - 1); sub(/^\(/, "", s)
      solves++; iterations += it; work += cols * it; seconds += s
    }
    END {
      if (solves == 0) { printf "| %s | 0 (no debug lines: run match with -v) | | | |\n", name; exit }
      printf "| %s | %d | %d | %.2f | %.0f |\n", name, solves, iterations, work / 1e9, seconds
    }' "$log"
done
