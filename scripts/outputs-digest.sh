#!/usr/bin/env bash
# Prints one line per output of the asi-lift command, `sha256  name`, for a fixed set of runs:
# every scenario of scenarios/ (report as text and JSON, trace as text and JSON lines), the VCD
# and CSV of the demo's first 10 s, their decoding, the plots of the demo (SVG and PNG) and of
# the safe drive, every stand guide (text and JSON), a live run at full speed (`serve`), `encode`,
# `timing` of three buses (text, JSON, SVG) and a short campaign. Comparing the lists of two builds shows whether a change
# altered any output:
#
#   scripts/outputs-digest.sh OLD_BINARY > old.txt
#   scripts/outputs-digest.sh target/release/asi-lift > new.txt
#   diff old.txt new.txt
#
# Run it from the repository's root. It writes only into a temporary directory.
set -euo pipefail
bin="$(realpath "$1")"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
# Outputs name their input files: run in the temporary directory with relative names, so that
# the lists of two runs compare.
# -L: the repository's scenarios/ is a link to rig/scenarios/; copy the files, not the link.
cp -rL scenarios "$out/scenarios"
cd "$out"
digest() { if [ -f "$1" ]; then sha256sum "$1" | awk -v n="$2" '{print $1 "  " n}'; else echo "missing  $2"; fi; }
for sc in scenarios/*.toml; do
  name="$(basename "$sc" .toml)"
  "$bin" run "$sc" --report "$name.txt" --trace "$name.trace.txt" >/dev/null 2>&1 || true
  "$bin" run "$sc" --format json --report "$name.json" --trace "$name.trace.jsonl" >/dev/null 2>&1 || true
  for f in "$name.txt" "$name.json" "$name.trace.txt" "$name.trace.jsonl"; do
    digest "$f" "$f"
  done
done
"$bin" run --until 10s --vcd "demo.vcd" --csv "demo.csv" --report "demo10.txt" >/dev/null 2>&1 || true
"$bin" run --until 3s --vcd "demo-late.vcd" --waveform-window 2s..2.01s --report /dev/null >/dev/null 2>&1 || true
for f in demo.vcd demo.csv demo10.txt demo-late.vcd; do digest "$f" "$f"; done
"$bin" decode "demo.csv" > "decode-csv.txt" 2>&1 || true
"$bin" decode "demo.vcd" --signal rig.bus.manchester --json > "decode-vcd.jsonl" 2>&1 || true
"$bin" decode "demo-late.vcd" --signal rig.bus.line_voltage > "decode-late.txt" 2>&1 || true
for f in decode-csv.txt decode-vcd.jsonl decode-late.txt; do digest "$f" "$f"; done
"$bin" run --until 20s --plot "demo.svg" --report /dev/null >/dev/null 2>&1 || true
"$bin" run --until 20s --plot "demo.png" --report /dev/null >/dev/null 2>&1 || true
"$bin" run scenarios/safe-drive-runaway.toml --until 35s --plot "safe-drive.svg" --report /dev/null >/dev/null 2>&1 || true
for f in demo.svg demo.png safe-drive.svg; do digest "$f" "$f"; done
for sc in scenarios/stand/*.toml; do
  name="stand-$(basename "$sc" .toml)"
  "$bin" stand "$sc" > "$name.txt" 2>&1 || true
  "$bin" stand "$sc" --format json > "$name.json" 2>&1 || true
  for f in "$name.txt" "$name.json"; do digest "$f" "$f"; done
done
"$bin" serve scenarios/fifo.toml --speed max --until 30s --listen 127.0.0.1:0 --format json --report "serve.json" >/dev/null 2>&1 || true
digest serve.json serve.json
"$bin" encode dexg 5 1010 > "encode-request.txt" 2>&1 || true
"$bin" encode --csv "encode.csv" --noise-rms 0.2 --seed 3 rdst 7B > /dev/null 2>&1 || true
for f in encode-request.txt encode.csv; do digest "$f" "$f"; done
for bus in lab 5 62ab; do
  "$bin" timing --bus "$bus" --duration 5s --samples 3 > "timing-$bus.txt" 2>&1 || true
  "$bin" timing --bus "$bus" --duration 5s --samples 3 --json --svg "timing-$bus.svg" > "timing-$bus.json" 2>&1 || true
  for f in "timing-$bus.txt" "timing-$bus.json" "timing-$bus.svg"; do digest "$f" "$f"; done
done
"$bin" campaign --runs 12 --seed 5 --profile smoke --jobs 2 --out "campaign.jsonl" --failures "fail" >/dev/null 2>&1 || true
"$bin" campaign summarize "campaign.jsonl" > "campaign-summary.txt" 2>&1 || true
for f in campaign.jsonl campaign-summary.txt; do digest "$f" "$f"; done
