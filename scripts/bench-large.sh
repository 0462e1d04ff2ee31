#!/usr/bin/env bash
# The default job (ABC+LM, ABC on a spanning subset) against the LM-only job on simulated sets
# of growing size (apps/bench/make_samples.cpp: a UR5 with 0.1 mm / 0.1 mrad errors, random
# poses, 10 um noise): wall time and peak memory of the whole `hivecal calibrate --samples`
# process, and the ratio of the two jobs. Wall time depends on the machine's load.
#   scripts/bench-large.sh [N ...]      (default: 2000 8000 12000)
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(2000 8000 12000)
cmake --preset host >/dev/null
cmake --build --preset host -j"$(nproc)" --target hivecal_cli make_samples >/dev/null
hivecal=build/host/apps/hivecal/hivecal
out=build/bench-large
mkdir -p "$out"
printf '%8s  %-14s %8s %10s %10s\n' poses job "wall[s]" "peak[MB]" "test[um]"
for n in "${sizes[@]}"; do
  build/host/apps/bench/make_samples "$n" 1 >"$out/s$n.csv"
  declare -A wall=()
  for job in lm abc+lm; do
    /usr/bin/time -f '%e %M' -o "$out/time" "$hivecal" calibrate --samples "$out/s$n.csv" --method "$job" \
      --out "$out/r$n.json" --quiet >"$out/r$n.txt" 2>&1
    read -r seconds kb <"$out/time"
    test_um=$(awk '/^ABC\+LM |^LM /{print $(NF-5)}' "$out/r$n.txt" | tail -1)
    wall[$job]=$seconds
    printf '%8s  %-14s %8s %10s %10s\n' "$n" "$job" "$seconds" "$(awk -v k="$kb" 'BEGIN{printf "%.1f", k / 1024}')" "$test_um"
  done
  echo "          default / LM-only: $(awk -v a="${wall[abc+lm]}" -v b="${wall[lm]}" 'BEGIN{printf "%.2f", a / b}')x"
done
