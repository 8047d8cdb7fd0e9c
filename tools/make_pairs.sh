#!/usr/bin/env bash
# Writes the pairs files of docs/results.md's tables (`shapematch bench match --pairs FILE`) from
# the data sets' own test-pair lists, so that nothing of the data sets is kept in this repository.
#   tools/make_pairs.sh [DATASETS] [OUT]     (defaults: ../shared/datasets, ./pairs)
# Writes OUT/faust_r_test.txt (the 15 FAUST_r test pairs, symmetric truth), OUT/tosca_r_test.txt
# (the 21 TOSCA_r isometric test pairs) and OUT/deformation_transfer.txt (cat and horse pose
# pairs, identity truth; match them with --close-holes), with absolute paths.
set -euo pipefail
data=$(cd "${1:-../shared/datasets}" && pwd)
out=${2:-pairs}
mkdir -p "$out"

faust=$data/faust_r_bcicp
while read -r a b; do
  [ -n "$a" ] || continue
  echo "$faust/off/$a.off $faust/off/$b.off $faust/corres/$a.vts $faust/corres/$b.vts $faust/corres/$b.sym.vts"
done < "$faust/test_pairs_included.txt" > "$out/faust_r_test.txt"

tosca=$data/tosca_r_bcicp/isometric
while read -r a b; do
  [ -n "$a" ] || continue
  echo "$tosca/off/$a.off $tosca/off/$b.off $tosca/corres/$a.vts $tosca/corres/$b.vts $tosca/corres/$b.sym.vts"
done < "$tosca/test_pairs_included.txt" > "$out/tosca_r_test.txt"

dt=$data/deformation_transfer
for pair in "cat-poses/0001 cat-poses/0005" "cat-poses/0002 cat-poses/0009" "horse-poses/1 horse-poses/4" \
            "horse-gallop/0001 horse-gallop/0017"; do
  set -- $pair
  echo "$dt/$1.obj $dt/$2.obj identity"
done > "$out/deformation_transfer.txt"
echo "wrote $out/faust_r_test.txt, $out/tosca_r_test.txt, $out/deformation_transfer.txt"
