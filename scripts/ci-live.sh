#!/usr/bin/env bash
# Live mode end to end (the book, "A controller in Python"): examples/controller.py serves the
# calls of scenarios/fifo.toml through the gateway without violations, and
# examples/check_gateway.py finds the gateway's input image and LAS as the bus trace has them.
# Needs target/release/asi-lift (.ci/run builds it); installs pymodbus into target/ci-venv.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/asi-lift
pymodbus=3.16.1
venv=target/ci-venv
py="$venv/bin/python"
if ! "$py" -c "import pymodbus, sys; sys.exit(pymodbus.__version__ != '$pymodbus')" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check "pymodbus==$pymodbus"
fi

dir="$(mktemp -d)"
serve_pid=
cleanup() {
  if [ -n "$serve_pid" ] && kill -0 "$serve_pid" 2>/dev/null; then
    kill "$serve_pid" 2>/dev/null || true
  fi
  rm -rf "$dir"
}
trap cleanup EXIT

# Port 0: the system picks a free port, and serve names it on standard error once it listens.
"$bin" serve fifo --controller external --speed max --until 120s --listen 127.0.0.1:0 \
  --report "$dir/report.json" --format json >"$dir/serve.out" 2>"$dir/serve.err" &
serve_pid=$!
port=
deadline=$((SECONDS + 30))
while [ -z "$port" ]; do
  port="$(sed -n 's/.*gateway on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$dir/serve.err")"
  if [ -z "$port" ]; then
    if ! kill -0 "$serve_pid" 2>/dev/null || [ "$SECONDS" -ge "$deadline" ]; then
      echo "ci-live: asi-lift serve did not start listening" >&2
      cat "$dir/serve.err" >&2
      exit 1
    fi
    sleep 0.1
  fi
done

started=$SECONDS
timeout 300 "$py" examples/controller.py --port "$port"
echo "ci-live: the example ran for $((SECONDS - started)) s of wall time"
# serve ends at --until and writes its report; give it a minute at most.
deadline=$((SECONDS + 60))
while kill -0 "$serve_pid" 2>/dev/null && [ "$SECONDS" -lt "$deadline" ]; do
  sleep 0.2
done
serve_status=0
if kill -0 "$serve_pid" 2>/dev/null; then
  echo "ci-live: asi-lift serve did not end" >&2
  exit 1
fi
wait "$serve_pid" || serve_status=$?
serve_pid=
cat "$dir/serve.out"

"$py" - "$dir/report.json" "$serve_status" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
bad = []
if r["violations"]:
    bad.append(f"violations: {r['violations']}")
unserved = [p["button"] for p in r["passengers"] if p["served_at_s"] is None]
if not r["passengers"] or unserved:
    bad.append(f"presses not served: {unserved or 'no presses at all'}")
live = r["live"]
if live["exceptions"] or live["watchdog_trips"]:
    bad.append(f"exceptions {live['exceptions']}, watchdog trips {live['watchdog_trips']}")
if sys.argv[2] != "0":
    bad.append(f"asi-lift serve exited with {sys.argv[2]}")
for p in r["passengers"]:
    print(f"ci-live: {p['button']:10} pressed at {p['pressed_at_s']:5.1f} s, served at {p['served_at_s']} s")
if bad:
    sys.exit("ci-live: " + "; ".join(bad))
EOF

timeout 300 "$py" examples/check_gateway.py
