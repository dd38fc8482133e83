//! The test of asi-lift's live view in a real headless browser lives in `tests/browser.rs` and
//! needs the `browser` feature, chromium and chromedriver: `bash scripts/ci-browser.sh` installs
//! them, starts chromedriver and runs it (the book, "Live view in the browser"). Without the
//! feature this package is empty, so that `cargo test --workspace` builds no WebDriver client.
