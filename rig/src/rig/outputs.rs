//! Where a run's transactions go besides the report: the transaction trace (text or JSON
//! lines), the waveform outputs (VCD, line-voltage CSV) and an observer.

use crate::waves::{RigSample, WaveOutputs, Waves, DEFAULT_WINDOW};
use asi_master::record::TransactionRecord;
use asi_phy::{Pulse, SimTime};
use asi_trace::trace::{write_record, TraceFormat};
use std::io::Write;

/// Receives every bus transaction of a run ([`super::Rig::on_transaction`]).
pub type TransactionObserver = Box<dyn FnMut(&TransactionRecord)>;

/// The outputs of a run that follow the bus transaction by transaction.
#[derive(Default)]
pub(super) struct Outputs {
    /// Where the bus's transaction trace goes, if anywhere, and in which form.
    pub trace: Option<(Box<dyn Write>, TraceFormat)>,
    trace_error: Option<String>,
    /// The VCD and line-voltage outputs, if wanted.
    pub waves: Option<Waves>,
    /// Who else wants every transaction, in the order they were added.
    pub observers: Vec<TransactionObserver>,
    /// A copy's: the original's waveforms as they stood, without writers, for the waveform
    /// outputs the copy is given before it steps on to go on from
    /// ([`Waves::continue_into`]).
    pub copied_waves: Option<Waves>,
}

/// A copy of a rig has no outputs: they are writers of the rig they were given to. It keeps
/// the state of the waveforms, for outputs of its own to go on from.
impl Clone for Outputs {
    fn clone(&self) -> Outputs {
        let waves = self.waves.as_ref().or(self.copied_waves.as_ref());
        Outputs {
            copied_waves: waves.map(|w| {
                w.continue_into(WaveOutputs {
                    vcd: Some(Box::new(std::io::sink())),
                    csv: Some(Box::new(std::io::sink())),
                    window: DEFAULT_WINDOW,
                    pulse_window: None,
                })
            }),
            ..Outputs::default()
        }
    }
}

impl Outputs {
    /// The rig steps on: a copy's waveforms not taken up by then can no longer be.
    #[inline]
    pub(super) fn stepped(&mut self) {
        if self.copied_waves.is_some() {
            self.copied_waves = None;
        }
    }

    /// Whether anything wants the transactions.
    pub(super) fn wanted(&self) -> bool {
        self.trace.is_some() || self.waves.is_some() || !self.observers.is_empty()
    }

    /// The first error writing the trace or the waveforms, if any.
    pub(super) fn error(&self) -> Option<&str> {
        self.trace_error
            .as_deref()
            .or_else(|| self.waves.as_ref().and_then(|w| w.error()))
    }

    /// Hands the transactions and line pulses since the last call to the outputs; `now` is
    /// the simulated time they reach.
    pub(super) fn transactions(
        &mut self,
        records: &[TransactionRecord],
        pulses: &[Pulse],
        now: SimTime,
    ) {
        for f in &mut self.observers {
            records.iter().for_each(f);
        }
        if let Some((out, format)) = self.trace.as_mut() {
            for r in records {
                if let Err(e) = write_record(out, r, *format) {
                    self.trace_error.get_or_insert_with(|| e.to_string());
                    self.trace = None;
                    break;
                }
            }
        }
        if let Some(w) = self.waves.as_mut() {
            w.pulses(pulses);
            for r in records {
                w.transaction(r);
            }
            w.flush(now);
        }
    }

    /// The rig's state at `t`, for the waveforms.
    pub(super) fn sample(&mut self, t: SimTime, sample: &RigSample) {
        if let Some(w) = self.waves.as_mut() {
            w.sample(t, sample);
        }
    }

    /// Flushes the trace and ends the waveforms at `now`.
    pub(super) fn finish(&mut self, now: SimTime) {
        if let Some((out, _)) = self.trace.as_mut() {
            if let Err(e) = out.flush() {
                self.trace_error.get_or_insert_with(|| e.to_string());
            }
        }
        if let Some(w) = self.waves.as_mut() {
            w.finish(now);
        }
    }
}
