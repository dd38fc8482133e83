//! Trace records go to `tracing` (target `asi_master::trace`, level TRACE), to the ring and to
//! the callback, one per transaction.

use crate::common::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use tracing::span::{Attributes, Id, Record};
use tracing::{Event, Metadata, Subscriber};

struct Count {
    events: Arc<AtomicUsize>,
    first: Arc<Mutex<String>>,
}

struct Text<'a>(&'a mut String);

impl tracing::field::Visit for Text<'_> {
    fn record_debug(&mut self, _field: &tracing::field::Field, value: &dyn std::fmt::Debug) {
        if self.0.is_empty() {
            *self.0 = format!("{value:?}");
        }
    }
}

impl Subscriber for Count {
    fn enabled(&self, m: &Metadata<'_>) -> bool {
        m.target() == "asi_master::trace"
    }
    fn new_span(&self, _: &Attributes<'_>) -> Id {
        Id::from_u64(1)
    }
    fn record(&self, _: &Id, _: &Record<'_>) {}
    fn record_follows_from(&self, _: &Id, _: &Id) {}
    fn event(&self, e: &Event<'_>) {
        if self.events.fetch_add(1, Ordering::SeqCst) == 0 {
            if let Ok(mut s) = self.first.lock() {
                e.record(&mut Text(&mut s));
            }
        }
    }
    fn enter(&self, _: &Id) {}
    fn exit(&self, _: &Id) {}
}

/// Set in the process that runs the test body, see [`every_transaction_is_one_record_everywhere`].
const ALONE: &str = "ASI_BUS_TRACING_OUT_ALONE";

/// The test body runs in a process of its own: this binary again, with only this test. A
/// scoped subscriber is not enough when other tests run buses on other threads, because
/// `tracing` settles once per call site and for the whole process whether anyone listens: if
/// another thread's bus reaches the call site first, while this subscriber is the only one, the
/// answer is "no one" (that thread's default) and the records are lost here too.
#[test]
fn every_transaction_is_one_record_everywhere() {
    if std::env::var_os(ALONE).is_none() {
        let out = std::process::Command::new(std::env::current_exe().expect("the test binary"))
            .args([
                "every_transaction_is_one_record_everywhere",
                "--test-threads=1",
            ])
            .env(ALONE, "1")
            .output()
            .expect("the test binary runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stdout}{stderr}");
        assert!(stdout.contains("test result: ok. 1 passed"), "{stdout}");
        return;
    }
    let events = Arc::new(AtomicUsize::new(0));
    let first = Arc::new(Mutex::new(String::new()));
    let sub = Count {
        events: events.clone(),
        first: first.clone(),
    };
    let calls = Arc::new(AtomicUsize::new(0));
    let c2 = calls.clone();
    let mut bus = io_bus(3);
    bus.enable_trace(16);
    bus.set_trace_callback(Some(Box::new(move |_| {
        c2.fetch_add(1, Ordering::SeqCst);
    })));
    tracing::subscriber::with_default(sub, || bus.advance_to(ms(20)));
    let n = bus.stats().transactions as usize;
    assert!(n > 50);
    assert_eq!(events.load(Ordering::SeqCst), n);
    assert_eq!(calls.load(Ordering::SeqCst), n);
    let ring = bus.trace_ring_mut().expect("ring");
    assert_eq!(ring.len(), 16);
    assert_eq!(ring.dropped() as usize, n - 16);
    let text = first.lock().map(|s| s.clone()).unwrap_or_default();
    assert!(
        text.contains("0.005000000 s  detect    0 1 00000 10000 0 1  Read_IO_Configuration 0A"),
        "{text}"
    );
    // Without ring and callback, the subscriber alone still gets every record.
    bus.enable_trace(0);
    bus.set_trace_callback(None);
    let sub = Count {
        events: events.clone(),
        first,
    };
    tracing::subscriber::with_default(sub, || bus.advance_to(ms(40)));
    let m = bus.stats().transactions as usize;
    assert!(m > n + 50);
    assert_eq!(events.load(Ordering::SeqCst), m);
    assert_eq!(calls.load(Ordering::SeqCst), n);
}
