#!/usr/bin/env bash
# Whole process against whole process: `hivecal calibrate --samples S --method lm` against
# ceres_calibrate (apps/bench/ceres_calibrate.cpp: the same fit written with Ceres, the same
# parameters estimated) on simulated sets (apps/bench/make_samples.cpp), timed by hyperfine.
# Three hivecal runs: the LM job as a user runs it (blunder test, significance test), one fit
# (--keep-outliers --significance 0: what the Ceres program does), and the process start alone
# (--help); the Ceres program's start alone is its usage exit. Also the largest gap between the
# two calibrations' predictions of the samples' poses. Wall time depends on the machine's load.
#   scripts/bench-process.sh [N ...]      (default: 100 300)
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(100 300)
cmake --preset host >/dev/null
cmake --build --preset host -j"$(nproc)" --target hivecal_cli make_samples ceres_calibrate >/dev/null
hivecal=build/host/apps/hivecal/hivecal
ceres=build/host/apps/bench/ceres_calibrate
out=build/bench-process
mkdir -p "$out"

# mean_ms JSON K: hyperfine's mean wall time of its K-th command (1-based) in milliseconds.
mean_ms() { grep -o '"mean": [0-9.e+-]*' "$1" | awk -v k="$2" 'NR == k {printf "%.2f", $2 * 1e3}'; }

for n in "${sizes[@]}"; do
  build/host/apps/bench/make_samples "$n" 1 >"$out/s$n.csv"
  one_fit=("$hivecal" calibrate --samples "$out/s$n.csv" --method lm --split 1 --keep-outliers --significance 0
    --quiet --out "$out/one$n.json")
  "${one_fit[@]}" >/dev/null
  # The parameters hivecal estimated: the Ceres program estimates the same ones.
  estimated=$(awk '/"estimated": \[/ {f = 1; next} f && /\]/ {exit} f {gsub(/[ ",]/, ""); printf "%s%s", s, $0; s = ","}' \
    "$out/one$n.json")
  hyperfine -N -i --style none -w 5 -r 40 --export-json "$out/t$n.json" \
    "$hivecal calibrate --samples $out/s$n.csv --method lm --split 1 --quiet --out $out/job$n.json" \
    "${one_fit[*]}" \
    "$ceres $out/s$n.csv $estimated $out/ceres$n.json" \
    "$hivecal --help" \
    "$ceres" >/dev/null 2>&1
  # The two calibrations' predictions of the samples' own poses.
  tail -n +2 "$out/s$n.csv" | cut -d, -f1-6 | sed '1i q1,q2,q3,q4,q5,q6' >"$out/j$n.csv"
  "$hivecal" predict --calibration "$out/one$n.json" --joints "$out/j$n.csv" --out "$out/ph$n.csv"
  "$hivecal" predict --calibration "$out/ceres$n.json" --joints "$out/j$n.csv" --out "$out/pc$n.csv"
  gap_um=$(paste -d, <(tail -n +2 "$out/ph$n.csv") <(tail -n +2 "$out/pc$n.csv") |
    awk -F, '{d = sqrt(($1 - $4)^2 + ($2 - $5)^2 + ($3 - $6)^2); if (d > m) m = d} END {printf "%.2g", m * 1e6}')
  job=$(mean_ms "$out/t$n.json" 1)
  one=$(mean_ms "$out/t$n.json" 2)
  theirs=$(mean_ms "$out/t$n.json" 3)
  echo "$n samples, $(tr ',' '\n' <<<"$estimated" | wc -l) parameters estimated; mean wall time of the whole process:"
  printf '  %-52s %8s ms\n' "hivecal calibrate --method lm (the job)" "$job" \
    "hivecal, one fit (--keep-outliers --significance 0)" "$one" \
    "ceres_calibrate (one fit)" "$theirs" \
    "hivecal --help (process start)" "$(mean_ms "$out/t$n.json" 4)" \
    "ceres_calibrate, usage exit (process start)" "$(mean_ms "$out/t$n.json" 5)"
  echo "  Ceres / hivecal: $(awk -v a="$theirs" -v b="$one" 'BEGIN {printf "%.2f", a / b}')x one fit against one fit," \
    "$(awk -v a="$theirs" -v b="$job" 'BEGIN {printf "%.2f", a / b}')x against the job;" \
    "largest prediction gap between the two calibrations: $gap_um um"
done
