//! The command mailbox in parameter words 32..49 (table 4.1 of the lift thesis "Příkaz | T |
//! Výsledek"; docs/master.md).
//!
//! **Protocol** (decision; the lift thesis gives only the word layout): the PLC writes the request
//! bytes into output words 33..49 (byte 1 in the high half of word 33), then the command into
//! output word 32 bits 15..8 and *toggles* T (bit 7). The master takes a job when the output T
//! differs from the T of its last result. When the job is done it writes the response bytes into
//! input words 33..49, then input word 32 = command (bits 15..8), T = the job's T (bit 7),
//! result (bits 6..0). The job is complete when input T equals output T.
//!
//! A slave address byte holds the address in bits 4..0 and the B select in bit 5.
//!
//! | command | code | request bytes | response bytes |
//! |---|---|---|---|
//! | Write_Parameter | 0x01 | addr, parameter | parameter echo |
//! | Read_Status | 0x02 | addr | S3..S0 |
//! | Change_Address | 0x03 | old addr, new addr | — |
//! | Read_Projected (LPS, PCD, PP) | 0x04 | addr | projected 0/1, IO·16+ID, ID1·16+ID2, PP |
//! | Write_Projected (configuration mode only) | 0x05 | addr, projected 0/1, IO·16+ID, ID1·16+ID2, PP | — |
//! | Read_Actual (LDS, CDI, PI) | 0x06 | addr | detected 0/1, IO·16+ID, ID1·16+ID2, PI |
//! | Store_Actual_Configuration (configuration mode only) | 0x07 | — | — |
//! | Set_Operation_Mode | 0x08 | 0 protected / 1 configuration | — |
//! | Read_List | 0x09 | 0 LDS, 1 LAS, 2 LPS, 3 LCS (cleared by reading), 4 LPF | 8 bytes, byte 1 = slaves 0..7 |
//! | Read_Flags | 0x0A | — | EC flags high byte, low byte (docs/asi.md §5.3 values) |

use crate::image::{Image, MAILBOX_BYTES, MAILBOX_WORD};
use asi_phy::SlaveAddr;

/// Mailbox command codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Command {
    /// Write a slave's parameter (a bus job).
    WriteParameter = 0x01,
    /// Read a slave's status (a bus job).
    ReadStatus = 0x02,
    /// Move a slave to another address (Delete_Address + Address_Assignment; a bus job).
    ChangeAddress = 0x03,
    /// Read one address of the projected configuration.
    ReadProjected = 0x04,
    /// Write one address of the projected configuration (configuration mode only).
    WriteProjected = 0x05,
    /// Read one address of the detected configuration.
    ReadActual = 0x06,
    /// Take the detected configuration as the projected one (configuration mode only).
    StoreActual = 0x07,
    /// Protected or configuration mode.
    SetMode = 0x08,
    /// Read LDS, LAS, LPS, LCS or LPF.
    ReadList = 0x09,
    /// Read the execution-control flags.
    ReadFlags = 0x0A,
}

impl Command {
    /// The command with code `c`.
    pub const fn from_code(c: u8) -> Option<Command> {
        Some(match c {
            0x01 => Command::WriteParameter,
            0x02 => Command::ReadStatus,
            0x03 => Command::ChangeAddress,
            0x04 => Command::ReadProjected,
            0x05 => Command::WriteProjected,
            0x06 => Command::ReadActual,
            0x07 => Command::StoreActual,
            0x08 => Command::SetMode,
            0x09 => Command::ReadList,
            0x0A => Command::ReadFlags,
            _ => return None,
        })
    }
}

/// Mailbox result codes (input word 32 bits 6..0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum JobResult {
    /// Done.
    Ok = 0,
    /// The slave did not answer (after the repeat).
    NoResponse = 1,
    /// An argument is out of range.
    InvalidArgument = 2,
    /// Not allowed in this mode or phase.
    NotAllowed = 3,
    /// Unknown command code.
    UnknownCommand = 4,
    /// No slave detected at the address.
    SlaveNotFound = 5,
    /// The target address is already taken.
    AddressOccupied = 6,
}

impl JobResult {
    /// The result with code `c`.
    pub const fn from_code(c: u8) -> Option<JobResult> {
        Some(match c {
            0 => JobResult::Ok,
            1 => JobResult::NoResponse,
            2 => JobResult::InvalidArgument,
            3 => JobResult::NotAllowed,
            4 => JobResult::UnknownCommand,
            5 => JobResult::SlaveNotFound,
            6 => JobResult::AddressOccupied,
            _ => return None,
        })
    }
}

/// The mailbox byte of a slave address: bits 4..0 address, bit 5 = B.
pub const fn address_byte(a: SlaveAddr) -> u8 {
    match a.select {
        asi_phy::Select::A => a.address.get(),
        asi_phy::Select::B => a.address.get() | 0x20,
    }
}

/// The slave address of a mailbox byte (`None` for 0B or bits above 5).
pub const fn address_from_byte(b: u8) -> Option<SlaveAddr> {
    if b & 0xC0 != 0 {
        return None;
    }
    if b & 0x20 != 0 {
        SlaveAddr::b(b & 0x1F)
    } else {
        SlaveAddr::a(b & 0x1F)
    }
}

/// A job as the PLC posted it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MailboxRequest {
    /// The command code.
    pub command: u8,
    /// T of the request.
    pub toggle: bool,
    /// Request bytes 1..34 (index 0 = byte 1).
    pub bytes: [u8; MAILBOX_BYTES],
}

/// PLC side: posts a job into the output image (arguments, command, T toggled).
pub fn post(output: &mut Image, command: Command, args: &[u8]) {
    for k in 1..=MAILBOX_BYTES {
        output.set_mailbox_byte(k, args.get(k - 1).copied().unwrap_or(0));
    }
    let w = output.word(MAILBOX_WORD);
    let t = (w ^ 0x80) & 0x80;
    output.set_word(MAILBOX_WORD, ((command as u16) << 8) | t);
}

/// PLC side: the result of the last posted job if it is complete: (command, result, response
/// bytes). An unknown result code reads as `None`.
pub fn completed(input: &Image, output: &Image) -> Option<(u8, JobResult, [u8; MAILBOX_BYTES])> {
    let wi = input.word(MAILBOX_WORD);
    let wo = output.word(MAILBOX_WORD);
    if (wi ^ wo) & 0x80 != 0 || wi >> 8 != wo >> 8 {
        return None;
    }
    let mut bytes = [0u8; MAILBOX_BYTES];
    for (k, b) in bytes.iter_mut().enumerate() {
        *b = input.mailbox_byte(k + 1);
    }
    Some((
        (wi >> 8) as u8,
        JobResult::from_code((wi & 0x7F) as u8)?,
        bytes,
    ))
}

/// The master's side of the mailbox: which job it has taken.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Mailbox {
    last_t: bool,
    busy: bool,
}

impl Mailbox {
    /// A new job if the PLC toggled T and no job is running.
    ///
    /// Asked before every call the master sends, and nearly always the answer is no: that
    /// check is inlined into the caller, copying the request out of the image is not.
    #[inline]
    pub(crate) fn take(&mut self, output: &Image) -> Option<MailboxRequest> {
        let w = output.word(MAILBOX_WORD);
        let t = w & 0x80 != 0;
        if self.busy || t == self.last_t {
            return None;
        }
        self.take_posted(output, w, t)
    }

    /// Whether [`Mailbox::take`] would take a job now.
    pub(crate) fn posted(&self, output: &Image) -> bool {
        !self.busy && (output.word(MAILBOX_WORD) & 0x80 != 0) != self.last_t
    }

    /// Takes the job the PLC has just posted (output word 32 = `w`, its T = `t`).
    #[inline(never)]
    fn take_posted(&mut self, output: &Image, w: u16, t: bool) -> Option<MailboxRequest> {
        self.busy = true;
        let mut bytes = [0u8; MAILBOX_BYTES];
        for (k, b) in bytes.iter_mut().enumerate() {
            *b = output.mailbox_byte(k + 1);
        }
        Some(MailboxRequest {
            command: (w >> 8) as u8,
            toggle: t,
            bytes,
        })
    }

    /// Writes the result of `req` into the input image.
    pub(crate) fn finish(
        &mut self,
        input: &mut Image,
        req: &MailboxRequest,
        result: JobResult,
        response: &[u8],
    ) {
        for k in 1..=MAILBOX_BYTES {
            input.set_mailbox_byte(k, response.get(k - 1).copied().unwrap_or(0));
        }
        input.set_word(
            MAILBOX_WORD,
            ((req.command as u16) << 8) | ((req.toggle as u16) << 7) | result as u16,
        );
        self.last_t = req.toggle;
        self.busy = false;
    }

    /// Forgets a running job (power fail); its result is written as `NoResponse`.
    pub(crate) fn abort(&mut self, input: &mut Image, req: &MailboxRequest) {
        self.finish(input, req, JobResult::NoResponse, &[]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_round_trip_through_the_images() {
        let mut input = Image::default();
        let mut output = Image::default();
        let mut mb = Mailbox::default();
        assert_eq!(mb.take(&output), None);
        post(&mut output, Command::ReadStatus, &[5]);
        assert_eq!(output.word(32), 0x0280);
        assert_eq!(output.word(33), 0x0500);
        assert_eq!(completed(&input, &output), None);
        let req = mb.take(&output).expect("job");
        assert_eq!(req.command, 2);
        assert_eq!(req.bytes[0], 5);
        assert_eq!(mb.take(&output), None, "one job at a time");
        mb.finish(&mut input, &req, JobResult::Ok, &[0b0010]);
        assert_eq!(input.word(32), 0x0280);
        let (cmd, res, bytes) = completed(&input, &output).expect("done");
        assert_eq!((cmd, res, bytes[0]), (2, JobResult::Ok, 0b0010));
        assert_eq!(mb.take(&output), None, "same T: no new job");
        post(&mut output, Command::ReadFlags, &[]);
        assert_eq!(output.word(32), 0x0A00);
        assert!(mb.take(&output).is_some());
    }

    #[test]
    fn address_bytes() {
        let b5 = SlaveAddr::b(5).expect("5B");
        assert_eq!(address_byte(b5), 0x25);
        assert_eq!(address_from_byte(0x25), Some(b5));
        assert_eq!(address_from_byte(0x20), None);
        assert_eq!(address_from_byte(0x40), None);
    }
}
