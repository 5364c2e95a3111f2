#!/bin/bash
# What a long call's `Run` costs: instructions of examples/batch_timing (a batch of a scene
# file, `Tracer::trace_batch_into`) and examples/search_rooms (pyroomacoustics' two rooms,
# `Tracer::search`) built from this checkout and from COMMIT (its own examples), one thread,
# under callgrind: (instructions at 3 repetitions − at 1) / 2, the set-up subtracted.
# Needs valgrind. Usage (from the repository root): bash benches/run_cost_against.sh bcfcb8d
set -euo pipefail
root=$PWD
commit=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo build --quiet --profile test-opt --all-features --example batch_timing --example search_rooms
mkdir -p "$tmp/here" "$tmp/base"
cp target/test-opt/examples/{batch_timing,search_rooms} "$tmp/here/"
git archive "$commit" | (mkdir -p "$tmp/tree" && tar -x -C "$tmp/tree")
(cd "$tmp/tree" && CARGO_TARGET_DIR=${TARGET:-$root/target/run_cost_against} cargo build --quiet \
  --profile test-opt --all-features --offline --example batch_timing --example search_rooms)
cp "${TARGET:-$root/target/run_cost_against}"/test-opt/examples/{batch_timing,search_rooms} "$tmp/base/"
total() { callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}'; }
count() {
  RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$tmp/cg" "$@" >/dev/null 2>&1
  total "$tmp/cg"
}
printf '%-12s %-8s %s\n' case build instructions
for scene in seed500 layers10 room2d; do
  for build in base here; do
    a=$(count "$tmp/$build/batch_timing" "fixtures/bench/$scene.json" 1)
    b=$(count "$tmp/$build/batch_timing" "fixtures/bench/$scene.json" 3)
    printf '%-12s %-8s %d\n' "$scene" "$build" $(((b - a) / 2))
  done
done
for build in base here; do
  a=$(count "$tmp/$build/search_rooms" 1)
  b=$(count "$tmp/$build/search_rooms" 3)
  printf '%-12s %-8s %d\n' rooms "$build" $(((b - a) / 2))
done
