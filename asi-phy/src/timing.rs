//! Bus timing: bit time, pauses, reply window (docs/physical-layer.md "Timing"; docs/asi.md §2.3).
//!
//! All spans are measured between pulses: a request occupies 14 bit times from its first pulse
//! (start of the start bit) to its last (end of the end bit), a response 7. With the defaults a
//! transaction takes 84 + 18 + 42 + 10 = 154 µs, the figure of the lift thesis (§2.1), and a
//! request that gets no answer takes the same slot: 84 + 60 + 10 = 154 µs.

use crate::time::SimDuration;

/// The timing of one AS-i segment. Build it with [`BusTiming::default`] or
/// [`BusTiming::builder`], which checks that the values fit together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusTiming {
    bit_time: SimDuration,
    tolerance: SimDuration,
    min_pause: SimDuration,
    async_pause: SimDuration,
    master_pause: SimDuration,
    reply_min: SimDuration,
    reply_max: SimDuration,
    response_timeout: SimDuration,
    slave_pause: SimDuration,
}

/// A timing value that does not fit: the field and the rule it breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("bus timing: {field} = {value}: {rule}")]
pub struct TimingError {
    /// The field at fault.
    pub field: &'static str,
    /// Its value.
    pub value: SimDuration,
    /// The rule it breaks.
    pub rule: &'static str,
}

impl Default for BusTiming {
    /// docs/physical-layer.md: bit 6 µs, master pause 18 µs (3 bit times), replies within 2..5 bit times,
    /// response timeout 10 bit times, slave pause 10 µs; receivers tolerate ±0.5 µs of pulse
    /// jitter, end a telegram after 9 µs (1.5 bit times) of silence and need 18 µs (3 bit
    /// times) of silence after an erroneous telegram (A²SI asynchronous state).
    fn default() -> Self {
        BusTiming {
            bit_time: SimDuration::from_micros(6),
            tolerance: SimDuration::from_nanos(500),
            min_pause: SimDuration::from_micros(9),
            async_pause: SimDuration::from_micros(18),
            master_pause: SimDuration::from_micros(18),
            reply_min: SimDuration::from_micros(12),
            reply_max: SimDuration::from_micros(30),
            response_timeout: SimDuration::from_micros(60),
            slave_pause: SimDuration::from_micros(10),
        }
    }
}

/// Builds a [`BusTiming`] from the defaults; [`BusTimingBuilder::build`] checks it.
#[derive(Clone, Copy, Debug)]
pub struct BusTimingBuilder(BusTiming);

macro_rules! setters {
    ($($(#[$doc:meta])* $name:ident),* $(,)?) => {
        impl BusTimingBuilder {
            $( $(#[$doc])* pub fn $name(mut self, value: SimDuration) -> Self {
                self.0.$name = value;
                self
            } )*
        }
        impl BusTiming {
            $( $(#[$doc])* pub fn $name(&self) -> SimDuration {
                self.$name
            } )*
        }
    };
}

setters! {
    /// One bit time (6 µs); the half-bit grid is half of it.
    bit_time,
    /// The largest deviation of a pulse from the half-bit grid a receiver accepts.
    tolerance,
    /// The shortest silence that ends a telegram.
    min_pause,
    /// The silence a receiver needs before it accepts a telegram after an erroneous one. A
    /// master must leave at least this much after a corrupt or colliding telegram before its
    /// repeat, or the slaves, still asynchronous, ignore the repeat too.
    async_pause,
    /// The slaves' reply delay: last pulse of the request to first pulse of the response.
    master_pause,
    /// The earliest a slave may start its reply after the request.
    reply_min,
    /// The latest a slave may start its reply after the request.
    reply_max,
    /// How long the master waits, from the end of its request, for a response.
    response_timeout,
    /// End of the response (or of the response timeout) to the next request.
    slave_pause,
}

impl BusTiming {
    /// A builder starting from the defaults.
    pub fn builder() -> BusTimingBuilder {
        BusTimingBuilder(BusTiming::default())
    }

    /// Half a bit time: the grid the pulses sit on (3 µs).
    pub fn half_bit(&self) -> SimDuration {
        SimDuration::from_nanos(self.bit_time.as_nanos() / 2)
    }

    /// From first to last pulse of a request: 14 bit times (84 µs).
    pub fn request_span(&self) -> SimDuration {
        self.bit_time.saturating_mul(14)
    }

    /// From first to last pulse of a response: 7 bit times (42 µs).
    pub fn response_span(&self) -> SimDuration {
        self.bit_time.saturating_mul(7)
    }

    /// One transaction with a response: request, master pause, response, slave pause (154 µs).
    pub fn transaction(&self) -> SimDuration {
        self.request_span() + self.master_pause + self.response_span() + self.slave_pause
    }

    /// One transaction that gets no response: request, response timeout, slave pause.
    pub fn unanswered_transaction(&self) -> SimDuration {
        self.request_span() + self.response_timeout + self.slave_pause
    }

    fn check(self) -> Result<BusTiming, TimingError> {
        let t = &self;
        let err = |field, value, rule| Err(TimingError { field, value, rule });
        if t.bit_time.as_nanos() < 2 || t.bit_time.as_nanos() % 2 != 0 {
            return err(
                "bit_time",
                t.bit_time,
                "must be a positive even number of nanoseconds",
            );
        }
        if t.tolerance.saturating_mul(4) >= t.half_bit() {
            return err(
                "tolerance",
                t.tolerance,
                "must be below a quarter of the half-bit grid",
            );
        }
        if t.min_pause <= t.bit_time + t.tolerance.saturating_mul(2) {
            return err(
                "min_pause",
                t.min_pause,
                "must exceed one bit time plus twice the tolerance (the longest gap inside a telegram)",
            );
        }
        if t.slave_pause < t.min_pause + t.tolerance.saturating_mul(2) {
            return err(
                "slave_pause",
                t.slave_pause,
                "must be at least min_pause plus twice the tolerance, or receivers cannot see it",
            );
        }
        if t.async_pause < t.min_pause {
            return err("async_pause", t.async_pause, "must be at least min_pause");
        }
        if t.reply_min < t.min_pause {
            return err("reply_min", t.reply_min, "must be at least min_pause");
        }
        if t.reply_max < t.reply_min {
            return err("reply_max", t.reply_max, "must be at least reply_min");
        }
        if t.master_pause < t.reply_min || t.master_pause > t.reply_max {
            return err(
                "master_pause",
                t.master_pause,
                "must lie within reply_min..=reply_max",
            );
        }
        if t.response_timeout <= t.reply_max {
            return err(
                "response_timeout",
                t.response_timeout,
                "must exceed reply_max",
            );
        }
        Ok(self)
    }
}

impl BusTimingBuilder {
    /// The timing, if its values fit together.
    pub fn build(self) -> Result<BusTiming, TimingError> {
        self.0.check()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_give_the_thesis_154_us_transaction() {
        let t = BusTiming::default();
        assert_eq!(t.transaction(), SimDuration::from_micros(154));
        assert_eq!(t.unanswered_transaction(), SimDuration::from_micros(154));
        assert_eq!(t.half_bit(), SimDuration::from_micros(3));
        assert_eq!(BusTiming::builder().build(), Ok(t));
    }

    #[test]
    fn each_rule_rejects_a_timing_that_breaks_it() {
        let us = SimDuration::from_micros;
        let cases = [
            (
                BusTiming::builder().bit_time(SimDuration::from_nanos(5999)),
                "bit_time",
            ),
            (
                BusTiming::builder().tolerance(SimDuration::from_nanos(750)),
                "tolerance",
            ),
            (BusTiming::builder().min_pause(us(7)), "min_pause"),
            (BusTiming::builder().slave_pause(us(9)), "slave_pause"),
            (BusTiming::builder().async_pause(us(8)), "async_pause"),
            (
                BusTiming::builder()
                    .reply_min(us(8))
                    .min_pause(us(8))
                    .async_pause(us(8))
                    .master_pause(us(40)),
                "master_pause",
            ),
            (BusTiming::builder().reply_max(us(11)), "reply_max"),
            (
                BusTiming::builder().response_timeout(us(30)),
                "response_timeout",
            ),
        ];
        for (builder, field) in cases {
            let e = builder.build().expect_err(field);
            assert_eq!(e.field, field, "{e}");
        }
        let e = BusTiming::builder()
            .min_pause(us(7))
            .build()
            .expect_err("min_pause");
        assert_eq!(
            e.to_string(),
            "bus timing: min_pause = 7 µs: must exceed one bit time plus twice the tolerance \
             (the longest gap inside a telegram)"
        );
    }
}
