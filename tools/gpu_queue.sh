#!/usr/bin/env bash
# Packs a queue of full-resolution matches for a lent GPU machine (docs/benchmarks.md, "A queue of
# pairs on a lent GPU"): the Release binary with the libraries it needs beyond glibc, the pairs'
# files (copied, never committed: keep DIR ignored), one pairs file per job and a runner.
#   tools/gpu_queue.sh PAIRS [on|off|both] [DIR] [-- MATCH-ARGS...]
# PAIRS: lines as for `bench match --pairs` (tools/make_pairs.sh). on/off/both: WKS (default on).
# DIR: default .dev. MATCH-ARGS replace the defaults below (the tables' command) for every job.
# On the machine: `cp -r DIR /root/q && cd /root/q && LIMIT=515 P=10 ./q.sh` (q.sh says more).
set -euo pipefail
pairs=$1
wks=${2:-on}
dir=${3:-.dev}
shift $(($# < 3 ? $# : 3))
[ "${1:-}" = "--" ] && shift
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--levels 6 --tol 3e-3 --greedy-above 200000 --later-round-iterations 1 --max-rounds 200)
case $wks in on | off | both) ;; *) echo "gpu_queue: WKS must be on, off or both, not '$wks'" >&2; exit 2 ;; esac
bin=${SHAPEMATCH:-build/shapematch}
[ -x "$bin" ] || { echo "gpu_queue: no binary at $bin (build Release first)" >&2; exit 2; }

mkdir -p "$dir/lib" "$dir/data" "$dir/pairs"
cp "$bin" "$dir/shapematch"
# Everything ldd resolves except glibc's own and the Vulkan loader (the machine brings its own).
ldd "$bin" | awk '$3 ~ /^\// {print $3}' | while read -r lib; do
  case $(basename "$lib") in
    libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux* | libvulkan.so*) ;;
    *) cp -L "$lib" "$dir/lib/" ;;
  esac
done

: > "$dir/jobs.txt"
n=0
while read -r line; do
  [ -n "$line" ] || continue
  n=$((n + 1))
  set -- $line
  name=$(printf '%02d-%s-%s' "$n" "$(basename "${1%.*}")" "$(basename "${2%.*}")")
  mkdir -p "$dir/data/$name"
  out=()
  for field in "$@"; do
    if [ -f "$field" ]; then
      cp "$field" "$dir/data/$name/"
      out+=("../data/$name/$(basename "$field")")
    else
      out+=("$field")  # identity, map
    fi
  done
  echo "${out[*]}" > "$dir/pairs/$name.txt"
  case $wks in
    both) printf '%s on\n%s off\n' "$name" "$name" >> "$dir/jobs.txt" ;;
    *) echo "$name $wks" >> "$dir/jobs.txt" ;;
  esac
done < "$pairs"

printf '%s\n' "${args[@]}" > "$dir/match_args.txt"
cat > "$dir/q.sh" <<'EOF'
#!/bin/bash
# Runs the jobs of jobs.txt (or $JOBS), P at once, each `bench match` of one pair with the options
# of match_args.txt and --backend $BACKEND (vulkan; cpu where no NVIDIA device shows) at FACES faces
# (full), THREADS threads each (default nproc / P), stopped LIMIT seconds after the queue starts;
# then packs logs, tables, results and checkpoints (no meshes) into $OUT/q.txz (also every PACK
# seconds, 60, on the way: a call killed at its limit brings back the latest). Run it from a
# folder outside the checkout (a later call would replace an ignored folder it does not carry).
# Runs go on where an earlier call stopped (bench match --resume): unpack its q.txz here first.
LIMIT=${LIMIT:-515}; P=${P:-8}; BACKEND=${BACKEND:-vulkan}; FACES=${FACES:-full}
# Each run's share of the cores: P runs of all threads each leave the host oversubscribed and the
# GPU waiting (thirty-third session: one thread each was 6.5 % faster than sixteen, 11 at once).
THREADS=${THREADS:-$(( $(nproc) / P > 0 ? $(nproc) / P : 1 ))}
export LD_LIBRARY_PATH=$PWD/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
mkdir -p out log
{ date; nproc; free -g | head -2; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1; } > log/machine.txt
./shapematch devices > log/devices.txt 2>&1
if [ "$BACKEND" = vulkan ] && ! grep -q "0: NVIDIA" log/devices.txt; then
  echo "no NVIDIA device: cpu backend" >> log/machine.txt
  BACKEND=cpu
fi
(while true; do { date +%T; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv,noheader 2>&1; uptime; } >> log/smi.txt; sleep 30; done) &
SMI=$!
# Packs logs, tables, results and checkpoints (no meshes) into $OUT/q.txz, with one line per
# unfinished run's checkpoint (levels done, the attempt and its rounding) in log/checkpoints.txt.
pack() {
  cat out/*/bench_pairs.md > log/tables.md 2>/dev/null
  for c in out/*/runs/*.ckpt; do [ -f "$c" ] && echo "$c $(./shapematch checkpoint "$c" | tr -d ' \n')"; done > log/checkpoints.txt 2>&1
  # (tar's status 1: a file changed or went while it read, as the runs' logs and checkpoints do.)
  tar cJf "${OUT:-/tmp}/q.part.txz" --warning=no-file-changed --warning=no-file-removed --exclude='*.ply' \
    --exclude='*.png' --exclude=levels log out 2>/dev/null
  [ $? -le 1 ] && mv -f "${OUT:-/tmp}/q.part.txz" "${OUT:-/tmp}/q.txz"
}
# Every PACK seconds too: a call killed at its own limit (a LIMIT too long for it) still brings
# back the latest checkpoints (sixty-sixth session: one killed before its only pack brought none).
rm -f .stop
(renice -n 19 $BASHPID > /dev/null; export XZ_OPT=-1  # beside the timed runs: the spare cycles only
 n=0; while [ ! -e .stop ]; do sleep 5; n=$((n + 5)); [ "$n" -ge "${PACK:-60}" ] && { pack; n=0; }; done) &
PACKER=$!
# A job line: NAME on|off [TAG MATCH-ARGS...]: a TAG names a variant with options of its own
# (added by hand, e.g. `03-024-043 on ring2 --ring 2`), so that one call compares them.
run1() {
  local n=$1 w=$2 tag=${3:-} extra=()
  [ "$w" = off ] && extra=(--wks off)
  [ $# -gt 3 ] && extra+=("${@:4}")
  local id=$n-$w${tag:+-$tag}
  # A job that starts late (a slot freed by a short one) gets what is left of LIMIT, so that it
  # still ends as "timed out" with its record and checkpoint, not killed with the queue.
  local left=$((DEADLINE - $(date +%s)))
  if [ "$left" -lt 30 ]; then echo "$id not started (${left} s left)" >> log/done.txt; return; fi
  # (The jobs that start at once all get LIMIT: under a shorter limit than its last call's,
  # --resume runs a timed-out pair again only where that call got its checkpoint further.)
  [ "$left" -ge $((LIMIT - 5)) ] && left=$LIMIT
  mapfile -t margs < match_args.txt
  ./shapematch bench match --pairs "pairs/$n.txt" --faces "$FACES" --time-limit "$left" --out "out/$id" --resume -- \
    "${margs[@]}" --backend "$BACKEND" --threads "$THREADS" "${extra[@]}" >> "log/$id.bench.log" 2>&1
  echo "$id exit $? at $(date +%T)" >> log/done.txt
}
export -f run1
DEADLINE=$(($(date +%s) + LIMIT))
export LIMIT DEADLINE BACKEND FACES THREADS
timeout $((LIMIT + 45)) xargs -P "$P" -L 1 bash -c 'run1 "$@"' _ < "${JOBS:-jobs.txt}"
kill $SMI
touch .stop; wait $PACKER  # (not killed: it may be halfway through a pack)
pack
ls -la "${OUT:-/tmp}/q.txz"
EOF
chmod +x "$dir/q.sh"
echo "gpu_queue: $(wc -l < "$dir/jobs.txt") jobs in $dir ($(du -sh "$dir" | cut -f1))"
