#!/bin/bash
# Instructions per ray of examples/amplitude_cost under callgrind, one thread: for each case and
# way, (instructions at 3 repetitions - instructions at 1) / (2 x rays), the cost of one ray
# without the set-up. Needs valgrind. Usage (from the repository root):
#   cargo build --release --example amplitude_cost && bash benches/amplitude_instructions.sh
set -euo pipefail
bin=${BIN:-target/release/examples/amplitude_cost}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-16s %-20s %s\n' case way instructions_per_ray
for case in ${CASES:-one_refraction layers10}; do
  for way in ${WAYS:-ray ray_asking ray_then_amplitude solve_with_amplitude}; do
    for reps in 1 3; do
      RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$tmp/$reps" \
        "$bin" "$case" "$way" "$reps" 2>"$tmp/err.$reps" >/dev/null
    done
    rays=$(sed -n 's/^rays per repetition: //p' "$tmp/err.1")
    total() { callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}'; }
    awk -v a="$(total "$tmp/1")" -v b="$(total "$tmp/3")" -v n="$rays" -v c="$case" -v w="$way" \
      'BEGIN { printf "%-16s %-20s %.1f\n", c, w, (b - a) / (2 * n) }'
  done
done
