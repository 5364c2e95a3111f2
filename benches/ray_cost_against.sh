#!/bin/bash
# What a ray that does not ask for amplitudes costs here and at other commits: examples/ray_cost
# (`Tracer::solve` over a case's receivers, no amplitudes) built from this checkout and from
# each COMMIT (its tree with this ray_cost.rs copied in), then
#  - instructions per ray under callgrind, one thread: (instructions at 3 repetitions −
#    instructions at 1) / (2 × rays), the set-up subtracted;
#  - nanoseconds per ray, the builds run in alternation (ROUNDS rounds, default 21, each
#    build first in turn), the median per build.
# Needs valgrind. Usage (from the repository root):
#   bash benches/ray_cost_against.sh 6b92966 1251dab
set -euo pipefail
root=$PWD
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
target=${TARGET:-$root/target/ray_cost_against}
cargo build --quiet --release --example ray_cost
cp target/release/examples/ray_cost "$tmp/bin.here"
names=(here)
for commit in "$@"; do
  git archive "$commit" | (mkdir -p "$tmp/tree.$commit" && tar -x -C "$tmp/tree.$commit")
  cp examples/ray_cost.rs "$tmp/tree.$commit/examples/"
  (cd "$tmp/tree.$commit" && CARGO_TARGET_DIR=$target cargo build --quiet --release --offline \
    --example ray_cost)
  cp "$target/release/examples/ray_cost" "$tmp/bin.$commit"
  names+=("$commit")
done
printf '%-16s %-10s %s\n' case build instructions_per_ray
for case in ${CASES:-one_refraction layers10}; do
  for name in "${names[@]}"; do
    for reps in 1 3; do
      RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.$reps" \
        "$tmp/bin.$name" "$case" "$reps" 2>"$tmp/err.$reps" >/dev/null
    done
    rays=$(sed -n 's/^rays per repetition: //p' "$tmp/err.1")
    total() { callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}'; }
    awk -v a="$(total "$tmp/cg.1")" -v b="$(total "$tmp/cg.3")" -v n="$rays" -v c="$case" \
      -v w="$name" 'BEGIN { printf "%-16s %-10s %.1f\n", c, w, (b - a) / (2 * n) }'
  done
done
printf '\n%-16s %-10s %s\n' case build median_ns_per_ray
for case in ${CASES:-one_refraction layers10}; do
  for name in "${names[@]}"; do : >"$tmp/ns.$name"; done
  for round in $(seq 1 "${ROUNDS:-21}"); do
    count=${#names[@]}
    for k in $(seq 0 $((count - 1))); do
      name=${names[$(((round + k) % count))]}
      RAYON_NUM_THREADS=1 "$tmp/bin.$name" "$case" 20 2>/dev/null >>"$tmp/ns.$name"
    done
  done
  for name in "${names[@]}"; do
    sort -g "$tmp/ns.$name" | awk -v c="$case" -v w="$name" \
      '{ v[NR] = $1 } END { printf "%-16s %-10s %.2f\n", c, w, v[int((NR + 1) / 2)] }'
  done
done
