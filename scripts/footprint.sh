#!/usr/bin/env bash
# Footprint report of the bare-metal build, as Markdown for docs/footprint.md:
# flash and static RAM per component, stack (static .su/.ci analysis and the measured paint
# high-water mark), executed instructions per core workload and per stage of one full
# calibration from captures (QEMU instruction-count plugin).
#   cmake --workflow --preset cortex-m7 && cmake --build --preset host --target hivecal_cli &&
#   scripts/footprint.sh [build-dir] [qemu-machine]
# Defaults: build/cortex-m7, mps2-an500. Everything it needs is in the repository (the QEMU
# instruction-count plugin source: scripts/qemu-insn-count/insn_count.c, built here with cc).
# Environment:
#   HIVECAL_INSN_PLUGIN_SRC  plugin source (default scripts/qemu-insn-count/insn_count.c)
#   HIVECAL_FOOTPRINT_REPEATS repeats per workload for the instruction counts (default 10)
#   HIVECAL_HOST_TOOL        host `hivecal` that simulates the 512-sample session
#                            (default build/host/apps/hivecal/hivecal)
set -euo pipefail
cd "$(dirname "$0")/.."

build=${1:-build/cortex-m7}
machine=${2:-mps2-an500}
plugin_src=${HIVECAL_INSN_PLUGIN_SRC:-scripts/qemu-insn-count/insn_count.c}
repeats=${HIVECAL_FOOTPRINT_REPEATS:-10}
probe=$build/tests/firmware/hivecal_firmware_core.elf
tests_elf=$build/tests/firmware/hivecal_firmware_tests.elf
job_elf=$build/tests/firmware/hivecal_firmware_capture_job.elf
host_tool=${HIVECAL_HOST_TOOL:-build/host/apps/hivecal/hivecal}
runner=scripts/run-qemu-mps2.sh
for f in "$probe" "$tests_elf" "$job_elf" "$host_tool"; do
  [ -f "$f" ] || { echo "footprint: $f missing; build the preset first" >&2; exit 1; }
done

kib() { awk -v b="$1" 'BEGIN { printf "%.1f", b / 1024 }'; }

# --- sizes ------------------------------------------------------------------------------

# Berkeley sizes of an ELF: "text data bss" (bss includes the stack and its guard).
elf_sizes() { arm-none-eabi-size "$1" | awk 'NR == 2 { print $1, $2, $3 }'; }

image_table() {
  echo "| image | text (flash) | data (flash + RAM) | bss incl. stack (RAM) | flash total | static RAM total |"
  echo "|---|---:|---:|---:|---:|---:|"
  for elf in "$probe" "$job_elf" "$tests_elf"; do
    read -r text data bss < <(elf_sizes "$elf")
    printf '| %s | %d | %d | %d | %d (%s KiB) | %d (%s KiB) |\n' "$(basename "$elf")" "$text" "$data" "$bss" \
      $((text + data)) "$(kib $((text + data)))" $((data + bss)) "$(kib $((data + bss)))"
  done
}

# Per-component bytes in a linked image, from its GNU ld map: every input section kept in an
# allocated output section, grouped by the object or archive it came from.
map_components() {
  awk '
    function component(file) {
      if (file ~ /libhivecal\.a\(/) { sub(/.*\(/, "", file); sub(/\.obj\)$/, "", file); return "lib: " file }
      if (file ~ /hivecal_baremetal\.dir/) { sub(/.*\/src\//, "", file); sub(/\.obj$/, "", file); return "port/baremetal: " file }
      if (file ~ /tests\/firmware/) { sub(/.*\.dir\//, "", file); sub(/\.obj$/, "", file); return "firmware: " file }
      if (file ~ /libstdc\+\+|libsupc\+\+/) return "toolchain: libstdc++ (nano)"
      if (file ~ /libm\.a/) return "toolchain: newlib libm"
      if (file ~ /libc_nano\.a|libc\.a/) return "toolchain: newlib libc (nano)"
      if (file ~ /libgcc\.a/) return "toolchain: libgcc"
      if (file == "padding") return "alignment padding"
      if (file == "stack") return "stack + 32-byte MPU guard (linker script)"
      return "other: " file
    }
    function kind(section) {
      if (section == ".data") return "data"
      if (section == ".bss" || section == ".stack") return "bss"
      return "text"
    }
    function add(file, size) {
      if (output == "" || size == 0) return
      c = component(file)
      bytes[c, kind(output)] += size
      seen[c] = 1
    }
    /^Linker script and memory map/ { in_map = 1; next }
    /^Cross Reference Table/ { in_map = 0 }
    !in_map { next }
    # Output section header: ".name addr size" or ".name" then "addr size" on the next line.
    /^\.[A-Za-z_.]+/ {
      output = ($1 ~ /^\.(isr_vector|text|rodata|ARM\.extab|ARM\.exidx|preinit_array|init_array|data|bss|stack)$/) ? $1 : ""
      next
    }
    $1 == "*fill*" && NF >= 3 { add(output == ".stack" ? "stack" : "padding", hex($3)); next }
    # Input section: " .name addr size file" or " .name" then "addr size file".
    /^ [.*A-Za-z_]/ && $1 !~ /^\*/ {
      if (NF >= 4 && $2 ~ /^0x/) { add($4, hex($3)); next }
      if (NF == 1) { pending = 1; next }
      next
    }
    pending && /^ +0x[0-9a-f]+ +0x[0-9a-f]+ +[^ ]/ { add($3, hex($2)); pending = 0; next }
    { pending = 0 }
    function hex(s,   v, i, c) {
      v = 0; s = tolower(s); sub(/^0x/, "", s)
      for (i = 1; i <= length(s); i++) { c = index("0123456789abcdef", substr(s, i, 1)) - 1; v = v * 16 + c }
      return v
    }
    END {
      for (c in seen) printf "%s\t%d\t%d\t%d\n", c, bytes[c, "text"], bytes[c, "data"], bytes[c, "bss"]
    }' "$1"
}

component_table() {
  local map=${1%.elf}.map
  [ -f "$map" ] || { echo "(no link map $map)"; return; }
  echo "| component | text+rodata (flash) | data (flash + RAM) | bss (RAM) |"
  echo "|---|---:|---:|---:|"
  map_components "$map" | sort | awk -F'\t' '
    { printf "| %s | %d | %d | %d |\n", $1, $2, $3, $4; t += $2; d += $3; b += $4 }
    END { printf "| **total** | **%d** | **%d** | **%d** |\n", t, d, b }'
}

archive_table() {
  echo "| lib object (before --gc-sections) | text | data | bss |"
  echo "|---|---:|---:|---:|"
  arm-none-eabi-size "$build/lib/libhivecal.a" | awk 'NR > 1 {
      name = $6; sub(/\.obj.*/, "", name); sub(/.*\//, "", name)
      printf "| %s | %d | %d | %d |\n", name, $1, $2, $3; t += $1; d += $2; b += $3 }
    END { printf "| **libhivecal.a** | **%d** | **%d** | **%d** |\n", t, d, b }'
}

# --- stack ------------------------------------------------------------------------------

su_files() { find "$build/lib" "$build/port" "$build/tests/firmware" -name '*.su' 2>/dev/null; }

biggest_frames() {
  echo "| frame [bytes] | kind | function |"
  echo "|---:|---|---|"
  su_files | xargs cat | awk -F'\t' '{ n = $1; sub(/^[^:]*:[0-9]+:[0-9]+:/, "", n); print $2 "\t" $3 "\t" n }' |
    sort -t$'\t' -k1,1nr | awk -F'\t' '!seen[$3]++' | head -12 |
    awk -F'\t' '{ gsub(/\|/, "\\|", $3); printf "| %d | %s | `%s` |\n", $1, $2, $3 }'
}

# Static stack analysis over GCC's -fcallgraph-info=su call graphs (.ci): a function's worst
# depth is its own frame plus its deepest callee. Library functions without .ci (newlib,
# libgcc) count 0 and are listed; an indirect call counts as the worst of the functions whose
# name matches `indirect` (the FW_TEST bodies for the test image).
CALLGRAPH_AWK='
  /^node:/ {
    split($0, f, "\"")
    title = f[2]; label = f[4]
    if (match(label, /[0-9]+ bytes/)) {
      s = substr(label, RSTART, RLENGTH) + 0
      if (!(title in size) || s > size[title]) size[title] = s
      if (label ~ /dynamic/) dynamic[title] = 1
    }
    next
  }
  /^edge:/ {
    split($0, f, "\"")
    # Complete-object constructors/destructors (C1/D1) are emitted as aliases of C2/D2.
    sub(/C1E/, "C2E", f[4]); sub(/D1Ev/, "D2Ev", f[4])
    key = f[2] SUBSEP f[4]
    if (!(key in have)) { have[key] = 1; edges[f[2]] = edges[f[2]] " " f[4] }
    next
  }
  function worst(node,   list, k, i, v, best, child) {
    if (node in memo) return memo[node]
    if (node in active) { recursive = recursive " " node; return 0 }
    active[node] = 1
    best = 0; child = ""
    k = split(edges[node], list, " ")
    for (i = 1; i <= k; i++) {
      if (list[i] == "__indirect_call" && indirect != "") {
        v = worst_indirect(); if (v > best) { best = v; child = best_indirect }
        continue
      }
      v = worst(list[i]); if (v > best) { best = v; child = list[i] }
    }
    delete active[node]
    if (!(node in size) && node != "__indirect_call") unaccounted[node] = 1
    next_on_path[node] = child
    memo[node] = size[node] + best
    return memo[node]
  }
  function worst_indirect(   t, v, best) {
    if (indirect_done) return indirect_value
    best = 0
    for (t in size) if (t ~ indirect) { v = worst(t); if (v > best) { best = v; best_indirect = t } }
    indirect_done = 1; indirect_value = best
    return best
  }
  function display(node) { sub(/.*:/, "", node); return node }  # local functions: "file:symbol"
  function notes(   u, list, d, dl) {
    list = ""; for (u in unaccounted) list = list " `" u "`"
    if (list != "") printf "\nLibrary functions reached without stack data (counted 0):%s\n", list
    dl = ""; for (d in dynamic) dl = dl " `" display(d) "`"
    if (dl != "") printf "\nFunctions with dynamic frames:%s\n", dl
    if (recursive != "") printf "\nRecursion found at:%s\n", recursive
  }
'

# Worst path from `root` in the objects given, as a table.
worst_path() {
  local root=$1 indirect_regex=$2
  shift 2
  cat "$@" | awk -v root="$root" -v indirect="$indirect_regex" "$CALLGRAPH_AWK"'
    END {
      printf "static worst path from `%s`: **%d bytes**\n\n", root, worst(root)
      printf "| frame [bytes] | function |\n|---:|---|\n"
      for (node = root; node != ""; node = next_on_path[node])
        printf "| %d | `%s`%s |\n", size[node], display(node), (node in size) ? "" : " (library, not analysed)"
      notes()
    }' | c++filt
}

# Worst stack depth of every public lib function (what a caller must budget for it).
lib_entry_stack() {
  cat "$@" | awk "$CALLGRAPH_AWK"'
    END {
      for (t in size) if (t ~ /^_ZN?K?7hivecal/) printf "%d\t%d\t%s\n", worst(t), size[t], t
    }' | sort -t$'\t' -k1,1nr | head -12 | c++filt |
    awk -F'\t' 'BEGIN { print "| worst depth [bytes] | own frame | function |"; print "|---:|---:|---|" }
                { printf "| %d | %d | `%s` |\n", $1, $2, $3 }'
}

# --- instructions -----------------------------------------------------------------------

plugin=$build/libinsncount.so
build_plugin() {
  [ -f "$plugin_src" ] || { echo "footprint: plugin source $plugin_src missing (set HIVECAL_INSN_PLUGIN_SRC)" >&2; exit 1; }
  if [ ! -f "$plugin" ] || [ "$plugin_src" -nt "$plugin" ]; then
    "${CC:-cc}" -shared -fPIC -O2 "$plugin_src" -o "$plugin"
  fi
}

# Executed guest instructions of one run: "<instructions> <stack high-water bytes>".
count_run() {
  local elf=$1
  shift
  local out
  out=$(HIVECAL_QEMU_EXTRA="-plugin $plugin -d plugin" "$runner" "$machine" "$elf" "$@" 2>&1)
  local insns stack
  insns=$(sed -n 's/^insns: //p' <<<"$out" | tail -1)
  stack=$(sed -n 's/.*stack high-water:\{0,1\} \([0-9]*\) of.*/\1/p' <<<"$out" | tail -1)
  echo "${insns:-0} ${stack:-0}"
}

instruction_table() {
  read -r base base_stack < <(count_run "$probe" fill 1)
  echo "| workload (core probe, 512 samples) | instructions per call | per sample (per sincos) | stack high-water [bytes] |"
  echo "|---|---:|---:|---:|"
  printf '| startup + fill 512 samples (baseline) | %d | %d | %d |\n' "$base" $((base / 512)) "$base_stack"
  local w n label total stack per
  for w in sincos:3072:"math::sincos x 3072 (6 per sample)" fk:512:"fk_tool_point x 512" jacobian:512:"tool_point_jacobian x 512" \
           cost:512:"evaluate_cost mean_abs_3d, refit, 512 samples" \
           cost_358:358:"evaluate_cost mean_abs_3d, refit, 358 training samples" \
           cost_fixed:512:"evaluate_cost sum_squares, fixed base, 512 samples" \
           metrics:512:"accuracy_report (train/test/overall)"; do
    IFS=: read -r name n label <<<"$w"
    read -r total stack < <(count_run "$probe" "$name" "$repeats")
    per=$(((total - base) / repeats))
    printf '| %s | %d | %d | %d |\n' "$label" "$per" $((per / n)) "$stack"
    [ "$name" = cost_358 ] && echo "$per" >"$build/footprint-cost358.txt"
  done
}

# The full calibration from captures: a simulated session of 21 waypoints written by the host
# tool (476 quasi-static samples with the extraction at the instant: the most that stays below
# the image's 512-sample capacity), then the capture job image stopped after each stage: the
# differences are the stages' instructions.
session=$build/fw-session-w21
make_session() {
  if [ ! -f "$session/robot.cap" ]; then
    mkdir -p "$session"
    "$host_tool" simulate --out-dir "$session" --waypoints 21 --duration-s 1 --seed 1 >/dev/null
  fi
}

job_run() {  # <SN> <cycles> [clock|extraction|abc|lm|compliance]: "<instructions> <stack> <samples> <evaluations> <digest>"
  local out insns stack samples evals digest
  out=$(HIVECAL_QEMU_EXTRA="-plugin $plugin -d plugin" "$runner" "$machine" "$job_elf" \
        "$PWD/$session/robot.cap" "$PWD/$session/tracker.cap" "$@" 2>&1)
  insns=$(sed -n 's/^insns: //p' <<<"$out" | tail -1)
  stack=$(sed -n 's/^stack high-water: \([0-9]*\) of.*/\1/p' <<<"$out")
  samples=$(sed -n 's/^samples kept: //p' <<<"$out")
  evals=$(sed -n 's/^ABC evaluations: //p' <<<"$out")
  digest=$(sed -n 's/^capture job digest: //p' <<<"$out")
  echo "${insns:-0} ${stack:-0} ${samples:-0} ${evals:-0} ${digest:-none}"
  grep -q "^test MAE" <<<"$out" && sed -n 's/^\(test MAE [A-Za-z ]*\) \[m\]: \([^ ]*\).*/\1 \2/p' <<<"$out" >"$build/footprint-job-mae.txt"
  return 0
}

job_table() {
  local c s e a1 a full stack samples evals digest x
  read -r c _ <<<"$(job_run 150 300 clock)"
  read -r e _ samples _ <<<"$(job_run 150 300 extraction)"
  read -r a1 _ _ x _ <<<"$(job_run 150 1 abc)"
  read -r a _ _ evals _ <<<"$(job_run 150 300 abc)"
  local lm lm_stack lm_digest
  read -r lm lm_stack _ _ lm_digest <<<"$(job_run 150 300 lm)"
  local lm_mae
  lm_mae=$(tr '\n' ';' <"$build/footprint-job-mae.txt" | sed 's/;$//; s/;/; /g')
  local co co_stack co_digest co_mae
  read -r co co_stack _ _ co_digest <<<"$(job_run 150 300 compliance)"
  co_mae=$(tr '\n' ';' <"$build/footprint-job-mae.txt" | sed 's/;$//; s/;/; /g')
  read -r full stack _ _ digest <<<"$(job_run 150 300)"
  local per_eval=$(((a - a1) / (evals - x)))
  echo "| stage (512-capacity image, $samples samples, ABC 150 x 300) | instructions | share |"
  echo "|---|---:|---:|"
  awk -v c="$c" -v e="$e" -v a="$a" -v f="$full" -v n="$evals" -v pe="$per_eval" 'BEGIN {
    printf "| startup + pass 1: decode both captures, clock sync | %.0f | %.1f %% |\n", c, 100 * c / f
    printf "| pass 2: decode again, sample extraction | %.0f | %.1f %% |\n", e - c, 100 * (e - c) / f
    printf "| split + ABC (%.0f evaluations, ~%.0f instructions each incl. solver) | %.0f | %.1f %% |\n", n, pe, a - e, 100 * (a - e) / f
    printf "| LM on the full model + validation | %.0f | %.1f %% |\n", f - a, 100 * (f - a) / f
    printf "| **whole run** | **%.0f** | 100 %% |\n", f }'
  echo
  echo "Digest of this run: \`$digest\`; stack high-water $stack bytes; $(tr '\n' ';' <"$build/footprint-job-mae.txt" | sed 's/;$//; s/;/; /g') m."
  echo
  echo "LM-only job (the same passes, then LM on the full model from the nominal geometry): $lm instructions"
  echo "(passes $e, LM + validation $((lm - e))); digest \`$lm_digest\`; stack high-water $lm_stack bytes; $lm_mae m."
  echo
  echo "Compliance job (the same passes, LM, then LM+compliance from LM's geometry): $co instructions"
  echo "(passes $e, LM + LM+compliance + validation $((co - e))); digest \`$co_digest\`; stack high-water $co_stack bytes; $co_mae m."
  echo "$full" >"$build/footprint-job-insns.txt"
  echo "$lm" >"$build/footprint-lm-job-insns.txt"
  echo "$co" >"$build/footprint-compliance-job-insns.txt"
  local worst=$((stack > lm_stack ? stack : lm_stack))
  echo "$((worst > co_stack ? worst : co_stack))" >"$build/footprint-job-stack.txt"
  echo "$per_eval" >"$build/footprint-job-per-eval.txt"
}

# --- report -----------------------------------------------------------------------------

ci_files_for() {  # objects of lib, port and the given firmware directory
  find "$build/lib" "$build/port" "$build/tests/firmware/CMakeFiles/$1.dir" -name '*.ci' 2>/dev/null
}

build_plugin
make_session
read -r job_text job_data job_bss < <(elf_sizes "$job_elf")
job_stack=$(arm-none-eabi-size -A "$job_elf" | awk '$1 == ".stack" { print $2 }')
read -r probe_text probe_data probe_bss < <(elf_sizes "$probe")
probe_stack=$(arm-none-eabi-size -A "$probe" | awk '$1 == ".stack" { print $2 }')
dataset_bytes=$(arm-none-eabi-nm -S --size-sort "$probe" | awk '$4 ~ /g_dataset/ { print strtonum_hex($2) } function strtonum_hex(s, v, i) { v = 0; s = tolower(s); for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1; return v }')
read -r tests_insns tests_stack < <(count_run "$tests_elf")

cat <<EOF
### Images (\`arm-none-eabi-size\`)

$(image_table)

### Per component, core probe image (from its link map, after --gc-sections)

$(component_table "$probe")

### Per component, capture calibration image

$(component_table "$job_elf")

### Per component, firmware test image

$(component_table "$tests_elf")

### lib archive members (compiled, before the linker drops unused sections)

$(archive_table)

### Stack

Biggest frames (\`-fstack-usage\`, lib + port + firmware):

$(biggest_frames)

Public lib functions by worst static stack depth (own frame + deepest callee chain):

$(lib_entry_stack $(find "$build/lib" -name '*.ci'))

Core probe, $(worst_path hivecal_reset_continue "" $(ci_files_for hivecal_firmware_core))

Capture calibration image (indirect calls: the worst cost evaluation, byte read or frame handler), $(worst_path hivecal_reset_continue "8evaluateEPKd|4readEPhjPj|on_joint_state|on_tracker_point" $(ci_files_for hivecal_firmware_capture_job))

Firmware tests, $(worst_path hivecal_reset_continue "fw_test_" $(ci_files_for hivecal_firmware_tests))

Measured high-water mark (paint): core probe (all workloads) $(count_run "$probe" all 1 | awk '{ print $2 }') bytes;
firmware tests $tests_stack bytes; capture calibration: see below.

### Executed instructions (QEMU plugin, $machine, ${repeats} repeats per workload)

$(instruction_table)

Firmware test image, whole run: $tests_insns instructions.

### One full calibration from captures (capture job image, QEMU plugin, $machine)

$(job_table)

### Budgets

The product budgets (docs/footprint.md, "Budgets"):

- Capture calibration image, 512-sample job: static RAM $((job_data + job_bss)) bytes of 131072
  (128 KiB; including a $job_stack-byte stack + guard): $((131072 - job_data - job_bss)) bytes left;
  flash $((job_text + job_data)) bytes of 139264 (136 KiB; $((139264 - job_text - job_data)) left).
- Stack of the capture calibration image, measured (paint high-water, the three jobs):
  $(cat "$build/footprint-job-stack.txt") bytes of $job_stack.
- LM-only job from captures (512-capacity image, LM on the full model):
  $(cat "$build/footprint-lm-job-insns.txt") instructions against 0.6e9:
  $(awk -v f="$(cat "$build/footprint-lm-job-insns.txt")" 'BEGIN { printf "%.2f x the budget", f / 0.6e9 }').
- LM-only job with compliance from captures (LM, then LM+compliance):
  $(cat "$build/footprint-compliance-job-insns.txt") instructions against 0.6e9:
  $(awk -v f="$(cat "$build/footprint-compliance-job-insns.txt")" 'BEGIN { printf "%.2f x the budget", f / 0.6e9 }').
- The paper's job from captures (about 512 samples, ABC 150 x 300, LM):
  $(cat "$build/footprint-job-insns.txt") instructions against 4e9:
  $(awk -v f="$(cat "$build/footprint-job-insns.txt")" 'BEGIN { printf "%.2f x the budget", f / 4e9 }').

- Dataset<512>: $dataset_bytes bytes; core probe static RAM $((probe_data + probe_bss)) bytes
  (including a $probe_stack-byte stack + guard) of 131072: $((131072 - probe_data - probe_bss)) bytes left.
- Core probe flash $((probe_text + probe_data)) bytes of 131072: $((131072 - probe_text - probe_data)) bytes left.
- One cost evaluation on 358 training samples: $(cat "$build/footprint-cost358.txt") instructions;
  4e9 instructions allow $((4000000000 / $(cat "$build/footprint-cost358.txt"))) such evaluations
  (ABC 150 x 300 = 45000 evaluations would need $((45000 * $(cat "$build/footprint-cost358.txt"))) instructions).
EOF
