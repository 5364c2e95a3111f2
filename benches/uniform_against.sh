#!/bin/bash
# Uniform scenes here against other commits: the same output and no more instructions.
# Builds (release, one build per commit) the command-line tool and the cost examples from this
# checkout and from each COMMIT (its own tree in $TARGETS/COMMIT.tree, with this
# examples/ray_cost.rs copied in, built into $TARGETS/COMMIT; TARGETS=/tmp/eigenray-against
# unless given), then
#  1. runs `eigenray solve SCENE` (the default output, stdout) on every scene of
#     examples/scenes, fixtures/cases, fixtures/amplitudes, fixtures/bench,
#     fixtures/pyroomacoustics and fixtures/every_stationary.json (this checkout's files, given
#     to every build) and says whether each commit's output is byte for byte the one here;
#  2. counts instructions under callgrind, one thread, each case's set-up subtracted
#     ((instructions at 3 repetitions − at 1) / 2): per ray of examples/ray_cost (the rays of
#     benches/eigenray.rs), examples/amplitude_cost and examples/gradient_cost; per batch of
#     examples/batch_timing on the bench scenes; and per repetition of examples/search_rooms
#     (the two rooms' search, as benches/search_rooms.py times it).
# Needs valgrind. Usage (from the repository root):
#   bash benches/uniform_against.sh a1457c0 bcfcb8d
# PARTS=outputs or PARTS=instructions runs one part only.
set -euo pipefail
root=$PWD
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
targets=${TARGETS:-/tmp/eigenray-against}
examples=(ray_cost amplitude_cost gradient_cost search_rooms batch_timing)
build() { # build SOURCE_DIR TARGET_DIR NAME
  (cd "$1" && CARGO_TARGET_DIR=$2 cargo build --quiet --release --offline --bin eigenray \
    "${examples[@]/#/--example=}")
  mkdir -p "$tmp/bin.$3"
  cp "$2/release/eigenray" "${examples[@]/#/$2/release/examples/}" "$tmp/bin.$3/"
}
build "$root" "${CARGO_TARGET_DIR:-$root/target}" here
names=(here)
for commit in "$@"; do
  # The tree where the build was (cargo builds again from another place).
  tree=$targets/$commit.tree
  mkdir -p "$tree"
  git archive "$commit" | tar -x -C "$tree"
  cmp -s examples/ray_cost.rs "$tree/examples/ray_cost.rs" || cp examples/ray_cost.rs "$tree/examples/"
  build "$tree" "$targets/$commit" "$commit"
  names+=("$commit")
done

if [[ ${PARTS:-outputs instructions} == *outputs* ]]; then
  printf '%-48s' scene
  printf ' %-10s' "${names[@]:1}"
  printf '\n'
  for scene in examples/scenes/*.json fixtures/cases/*.json fixtures/amplitudes/*.json \
    fixtures/bench/*.json fixtures/pyroomacoustics/*.json fixtures/every_stationary.json; do
    case $scene in *.expected.json | *.ref.json) continue ;; esac
    run() { # run NAME: the exit status and stdout of `eigenray solve`, one thread
      local status=0
      RAYON_NUM_THREADS=1 timeout 600 "$tmp/bin.$1/eigenray" solve "$scene" \
        >"$tmp/out.$1" 2>/dev/null || status=$?
      echo "$status"
    }
    here_status=$(run here)
    printf '%-48s' "$scene (exit $here_status)"
    for name in "${names[@]:1}"; do
      status=$(run "$name")
      if [[ $status != "$here_status" ]]; then
        printf ' %-10s' "exit_$status"
      elif cmp -s "$tmp/out.here" "$tmp/out.$name"; then
        printf ' %-10s' same
      else
        printf ' %-10s' DIFFERS
      fi
    done
    printf '\n'
  done
fi

[[ ${PARTS:-outputs instructions} == *instructions* ]] || exit 0
total() { callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}'; }
# cost NAME PER ARGS...: instructions of example ARGS of build NAME with the repetitions 1 and 3
# appended, (at 3 − at 1) / (2 × PER), PER the rays of a repetition (`rays`) or 1.
cost() {
  local name=$1 per=$2
  shift 2
  for reps in 1 3; do
    RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.$name.$reps" \
      "$tmp/bin.$name/$1" "${@:2}" "$reps" 2>"$tmp/err.$name.$reps" >/dev/null
  done
  if [[ $per == rays ]]; then per=$(sed -n 's/^rays per repetition: //p' "$tmp/err.$name.1"); fi
  awk -v a="$(total "$tmp/cg.$name.1")" -v b="$(total "$tmp/cg.$name.3")" -v n="$per" \
    'BEGIN { printf "%.1f\n", (b - a) / (2 * n) }'
}
# The cases: a label, then PER and the example's arguments.
cases=()
for c in one_refraction layers10 1_interaction 8_interactions 100_interactions \
  1_interaction_tol6 8_interactions_tol6 100_interactions_tol6 dipping8 dipping100 \
  reflector100k; do
  cases+=("ray_cost $c, per ray|rays ray_cost $c")
done
for c in one_refraction layers10; do
  for way in ray ray_asking ray_then_amplitude solve_with_amplitude; do
    cases+=("amplitude_cost $c $way, per ray|rays amplitude_cost $c $way")
  done
done
for c in one_refraction stack8 dipping8; do
  for way in ray ray_then_gradient solve_with_gradient; do
    cases+=("gradient_cost $c $way, per ray|rays gradient_cost $c $way")
  done
done
for scene in seed500 layers10 room2d; do
  cases+=("batch_timing $scene, per batch|1 batch_timing fixtures/bench/$scene.json")
done
cases+=("search_rooms, per repetition|1 search_rooms")
# Each build's counts in a process of its own (callgrind is one thread; the counts do not
# depend on the load).
for name in "${names[@]}"; do
  (
    for c in "${cases[@]}"; do
      read -ra args <<<"${c#*|}"
      cost "$name" "${args[@]}"
    done >"$tmp/counts.$name"
  ) &
done
wait
printf '%-44s %14s' case here
for name in "${names[@]:1}"; do printf ' %14s %7s' "$name" ratio; done
printf '\n'
for i in "${!cases[@]}"; do
  here=$(sed -n "$((i + 1))p" "$tmp/counts.here")
  printf '%-44s %14s' "${cases[$i]%%|*}" "$here"
  for name in "${names[@]:1}"; do
    base=$(sed -n "$((i + 1))p" "$tmp/counts.$name")
    printf ' %14s %7s' "$base" "$(awk -v h="$here" -v b="$base" 'BEGIN { printf "%.4f", h / b }')"
  done
  printf '\n'
done
