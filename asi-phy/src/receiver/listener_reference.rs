//! The listener as it was before [`Listener::accept`](super::Listener::accept) was tuned for
//! speed (the `rx` change), kept verbatim but for its name, and the equivalence property test
//! that holds the fast one to it: random frame sequences (starts and ends around the
//! pause and response-window borders, any bit count, random bits and line checks), fed to both
//! for every [`Expect`], give the same telegrams and the same listener state after every frame.

use super::checks::{Check, Checks};
use super::config::{Expect, ReceiverConfig, TelegramKind};
use super::line::Frame;
use super::{Listener, Received};
use crate::time::SimTime;

/// The reference listener; its fields mean what [`Listener`]'s of the same names mean.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct ReferenceListener {
    expect: Expect,
    async_pause: u64,
    response_window: u64,
    synced: bool,
    prev_end: Option<SimTime>,
    window_from: Option<SimTime>,
}

impl ReferenceListener {
    /// A listener that has just powered up, with the expectations of `cfg`.
    pub(super) fn new(cfg: &ReceiverConfig) -> ReferenceListener {
        ReferenceListener {
            expect: cfg.expect,
            async_pause: cfg.async_pause,
            response_window: cfg.response_window,
            synced: false,
            prev_end: None,
            window_from: None,
        }
    }

    /// Back to the power-up state.
    pub(super) fn reset(&mut self) {
        self.synced = false;
        self.prev_end = None;
        self.window_from = None;
    }

    /// The telegram this listener makes of `frame`, with all seven checks.
    pub(super) fn accept(&mut self, frame: &Frame) -> Received {
        let mut kind = match self.expect {
            Expect::Requests | Expect::Both => TelegramKind::Request,
            Expect::Responses => TelegramKind::Response,
        };
        if let Some(from) = self.window_from.take() {
            if frame.start >= from
                && frame.start.as_nanos() - from.as_nanos() <= self.response_window
            {
                kind = TelegramKind::Response;
            }
        }
        let mut failed = frame.line_failed;
        if let Some(prev) = self.prev_end {
            let silence = frame.start.as_nanos().saturating_sub(prev.as_nanos());
            if !self.synced && silence < self.async_pause {
                failed = failed.with(Check::Pause);
            }
        }
        if frame.bit_count != kind.bits() {
            failed = failed.with(Check::Length);
        }
        self.prev_end = Some(frame.end);
        let is_request = kind == TelegramKind::Request;
        if is_request || self.expect != Expect::Both {
            self.synced = failed.is_empty();
        }
        if self.expect == Expect::Both && is_request && failed.is_empty() {
            self.window_from = Some(frame.end);
        }
        Received {
            kind,
            start: frame.start,
            end: frame.end,
            pulses: frame.pulses,
            bit_count: frame.bit_count,
            raw: frame.raw,
            failed,
        }
    }

    /// The state as the fast listener keeps it: what it must equal after every frame.
    pub(super) fn state(&self) -> (Expect, u64, u64, bool, Option<SimTime>, Option<SimTime>) {
        (
            self.expect,
            self.async_pause,
            self.response_window,
            self.synced,
            self.prev_end,
            self.window_from,
        )
    }
}

impl Listener {
    /// The state in the reference's terms (see [`ReferenceListener::state`]).
    fn reference_state(&self) -> (Expect, u64, u64, bool, Option<SimTime>, Option<SimTime>) {
        (
            self.expect,
            self.async_pause,
            self.response_window,
            self.synced,
            self.prev_end,
            self.window_from,
        )
    }
}

mod equivalence {
    use super::*;
    use crate::timing::BusTiming;
    use proptest::prelude::*;

    /// One step of the test: a frame, or a reset of both listeners.
    #[derive(Clone, Debug)]
    enum Step {
        Frame(Frame),
        Reset,
    }

    /// Settings: the bus's own, and odd ones (no pause, no window, huge ones).
    fn config() -> impl Strategy<Value = ReceiverConfig> {
        let bus = BusTiming::default().receiver(Expect::Both);
        let odd = (
            prop_oneof![Just(0u64), 0u64..40_000, Just(u64::MAX), any::<u64>()],
            prop_oneof![Just(0u64), 0u64..100_000, Just(u64::MAX), any::<u64>()],
        )
            .prop_map(move |(async_pause, response_window)| ReceiverConfig {
                async_pause,
                response_window,
                ..bus
            });
        (
            prop_oneof![3 => Just(bus), 2 => odd],
            prop_oneof![
                Just(Expect::Requests),
                Just(Expect::Responses),
                Just(Expect::Both)
            ],
        )
            .prop_map(|(cfg, expect)| ReceiverConfig { expect, ..cfg })
    }

    /// A gap (or overlap, negative) between the end of one frame and the start of the next:
    /// around 0, the asynchronous pause and the response window of `cfg`, and anywhere.
    fn gap(cfg: ReceiverConfig) -> impl Strategy<Value = i128> {
        let (ap, rw) = (cfg.async_pause as i128, cfg.response_window as i128);
        prop_oneof![
            2 => -3i128..=3,
            3 => (-3i128..=3).prop_map(move |d| ap + d),
            3 => (-3i128..=3).prop_map(move |d| rw + d),
            2 => -200_000i128..200_000,
            1 => any::<u64>().prop_map(|g| g as i128),
            1 => any::<u64>().prop_map(|g| -(g as i128)),
        ]
    }

    /// Random frames with random gaps, now and then a reset; times clamped to the clock's
    /// range (so that frames pile up at 0 and at the end of time too).
    fn steps(cfg: ReceiverConfig) -> impl Strategy<Value = Vec<Step>> {
        let step = (
            gap(cfg),
            prop_oneof![4 => 0u64..200_000, 1 => any::<u64>()],
            prop_oneof![
                4 => Just(14u32),
                4 => Just(7u32),
                2 => 0u32..=17,
                1 => any::<u32>(),
            ],
            any::<u32>(),
            any::<u32>(),
            prop_oneof![3 => Just(0u8), 2 => any::<u8>()],
            0u8..20,
        );
        (
            prop_oneof![
                Just(0u64),
                0u64..1_000_000,
                Just(u64::MAX - 300_000),
                any::<u64>()
            ],
            prop::collection::vec(step, 0..40),
        )
            .prop_map(|(origin, raw_steps)| {
                let mut t = origin as i128;
                raw_steps
                    .into_iter()
                    .map(|(gap, len, bit_count, raw, pulses, failed, reset)| {
                        if reset == 0 {
                            return Step::Reset;
                        }
                        let clamp = |x: i128| x.clamp(0, u64::MAX as i128) as u64;
                        let start = clamp(t + gap);
                        let end = clamp(start as i128 + len as i128);
                        t = end as i128;
                        Step::Frame(Frame {
                            start: SimTime::from_nanos(start),
                            end: SimTime::from_nanos(end),
                            pulses,
                            bit_count,
                            raw,
                            line_failed: Checks::from_bits(failed),
                        })
                    })
                    .collect()
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4_000))]

        #[test]
        fn the_listener_equals_its_reference(
            (cfg, steps) in config().prop_flat_map(|cfg| (Just(cfg), steps(cfg))),
        ) {
            let mut fast = Listener::new(&cfg);
            let mut reference = ReferenceListener::new(&cfg);
            prop_assert_eq!(fast.reference_state(), reference.state());
            for step in &steps {
                match step {
                    Step::Frame(f) => {
                        let got = fast.accept(f);
                        let want = reference.accept(f);
                        prop_assert_eq!(got, want, "frame {:?}", f);
                        prop_assert_eq!(got.request(), want.request());
                        prop_assert_eq!(got.response(), want.response());
                    }
                    Step::Reset => {
                        fast.reset();
                        reference.reset();
                    }
                }
                prop_assert_eq!(fast.reference_state(), reference.state(), "after {:?}", step);
                prop_assert_eq!(fast.is_synchronised(), reference.synced);
            }
        }
    }
}
