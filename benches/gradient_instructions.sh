#!/bin/bash
# Instructions per ray of examples/gradient_cost under callgrind, one thread: for each case and
# way, (instructions at 3 repetitions - instructions at 1) / (2 x rays), the cost of one ray
# without the set-up; with both layers10 cases, the ratio of a ray through media with a speed
# gradient to one through the uniform layers, way by way. Needs valgrind. Usage (from the
# repository root; CASES and WAYS choose, e.g. CASES="layers10 layers10_speed_gradient" WAYS=ray):
#   cargo build --release --example gradient_cost && bash benches/gradient_instructions.sh
set -euo pipefail
bin=target/release/examples/gradient_cost
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-24s %-20s %s\n' case way instructions_per_ray
for case in ${CASES:-one_refraction stack8 dipping8 layers10 layers10_speed_gradient}; do
  for way in ${WAYS:-ray ray_then_gradient solve_with_gradient}; do
    for reps in 1 3; do
      RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$tmp/$reps" \
        "$bin" "$case" "$way" "$reps" 2>"$tmp/err.$reps" >/dev/null
    done
    rays=$(sed -n 's/^rays per repetition: //p' "$tmp/err.1")
    total() { callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}'; }
    awk -v a="$(total "$tmp/1")" -v b="$(total "$tmp/3")" -v n="$rays" -v c="$case" -v w="$way" \
      'BEGIN { printf "%-24s %-20s %.1f\n", c, w, (b - a) / (2 * n) }' | tee -a "$tmp/table"
  done
done
# The layers with a speed gradient against the uniform ones, way by way.
awk '$1 == "layers10" { u[$2] = $3 } $1 == "layers10_speed_gradient" { g[$2] = $3 }
  END { for (w in g) if (w in u) printf "layers10 speed gradient / uniform, %s: %.2f\n", w, g[w] / u[w] }' \
  "$tmp/table"
