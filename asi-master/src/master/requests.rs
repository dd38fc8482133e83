//! The requests the master sends for each call.

use super::*;

impl Master {
    // ----- requests -------------------------------------------------------------------

    pub(super) fn data_exchange(&self, a: SlaveAddr, out: Nibble) -> Option<Request> {
        if self.detected[a.index() as usize].is_ab() {
            Request::data_exchange_ab(a.address, a.select, Nibble::from_low_bits(out.get() & 7))
                .ok()
        } else {
            Request::data_exchange(a.address, out).ok()
        }
    }

    pub(super) fn write_parameter(&self, a: SlaveAddr, p: Nibble) -> Option<Request> {
        if self.detected[a.index() as usize].is_ab() {
            Request::write_parameter_ab(a.address, a.select, Nibble::from_low_bits(p.get() & 7))
                .ok()
        } else {
            Request::write_parameter(a.address, p).ok()
        }
    }

    pub(super) fn is_ab_call(&self, tx: Tx) -> bool {
        match tx {
            Tx::ActivateParam(a)
            | Tx::ActivateDexg(a)
            | Tx::Exchange(a)
            | Tx::OfflineDefault(a)
            | Tx::Include(a, InclStep::Param | InclStep::Dexg)
            | Tx::Job(JobStep::Param(a, _)) => self.detected[a.index() as usize].is_ab(),
            _ => false,
        }
    }

    pub(super) fn activation_parameter(&self, a: SlaveAddr) -> Nibble {
        if self.projected.lps().contains(a) {
            self.projected.parameter(a)
        } else {
            self.pi[a.index() as usize]
        }
    }

    pub(super) fn read(a: SlaveAddr, r: Read) -> Option<Request> {
        let (ad, s) = (a.address, a.select);
        match r {
            Read::Io => return READS.io[a.index() as usize],
            Read::Id => Request::read_id_code(ad, s),
            Read::Id1 => Request::read_id1(ad, s),
            Read::Id2 => Request::read_id2(ad, s),
        }
        .ok()
    }

    pub(super) fn request_for(&self, tx: Tx) -> Option<Request> {
        match tx {
            Tx::Detect(a, r) | Tx::Include(a, InclStep::Read(r)) => Self::read(a, r),
            Tx::ActivateParam(a) | Tx::Include(a, InclStep::Param) => {
                self.write_parameter(a, self.activation_parameter(a))
            }
            Tx::ActivateDexg(a) | Tx::Include(a, InclStep::Dexg) | Tx::OfflineDefault(a) => {
                self.data_exchange(a, Nibble::ALL)
            }
            Tx::Exchange(a) => {
                let out = if !self.host.data_exchange_active {
                    Nibble::ALL
                } else if self.has_analog(a.index() as usize) {
                    self.analog_out[a.index() as usize]
                } else {
                    self.image.output.nibble(a)
                };
                self.data_exchange(a, out)
            }
            Tx::Status(a) | Tx::Job(JobStep::Status(a)) => READS.status[a.index() as usize],
            Tx::Include(_, InclStep::AutoId1(_, id1)) => Some(Request::write_extended_id1(id1)),
            Tx::Include(_, InclStep::AutoAssign(t)) | Tx::Job(JobStep::Assign(t)) => {
                Some(Request::address_assignment(t.address))
            }
            Tx::Job(JobStep::Param(a, p)) => self.write_parameter(a, p),
            Tx::Job(JobStep::Delete(from, _)) => {
                Request::delete_address(from.address, from.select).ok()
            }
        }
    }
}

/// Read_Status and Read_IO_Configuration of every list bit (`None` where the call does not
/// exist), built at compile time: the management call and the inclusion probe of every cycle
/// are look-ups instead of assembling the telegram and its parity bit.
pub(super) struct ReadTable {
    /// `Request::read_status` of list bit `i`.
    pub(super) status: [Option<Request>; 64],
    /// `Request::read_io_configuration` of list bit `i`.
    pub(super) io: [Option<Request>; 64],
}

/// The Read_Status and Read_IO_Configuration requests.
pub(super) static READS: ReadTable = ReadTable::build();

impl ReadTable {
    const fn build() -> ReadTable {
        let mut t = ReadTable {
            status: [None; 64],
            io: [None; 64],
        };
        let mut i = 0;
        while i < 64 {
            if let Some(a) = SlaveAddr::from_index(i) {
                t.status[i as usize] = match Request::read_status(a.address, a.select) {
                    Ok(r) => Some(r),
                    Err(_) => None,
                };
                t.io[i as usize] = match Request::read_io_configuration(a.address, a.select) {
                    Ok(r) => Some(r),
                    Err(_) => None,
                };
            }
            i += 1;
        }
        t
    }
}
