#!/usr/bin/env bash
# The user guide (book/, mdBook): builds it with a pinned mdbook, checks that no internal
# link of the HTML is broken, and runs the examples it and the README show. mdbook only
# renders book/src, so a link that leaves it builds fine and is broken on the page;
# scripts/check-book-links.py catches that.
set -euo pipefail
cd "$(dirname "$0")/.."
# Pinned, so that every machine renders the same book and a new release cannot break CI.
MDBOOK_VERSION=0.4.52
tools="target/tools"
mdbook="$tools/bin/mdbook"
if ! [ -x "$mdbook" ] || [ "$("$mdbook" --version)" != "mdbook v$MDBOOK_VERSION" ]; then
  # Only the search feature: no `serve`/`watch`, which CI never uses and which double the
  # build (tokio, axum, notify). Several minutes on 2 cores, once per target/.
  cargo install mdbook --version "$MDBOOK_VERSION" --locked --root "$tools" \
    --no-default-features --features search
fi
set -x
"$mdbook" build book
python3 scripts/check-book-links.py book/book
# The examples the guide and the README show, run as a reader would, with the release build.
cargo build --release --bin asi-lift
python3 scripts/check-examples.py target/release/asi-lift
