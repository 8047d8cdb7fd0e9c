#!/usr/bin/env bash
# Solves each dumped LP (`match --dump-first-lps DIR`) once per starting primal weight ω₀ and
# prints one Markdown row per LP: its size, then PDHG's iterations (and seconds) at each ω₀.
#   tools/lp_sweep.sh DIR [OMEGAS] [-- LP-ARGS...]
# OMEGAS: space-separated, default "1 10 30 100". LP-ARGS: passed to every `shapematch lp`
# (default: --solver pdhg-cpu --tol 1e-3 --threads 1). SHAPEMATCH: the binary (build/shapematch).
set -euo pipefail
dir=$1
omegas=${2:-1 10 30 100}
shift $(($# < 2 ? $# : 2))
[ "${1:-}" = "--" ] && shift
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--solver pdhg-cpu --tol 1e-3 --threads 1)
bin=${SHAPEMATCH:-build/shapematch}
[ -x "$bin" ] || { echo "lp_sweep: no binary at $bin" >&2; exit 2; }
field() { sed -n "s/.*\"$1\": \"\{0,1\}\([^,\"}]*\).*/\1/p"; }

printf '| LP | columns |'
for w in $omegas; do printf ' ω₀ = %s |' "$w"; done
printf '\n|---|---|'
for _ in $omegas; do printf -- '---|'; done
printf '\n'
for f in "$dir"/*.smlp; do
  columns=? cells=
  for w in $omegas; do
    json=$("$bin" lp --from "$f" --initial-primal-weight "$w" "${args[@]}" 2>/dev/null) || true
    [ -n "$json" ] || { cells="$cells failed |"; continue; }
    columns=$(field variables <<<"$json")
    cells="$cells $(field iterations <<<"$json") $(field status <<<"$json") ($(printf '%.1f' "$(field seconds <<<"$json")") s) |"
  done
  echo "| $(basename "$f" .smlp) | $columns |$cells"
done
