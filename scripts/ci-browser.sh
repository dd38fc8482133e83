#!/usr/bin/env bash
# The live view in a real headless browser (the book, "Live view in the browser"): installs
# Debian's chromium and chromium-driver if they are missing, starts chromedriver on a free
# loopback port and runs the browser test (the `browser` feature of asi-lift-browser-test).
# With ASI_LIFT_SCREENSHOT=FILE the test also writes a screenshot of the page during a trip.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
  sudo=""
  if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -q
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium chromium-driver
fi
# Build first, so that chromedriver does not wait through the compile.
cargo test -p asi-lift-browser-test --features browser --no-run
port="$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
log="$(mktemp)"
chromedriver --port="$port" >"$log" 2>&1 &
driver=$!
trap 'kill "$driver" 2>/dev/null || true; rm -f "$log"' EXIT
for _ in $(seq 100); do
  if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then break; fi
  sleep 0.1
done
if ! CHROMEDRIVER_URL="http://127.0.0.1:$port" CHROMIUM="$(command -v chromium)" \
    cargo test -p asi-lift-browser-test --features browser -- --nocapture; then
  echo "chromedriver's log:" >&2
  cat "$log" >&2
  exit 1
fi
