#!/usr/bin/env bash
# CPU seconds per KB of input, default settings, on the adversarial scenes of issue 29
# (benches/adversarial_scenes.py): prints scene, bytes, user+system CPU seconds, CPU s per KB,
# peak resident memory and the entries' statuses. Usage: benches/adversarial_cpu.sh [EIGENRAY]
set -euo pipefail
usage='Usage: benches/adversarial_cpu.sh [EIGENRAY]

Writes the adversarial scenes of benches/adversarial_scenes.py to a temporary folder, solves
each once with EIGENRAY (default: target/release/eigenray) and prints scene, bytes, user+system
CPU seconds, CPU s per KB, peak resident memory (MB) and the entries statuses.'
case ${1:-} in
    -h | --help) echo "$usage"; exit 0 ;;
    -*) echo "$usage" >&2; exit 2 ;;
esac
if [ $# -gt 1 ]; then
    echo "$usage" >&2
    exit 2
fi
cd "$(dirname "$0")/.."
bin=${1:-target/release/eigenray}
if [ ! -x "$bin" ]; then
    echo "error: $bin is not an executable (build it first: cargo build --release)" >&2
    exit 2
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 benches/adversarial_scenes.py "$dir" > /dev/null
printf '%-24s %6s %8s %8s %9s  %s\n' scene bytes cpu_s s_per_KB peak_MB statuses
for f in "$dir"/*.json; do
    name=$(basename "$f" .json)
    bytes=$(stat -c %s "$f")
    /usr/bin/time -f '%U %S %M' -o "$dir/time" "$bin" solve "$f" --format jsonl > "$dir/out"
    read -r user sys kb < "$dir/time"
    statuses=$(grep -o '"status":"[a-z_]*"' "$dir/out" | sort | uniq -c | tr -d '"' | awk '{printf "%s %s ", $1, substr($2, 8)}')
    awk -v n="$name" -v b="$bytes" -v u="$user" -v s="$sys" -v k="$kb" -v st="$statuses" \
        'BEGIN { c = u + s; printf "%-24s %6d %8.2f %8.2f %9.1f  %s\n", n, b, c, c / (b / 1024), k / 1024, st }'
done
