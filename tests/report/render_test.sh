#!/usr/bin/env bash
# The HTML report as a browser shows it (ctest report.render): a simulated session is
# calibrated from streams and from paired samples, each report is rendered by headless
# Chromium (Debian's `chromium`, scripts/install-deps.sh) and its DOM is checked:
#   - every figure the input calls for is there (and no stream figure for samples input),
#     the clock-sync profiles in result.json agree (residual well under the speeds);
#   - no numeric tick label has more than three significant digits;
#   - every legend entry has a drawn element of its series in the same figure;
#   - no text runs past its figure's edges, as the browser lays it out;
#   - `hivecal report --calibration` redraws the same figures, the same bytes twice;
#   - a sample made a blunder is set aside and shown (table and figure), --cv draws its folds;
#   - a run of 12,000 samples: the result and the page stay small (the report keeps 5,000
#     samples, each figure draws at most its cap, the captions say so), redrawn the same.
#   tests/report/render_test.sh HIVECAL
set -uo pipefail
hivecal=${1:?usage: render_test.sh HIVECAL}
chromium_bin=${CHROMIUM:-chromium}
if ! command -v "$chromium_bin" >/dev/null 2>&1; then
  echo "FAIL: '$chromium_bin' not found: the report test needs headless Chromium (scripts/install-deps.sh installs Debian's chromium)"
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0
ok() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }

# DOM of an HTML file after Chromium parsed and laid it out.
render() {  # render HTML DOM_OUT
  timeout 120 "$chromium_bin" --headless --disable-gpu --no-sandbox --no-first-run --user-data-dir="$work/profile" \
    --dump-dom "file://$1" >"$2" 2>"$work/chromium.err"
}

# One figure per line: "id<TAB>svg markup" (newlines inside a figure become spaces).
figures_of() {  # figures_of DOM
  tr '\n' ' ' <"$1" | sed 's|<svg |\n<svg |g' | grep '^<svg ' | sed 's|</svg>.*|</svg>|' |
    sed -E 's|^<svg [^>]*id="([^"]*)"|\1\t&|'
}

# Significant digits of each numeric tick label above three, printed as "label".
long_ticks() {  # long_ticks DOM
  grep -o '<text class="tick"[^>]*>[^<]*</text>' "$1" | sed -E 's|<[^>]*>||g' | awk '
    {
      label = $0; mantissa = label; sub(/^[-+\xe2\x88\x92]*/, "", mantissa); sub(/[eE].*$/, "", mantissa)
      if (mantissa !~ /^[0-9.]+$/) next                   # not a number
      digits = mantissa; gsub(/\./, "", digits); sub(/^0+/, "", digits)
      if (index(mantissa, ".") == 0) sub(/0+$/, "", digits)  # 1250: three significant digits
      if (length(digits) > 3) print label
    }'
}

# Legend entries (per figure) without an element of their series in that figure.
orphan_legends() {  # orphan_legends DOM
  figures_of "$1" | while IFS=$'\t' read -r id svg; do
    grep -o '<text class="legend" data-series="[^"]*"' <<<"$svg" | sed -E 's|.*data-series="([^"]*)"|\1|' |
      while read -r name; do
        drawn=$(grep -o "<[a-z]* data-series=\"$name\"" <<<"$svg" | grep -vc '<text')
        [ "$drawn" -gt 0 ] || echo "$id: '$name'"
      done
  done
}

# Text laid out past its figure's edges by the browser (a legend entry cut at the panel's edge),
# one "id: 'text'" per line: the page with a script that measures every <text> of every <svg>.
overflowing_text() {  # overflowing_text HTML
  local probe="$work/probe.html"
  { sed '/^<\/body>$/,$d' "$1"; cat <<'JS'
<script>
const out = [];
for (const svg of document.querySelectorAll('svg')) {
  const box = svg.getBoundingClientRect();
  for (const t of svg.querySelectorAll('text')) {
    const r = t.getBoundingClientRect();
    if (r.width > 0 && (r.left < box.left - 0.5 || r.right > box.right + 0.5 || r.top < box.top - 0.5 ||
                        r.bottom > box.bottom + 0.5)) out.push(svg.id + ": '" + t.textContent + "'");
  }
}
const pre = document.createElement('pre');
pre.id = 'overflow';
pre.textContent = out.length + ' overflowing\n' + out.join('\n');
document.body.appendChild(pre);
</script>
</body>
</html>
JS
  } >"$probe"
  if ! render "$probe" "$work/probe.dom" || ! grep -q '<pre id="overflow">' "$work/probe.dom"; then
    echo "(the measuring script did not run)"
    return
  fi
  awk '/<pre id="overflow">/ { sub(/.*<pre id="overflow">/, ""); on = 1 }
       on { done = sub(/<\/pre>.*/, ""); print; if (done) exit }' "$work/probe.dom" | tail -n +2
}

check_report() {  # check_report NAME HTML EXPECTED_IDS...
  local name=$1 html=$2
  shift 2
  local dom="$work/$name.dom"
  if ! render "$html" "$dom" || ! grep -q '</html>' "$dom"; then
    fail "$name: chromium could not render $html: $(tail -3 "$work/chromium.err")"
    return
  fi
  local ids
  ids=$(figures_of "$dom" | cut -f1 | tr '\n' ' ')
  if [ "$ids" = "$* " ]; then ok; else fail "$name: figures [$ids], want [$* ]"; fi
  local svgs
  svgs=$(grep -o '<svg ' "$dom" | wc -l)
  if [ "$svgs" -eq $# ]; then ok; else fail "$name: $svgs <svg> elements, want $#"; fi
  local ticks long
  ticks=$(grep -o '<text class="tick"' "$dom" | wc -l)
  long=$(long_ticks "$dom")
  if [ "$ticks" -gt 100 ] && [ -z "$long" ]; then ok; else
    fail "$name: $ticks tick labels; with more than three significant digits: $(echo $long)"; fi
  local legends orphans
  legends=$(grep -o '<text class="legend"' "$dom" | wc -l)
  orphans=$(orphan_legends "$dom")
  if [ "$legends" -gt 10 ] && [ -z "$orphans" ]; then ok; else fail "$name: $legends legend entries; without a drawn element: $orphans"; fi
  local overflowing
  overflowing=$(overflowing_text "$html")
  if [ -z "$overflowing" ]; then ok; else fail "$name: text past its figure's edges: $overflowing"; fi
  echo "$name: $svgs figures, $ticks tick labels, $legends legend entries and every text's edges checked"
}

# The checkers must be able to fail: a long label and an orphan legend entry are found.
cat >"$work/bad.dom" <<'HTML'
<svg id="fig-bad"><text class="tick">231.25</text><text class="tick">1250</text><text class="tick">−0.01255</text><text class="tick">−0.0125</text><text class="tick">1e-05</text>
<text class="legend" data-series="measured">measured</text><rect class="swatch"></rect>
<text class="legend" data-series="calibrated">calibrated</text><polyline data-series="calibrated"></polyline></svg>
HTML
if [ "$(long_ticks "$work/bad.dom" | tr '\n' ' ')" = "231.25 −0.01255 " ] &&
   [ "$(orphan_legends "$work/bad.dom")" = "fig-bad: 'measured'" ]; then ok; else
  fail "the checkers miss a long tick label or an orphan legend entry: $(long_ticks "$work/bad.dom") / $(orphan_legends "$work/bad.dom")"
fi
# ... and a legend entry cut at the panel's edge is found (the browser measures it).
printf '<!DOCTYPE html>\n<html><body>\n<svg id="fig-cut" width="200" height="60"><text x="120" y="30">measurement noise (stated)</text><text x="10" y="30">fits</text></svg>\n</body>\n</html>\n' \
  >"$work/cut.html"
if [ "$(overflowing_text "$work/cut.html")" = "fig-cut: 'measurement noise (stated)'" ]; then ok; else
  fail "the checker misses text past a figure's edge: '$(overflowing_text "$work/cut.html")'"; fi

sim="$work/sim"
"$hivecal" simulate --out-dir "$sim" --waypoints 20 --duration-s 250 --seed 5 >/dev/null || { echo "FAIL: simulate"; exit 1; }
common=(fig-error-3d fig-error-x fig-error-y fig-error-z fig-vectors-xy fig-vectors-xz fig-cdf fig-histogram
        fig-convergence-global fig-convergence-lm fig-residual-q1 fig-residual-q2 fig-residual-q3 fig-residual-q4
        fig-residual-q5 fig-residual-q6 fig-outliers)

# From the streams: every figure, the drop reasons too.
if "$hivecal" calibrate --robot "$sim/robot.cap" --tracker "$sim/tracker.cap" --out "$work/streams.json" \
     --report "$work/streams" --quiet >/dev/null; then
  check_report streams "$work/streams/index.html" "${common[@]}" fig-clock-speeds fig-clock-residual fig-drop-timeline fig-drops
  # The clock figure's data in result.json: the matched profiles agree (residual rms well
  # under the tracker speed rms) and have as many bins in each column.
  clock=$(tr -d ' \n' <"$work/streams.json" | grep -o '"clock_match":{[^}]*}' | awk -F'"' '
    function values(key,   i, list) { for (i = 1; i < NF; i++) if ($i == key) { list = $(i + 1); break }
      gsub(/^:\[|\].*$/, "", list); return list }
    { n = split(values("tracker_speed_m_s"), v, ","); m = split(values("residual_m_s"), r, ",");
      t = split(values("t_s"), ts, ","); b = split(values("robot_speed_m_s"), rb, ",");
      for (i = 1; i <= n; i++) { sv += v[i] * v[i]; sr += r[i] * r[i] }
      if (n > 100 && n == m && n == t && n == b) printf "%d %.3f %.3f", n, sqrt(sv / n) * 1e3, sqrt(sr / n) * 1e3 }')
  read -r clock_bins speed_mm_s residual_mm_s <<<"${clock:-0 0 0}"
  if [ "$clock_bins" -gt 100 ] && awk -v s="$speed_mm_s" -v r="$residual_mm_s" 'BEGIN { exit !(s > 5 && r < 0.1 * s) }'; then
    ok; echo "streams: clock_match $clock_bins bins, rms tracker speed $speed_mm_s mm/s, rms residual $residual_mm_s mm/s"
  else fail "clock_match in result.json: '$clock' (bins, rms speed, rms residual [mm/s])"; fi
  if timeout 120 "$chromium_bin" --headless --disable-gpu --no-sandbox --no-first-run --user-data-dir="$work/profile" \
       --hide-scrollbars --window-size=1300,2000 --screenshot="$work/shot.png" "file://$work/streams/index.html" \
       >/dev/null 2>&1 && [ "$(head -c 8 "$work/shot.png" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] &&
     [ "$(stat -c %s "$work/shot.png")" -gt 50000 ]; then ok; else fail "screenshot of the report"; fi
  # Correlation coefficients of the parameter table are coefficients.
  bad_rho=$(grep -o '"correlation": [^,}]*' "$work/streams.json" | awk '{ v = $2 + 0; if (v > 1 || v < -1) print v }')
  rho_count=$(grep -c '"correlation": ' "$work/streams.json")
  if [ "$rho_count" -gt 10 ] && [ -z "$bad_rho" ]; then ok; else fail "$rho_count correlations; outside [-1, 1]: $bad_rho"; fi
  # Drawn again from the result: the same figures, and the same bytes every time.
  if "$hivecal" report --calibration "$work/streams.json" --out "$work/again" >/dev/null &&
     "$hivecal" report --calibration "$work/streams.json" --out "$work/again2" >/dev/null &&
     cmp -s "$work/again/index.html" "$work/again2/index.html"; then ok; else fail "report --calibration twice: different bytes"; fi
  check_report regenerated "$work/again/index.html" "${common[@]}" fig-clock-speeds fig-clock-residual fig-drop-timeline fig-drops
  # From Table 2 on (Table 1 has no stage times then, and the input facts name files), the
  # page is calibrate's own.
  if cmp -s <(sed -n '/<h2>Table 2/,$p' "$work/streams/index.html") <(sed -n '/<h2>Table 2/,$p' "$work/again/index.html"); then
    ok; else fail "report --calibration draws other tables or figures than calibrate --report"; fi
else
  fail "calibrate from streams"
fi

# From paired samples (the simulator's static truth) with a blunder (8 mm in x on line 11)
# and --cv 4: no stream figure; the blunder set aside and named, the folds drawn.
{ echo "q1,q2,q3,q4,q5,q6,x,y,z"; tail -n +2 "$sim/truth_samples.csv" | cut -d, -f4-12; } |
  awk -F, -v OFS=, 'NR == 11 { $7 = $7 + 0.008 } { print }' >"$work/samples.csv"
if "$hivecal" calibrate --samples "$work/samples.csv" --method all --cv 4 --out "$work/samples.json" \
     --report "$work/samples" --quiet >/dev/null; then
  check_report samples "$work/samples/index.html" "${common[@]}" fig-cv-folds
  if ! grep -q '"clock_match"' "$work/samples.json"; then ok; else fail "samples input: clock_match in result.json"; fi
  if grep -qE '<td>[^<]*/samples.csv:11</td><td>(7\.9|8\.0)[0-9]{2}</td><td>[0-9.]*</td><td>[0-9.]*</td>' "$work/samples/index.html" &&
     grep -q "data-series='set aside'" "$work/samples/index.html"; then ok; else
    fail "the blunder on samples.csv:11 is not in the outlier table and figure"; fi
  # Four fold rows (fold, training and held-out samples), each holding every kept sample.
  folds=$(grep -oE '<tr><td>[1-4]</td><td>[0-9]+</td><td>[0-9]+</td>' "$work/samples/index.html" |
    awk -F'</?td>' '$4 + $6 == 150 { n++ } END { print n + 0 }')
  if [ "$folds" -eq 4 ]; then ok; else fail "cross-validation table: $folds fold rows of 150 samples, want 4"; fi
  if "$hivecal" report --calibration "$work/samples.json" --out "$work/samples-again" >/dev/null &&
     cmp -s <(sed -n '/<h2>Table 2/,$p' "$work/samples/index.html") <(sed -n '/<h2>Table 2/,$p' "$work/samples-again/index.html")
  then ok; else fail "report --calibration draws other blunder or fold tables or figures than calibrate --report"; fi
else
  fail "calibrate from samples"
fi

# With --compliance (the same samples; the simulator bends joints 2 and 3): Table 1's
# LM+compliance row, the compliance terms in Table 4, joints 2 and 3 drawn rigid vs compliant.
if "$hivecal" calibrate --samples "$work/samples.csv" --compliance --out "$work/compliance.json" \
     --report "$work/compliance" --quiet >/dev/null; then
  check_report compliance "$work/compliance/index.html" "${common[@]}"
  if grep -q '<tr><td>LM+compliance</td>' "$work/compliance/index.html" &&
     grep -q '<tr><td>c_j2_o2</td><td>urad/m</td>' "$work/compliance/index.html" &&
     grep -q '"compliance": {' "$work/compliance.json"; then ok; else
    fail "compliance: no LM+compliance row in Table 1, no c_j2_o2 row in Table 4 or no compliance key"; fi
  for q in 2 3; do  # the shoulder and the elbow: both fits drawn
    if figures_of "$work/compliance.dom" | grep "^fig-residual-q$q" | grep -q 'data-series="ABC+LM (rigid)"'; then
      ok; else fail "compliance: fig-residual-q$q does not show the rigid fit"; fi
  done
  if "$hivecal" report --calibration "$work/compliance.json" --out "$work/compliance-again" >/dev/null &&
     cmp -s <(sed -n '/<h2>Table 2/,$p' "$work/compliance/index.html") \
            <(sed -n '/<h2>Table 2/,$p' "$work/compliance-again/index.html")
  then ok; else fail "report --calibration draws other compliance tables or figures than calibrate --report"; fi
else
  fail "calibrate --compliance from samples"
fi

# A run of 12,000 samples (the simulated arm's truth through predict, 10 um noise): the result
# keeps 5,000 of them (it was 3.3 MB, and 271 MiB at 10^6 samples, more than the commands read),
# the page draws at most 1,000 markers a joint panel and 400 arrows a set and says so (it was
# 10.4 MB of solid blocks), and `hivecal report` redraws it the same.
awk 'BEGIN { srand(12000); print "q1,q2,q3,q4,q5,q6"; for (i = 0; i < 12000; ++i)
  printf "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", rand() * 6 - 3, -rand() * 2.5 - 0.3, rand() * 2.4 - 1.2, rand() * 4 - 2,
    rand() * 3 - 1.5, rand() * 6 - 3 }' >"$work/large_joints.csv"
if "$hivecal" predict --calibration "$sim/truth.json" --joints "$work/large_joints.csv" --out "$work/large_points.csv" &&
   paste -d, "$work/large_joints.csv" "$work/large_points.csv" | awk -F, 'BEGIN { srand(12001); OFS = "," }
     NR == 1 { print "q1,q2,q3,q4,q5,q6,x,y,z"; next }
     { for (k = 7; k <= 9; ++k) $k = sprintf("%.9f", $k + (rand() + rand() + rand() - 1.5) * 2e-5); print }' \
     >"$work/large.csv" &&
   "$hivecal" calibrate --samples "$work/large.csv" --out "$work/large.json" --report "$work/large" --quiet >/dev/null; then
  check_report large "$work/large/index.html" "${common[@]}"
  result_bytes=$(stat -c %s "$work/large.json")
  page_bytes=$(stat -c %s "$work/large/index.html")
  kept=$(grep -c '"q_rad": ' "$work/large.json")
  if [ "$kept" -eq 5000 ] && grep -q '"sample_total": 12000' "$work/large.json" && [ "$result_bytes" -lt 2000000 ] &&
     [ "$page_bytes" -lt 1500000 ]; then ok; else
    fail "12,000 samples: $kept samples kept in a $result_bytes-byte result, a $page_bytes-byte page"; fi
  markers=$(figures_of "$work/large.dom" | grep '^fig-residual-q1' | grep -o '<circle data-series' | wc -l)
  arrows=$(figures_of "$work/large.dom" | grep '^fig-vectors-xy' | grep -o '<line data-series' | wc -l)
  if [ "$markers" -eq 1000 ] && [ "$arrows" -eq 800 ] &&
     grep -q "1,000 of 5,000 samples drawn, evenly spaced." "$work/large/index.html" &&
     grep -q "The report keeps 5,000 of the run's 12,000 samples" "$work/large/index.html"; then ok; else
    fail "12,000 samples: $markers markers in fig-residual-q1, $arrows arrows in fig-vectors-xy, or no caption saying so"; fi
  if "$hivecal" report --calibration "$work/large.json" --out "$work/large-again" >/dev/null &&
     cmp -s <(sed -n '/<h2>Table 2/,$p' "$work/large/index.html") <(sed -n '/<h2>Table 2/,$p' "$work/large-again/index.html")
  then ok; else fail "report --calibration of the 12,000-sample result draws another page"; fi
  echo "large: 12,000 samples, result $result_bytes bytes (5,000 samples kept), page $page_bytes bytes"
else
  fail "calibrate 12,000 samples"
fi

echo "report.render: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
