//! An AS-i slave: the slave IC's behaviour on the bus, and the device behind its 4-bit
//! peripheral ports (docs/master.md call table, §3; docs/asi.md §4, §6).
//!
//! The [`Slave`] answers the calls of docs/master.md as the ZMD slave ICs do (docs/asi.md §4):
//! it answers only a valid request addressed to it (the bus hands it only requests its
//! receiver accepted), Data_Exchange only after a Write_Parameter since its last reset (that is
//! what activation does), Write_Extended_ID1 and Address_Assignment only at address 0. What
//! happens at the peripheral ports is the [`Peripheral`] device's business.

use asi_phy::slave_id::ACK_0110;
use asi_phy::{
    Address, Call, Nibble, Request, Response, Select, SimDuration, SimTime, SlaveAddr, SlaveCodes,
};
use core::any::Any;
use core::fmt;

/// The device behind a slave's peripheral ports.
///
/// `exchange` is called on every Data_Exchange the slave answers, at the time the slave has
/// received the request; it gets the output bits and returns the input bits for the response.
/// A plain I/O module samples its input pins and then drives its outputs; an intelligent slave
/// (S-7.3 analog) may react to the outputs within the same telegram.
pub trait Peripheral: Any + fmt::Debug + Send + PeripheralClone {
    /// Data_Exchange: output bits D3..D0 in (D2..D0 for an A/B slave), input bits out.
    fn exchange(&mut self, now: SimTime, outputs: Nibble) -> Nibble;
    /// Write_Parameter: the parameter bits; returns the parameter echo (default: the bits).
    fn write_parameter(&mut self, _now: SimTime, parameter: Nibble) -> Nibble {
        parameter
    }
    /// The slave IC was reset (power-up, Reset_Slave, broadcast reset).
    fn reset(&mut self) {}
    /// The device reports a peripheral fault (status bit S1, docs/asi.md §6.2).
    fn periphery_fault(&self) -> bool {
        false
    }
    /// A count that moves whenever what the device drives outside the bus (a display, a
    /// relay, a current) may have changed, for an application that reads what the devices
    /// drive only when something did; `None` (the default): the device does not count, and
    /// what it drives is read at every output it takes.
    fn drive_changes(&self) -> Option<u64> {
        None
    }
    /// [`Peripheral::exchange`], and whether what the device drives outside the bus may have
    /// changed in it (its [`Peripheral::drive_changes`] moved). A device that counts may
    /// override it to say so without asking its count twice.
    fn exchange_noted(&mut self, now: SimTime, outputs: Nibble) -> (Nibble, bool) {
        let before = self.drive_changes();
        let inputs = self.exchange(now, outputs);
        (inputs, self.drive_changes() != before)
    }
    /// For typed access from the application.
    fn as_any(&self) -> &dyn Any;
    /// For typed access from the application.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// A copy of a [`Peripheral`] behind a box, so that a bus can be copied with its slaves' devices
/// (a snapshot of a run): any device that is `Clone` has it.
pub trait PeripheralClone {
    /// A copy of the device, boxed.
    fn clone_box(&self) -> Box<dyn Peripheral>;
}

impl<T: Peripheral + Clone> PeripheralClone for T {
    fn clone_box(&self) -> Box<dyn Peripheral> {
        Box::new(self.clone())
    }
}

impl Clone for Box<dyn Peripheral> {
    fn clone(&self) -> Self {
        (**self).clone_box()
    }
}

/// Status bit S0: address or ID code volatile (EEPROM write in progress).
pub const S0_VOLATILE: u8 = 0b0001;
/// Status bit S1: periphery fault.
pub const S1_PERIPHERY_FAULT: u8 = 0b0010;
/// Status bit S3: non-volatile memory read error.
pub const S3_NV_ERROR: u8 = 0b1000;

/// One AS-i slave: the IC state and its device.
#[derive(Clone)]
pub struct Slave {
    name: String,
    address: Address,
    nv_address: Address,
    codes: SlaveCodes,
    nv_id1: Nibble,
    parameter: Nibble,
    data_exchange_enabled: bool,
    nv_error: bool,
    eeprom_busy_until: SimTime,
    eeprom_write_time: SimDuration,
    /// The CB, address and I4 bits ([`Slave::DATA_EXCHANGE_BITS`]) of the Data_Exchange
    /// requests the slave answers as a standard (not A/B) slave with data exchange enabled:
    /// CB 0, its address, I4 0; or [`Slave::NO_DATA_EXCHANGE`] (which no request's bits
    /// hold under the mask) for an A/B slave, at address 0 or before a Write_Parameter. Kept
    /// by [`Slave::refresh`] after every change of those.
    data_exchange_at: u16,
    /// The device counts its drive changes ([`Peripheral::drive_changes`]).
    drive_counted: bool,
    /// What the device drives may have changed since [`Slave::take_drive_moved`] last looked.
    drive_moved: bool,
    device: Box<dyn Peripheral>,
}

impl fmt::Debug for Slave {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Slave")
            .field("name", &self.name)
            .field("address", &self.addr())
            .field("codes", &self.codes)
            .field("device", &self.device)
            .finish()
    }
}

impl Slave {
    /// A slave named `name` with non-volatile address `address` (0..=31; an A/B slave's select
    /// is ID1 bit 3: 0 = A, 1 = B), `codes` and `device`, just powered up.
    pub fn new(
        name: impl Into<String>,
        address: Address,
        codes: SlaveCodes,
        device: Box<dyn Peripheral>,
    ) -> Slave {
        Slave {
            name: name.into(),
            address,
            nv_address: address,
            codes,
            nv_id1: codes.id1,
            parameter: Nibble::ALL,
            data_exchange_enabled: false,
            nv_error: false,
            eeprom_busy_until: SimTime::ZERO,
            eeprom_write_time: SimDuration::from_millis(15),
            data_exchange_at: Slave::NO_DATA_EXCHANGE,
            drive_counted: device.drive_changes().is_some(),
            drive_moved: false,
            device,
        }
    }

    /// [`Slave::data_exchange_at`](Slave) of a slave that answers no Data_Exchange the quick
    /// way: no request's bits under [`Slave::DATA_EXCHANGE_BITS`] are it.
    const NO_DATA_EXCHANGE: u16 = 0xFFFF;

    /// The bits of a request ([`Request::bits`]) that tell a Data_Exchange and its address:
    /// CB (bit 12), the address (bits 11..7) and I4 (bit 6).
    const DATA_EXCHANGE_BITS: u16 = 1 << 12 | 0x1F << 7 | 1 << 6;

    /// Works out `data_exchange_at` from the address, the ID code and the data exchange
    /// flag: called after anything that may have changed them.
    fn refresh(&mut self) {
        let quick = self.address.get() != 0 && !self.codes.is_ab() && self.data_exchange_enabled;
        self.data_exchange_at = if quick {
            u16::from(self.address.get()) << 7
        } else {
            Slave::NO_DATA_EXCHANGE
        };
    }

    /// The slave's name (for traces and errors).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Current address with A/B select.
    pub fn addr(&self) -> SlaveAddr {
        SlaveAddr {
            address: self.address,
            select: self.select(),
        }
    }

    /// The address stored in the slave's EEPROM.
    pub fn nv_address(&self) -> Address {
        self.nv_address
    }

    /// The A/B select: B for an A/B slave with ID1 bit 3 set, else A.
    pub fn select(&self) -> Select {
        if self.codes.is_ab() && self.codes.id1.bit(3) {
            Select::B
        } else {
            Select::A
        }
    }

    /// IO, ID, ID1, ID2.
    pub fn codes(&self) -> SlaveCodes {
        self.codes
    }

    /// The parameter bits last written.
    pub fn parameter(&self) -> Nibble {
        self.parameter
    }

    /// `true` once a Write_Parameter has enabled data exchange since the last reset.
    pub fn data_exchange_enabled(&self) -> bool {
        self.data_exchange_enabled
    }

    /// The device.
    pub fn device(&self) -> &dyn Peripheral {
        self.device.as_ref()
    }

    /// The device, mutable.
    pub fn device_mut(&mut self) -> &mut dyn Peripheral {
        self.device.as_mut()
    }

    /// Whether the device counts its drive changes ([`Peripheral::drive_changes`]).
    #[inline]
    pub fn drive_counted(&self) -> bool {
        self.drive_counted
    }

    /// Sets status bit S3 (non-volatile memory error), a fault hook.
    pub fn set_nv_error(&mut self, on: bool) {
        self.nv_error = on;
    }

    /// Sets how long an EEPROM write keeps S0 set.
    pub fn set_eeprom_write_time(&mut self, d: SimDuration) {
        self.eeprom_write_time = d;
    }

    /// Status S3..S0 at `now` (docs/asi.md §6.2, spec 2.1 slave).
    pub fn status(&self, now: SimTime) -> Nibble {
        let mut s = 0;
        if now < self.eeprom_busy_until || self.address != self.nv_address {
            s |= S0_VOLATILE;
        }
        if self.device.periphery_fault() {
            s |= S1_PERIPHERY_FAULT;
        }
        if self.nv_error {
            s |= S3_NV_ERROR;
        }
        Nibble::from_low_bits(s)
    }

    /// Power-up or reset: address and ID1 from EEPROM, parameter 1111, data exchange disabled,
    /// the device reset.
    pub fn reset(&mut self) {
        self.address = self.nv_address;
        self.codes.id1 = self.nv_id1;
        self.parameter = Nibble::ALL;
        self.data_exchange_enabled = false;
        self.refresh();
        self.device.reset();
    }

    fn is_me(&self, address: Address, select: Select) -> bool {
        address == self.address && select == self.select()
    }

    /// The output bits of `req` if it is a Data_Exchange this slave answers as a standard
    /// (not A/B) slave: nearly every request a slave is handed, told from the request's bits
    /// without decoding its call. A Data_Exchange is CB 0 and I4 0 at an address other than 0
    /// ([`Request::as_data_exchange`]); a standard slave's select is always A, so the address
    /// alone says it is meant; `data_exchange_at` holds CB 0, I4 0 and the address only for
    /// a standard slave at an address other than 0 with data exchange enabled, so one
    /// comparison of the masked bits tells all. `None` sends the request the long way,
    /// through [`Slave::handle_call`]'s match of its call.
    #[inline]
    fn standard_data_exchange(&self, req: Request) -> Option<Nibble> {
        (req.bits() & Slave::DATA_EXCHANGE_BITS == self.data_exchange_at)
            .then(|| Nibble::from_low_bits(req.info()))
    }

    /// `true` if `req` is Read_Status with select A (CB 1, I4..I0 11110: ~Sel in I3) to this
    /// slave, an A slave or a standard one: the other request a slave is handed often (the
    /// master's management phase reads one active slave's status every cycle), told from its
    /// bits as [`Request::call`] tells it (with I3 set it is Read_Status at address 0 too),
    /// without decoding the call.
    #[inline]
    fn is_read_status_a(&self, req: Request) -> bool {
        req.cb()
            && req.info() == 0b11110
            && req.address() == self.address
            && self.select() == Select::A
    }

    /// The slave's answer to a valid request received at `now`, or `None` (not addressed, or a
    /// call it ignores). Broadcast reset resets the slave and gets no answer.
    ///
    /// The standard Data_Exchange (nearly every request) is answered here; every other
    /// request out of line ([`Slave::handle_other`]), so that the common answer does not
    /// save and restore the registers the others need. Inlined into the bus's quick
    /// transaction, where nearly every request is taken.
    #[inline(always)]
    pub fn handle(&mut self, now: SimTime, req: Request) -> Option<Response> {
        if let Some(outputs) = self.standard_data_exchange(req) {
            let (inputs, moved) = self.device.exchange_noted(now, outputs);
            self.drive_moved |= moved;
            return Some(Response::new(inputs));
        }
        self.handle_other(now, req)
    }

    /// Whether what the device drives outside the bus may have changed (its count moved,
    /// [`Peripheral::drive_changes`]) in the calls [`Slave::handle`] took since the last
    /// look; forgets it.
    #[inline(always)]
    pub fn take_drive_moved(&mut self) -> bool {
        core::mem::take(&mut self.drive_moved)
    }

    /// [`Slave::handle`] of a request that is not a standard Data_Exchange to this slave.
    #[inline(never)]
    fn handle_other(&mut self, now: SimTime, req: Request) -> Option<Response> {
        if self.is_read_status_a(req) {
            // The master's status poll: it changes nothing, so nothing to refresh.
            return Some(Response::new(self.status(now)));
        }
        let before = self.device.drive_changes();
        let answer = self.handle_call(now, req);
        self.refresh();
        self.drive_moved |= self.device.drive_changes() != before;
        answer
    }

    /// [`Slave::handle`] of a request that is not a standard Data_Exchange to this slave: the
    /// match of its call. The caller refreshes `data_exchange_at`.
    fn handle_call(&mut self, now: SimTime, req: Request) -> Option<Response> {
        let ab = self.codes.is_ab();
        let data = match req.call() {
            Call::DataExchange { address, data } => {
                let (sel, outputs) = if ab {
                    req.ab_payload()?
                } else {
                    (Select::A, data)
                };
                if !self.is_me(address, sel) || !self.data_exchange_enabled {
                    return None;
                }
                self.device.exchange(now, outputs)
            }
            Call::WriteParameter { address, parameter } => {
                let (sel, p) = if ab {
                    req.ab_payload()?
                } else {
                    (Select::A, parameter)
                };
                if !self.is_me(address, sel) {
                    return None;
                }
                self.parameter = p;
                self.data_exchange_enabled = true;
                self.device.write_parameter(now, p)
            }
            Call::AddressAssignment { new_address } => {
                if self.address.get() != 0 || new_address.get() == 0 {
                    return None;
                }
                self.address = new_address;
                self.nv_address = new_address;
                self.eeprom_busy_until = now + self.eeprom_write_time;
                ACK_0110
            }
            Call::WriteExtendedId1 { id1 } => {
                if self.address.get() != 0 {
                    return None;
                }
                self.codes.id1 = id1;
                self.nv_id1 = id1;
                self.eeprom_busy_until = now + self.eeprom_write_time;
                Nibble::ZERO
            }
            Call::DeleteAddress { address, select } => {
                if !self.is_me(address, select) {
                    return None;
                }
                self.address = Address::ZERO;
                Nibble::ZERO
            }
            Call::ResetSlave { address, select } => {
                if !self.is_me(address, select) {
                    return None;
                }
                self.reset();
                ACK_0110
            }
            Call::ReadIoConfiguration { address, select } if self.is_me(address, select) => {
                self.codes.io
            }
            Call::ReadIdCode { address, select } if self.is_me(address, select) => self.codes.id,
            Call::ReadId1 { address, select } if self.is_me(address, select) => self.codes.id1,
            Call::ReadId2 { address, select } if self.is_me(address, select) => self.codes.id2,
            Call::ReadStatus { address, select } if self.is_me(address, select) => self.status(now),
            Call::BroadcastReset => {
                self.reset();
                return None;
            }
            _ => return None,
        };
        Some(Response::new(data))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device that answers with its outputs turned round and notes every call.
    #[derive(Clone, Debug, Default)]
    struct Recorder {
        calls: Vec<(SimTime, Nibble)>,
        parameters: Vec<Nibble>,
        resets: u32,
    }

    impl Peripheral for Recorder {
        fn exchange(&mut self, now: SimTime, outputs: Nibble) -> Nibble {
            self.calls.push((now, outputs));
            Nibble::from_low_bits(!outputs.get())
        }
        fn write_parameter(&mut self, _now: SimTime, parameter: Nibble) -> Nibble {
            self.parameters.push(parameter);
            parameter
        }
        fn reset(&mut self) {
            self.resets += 1;
        }
        fn as_any(&self) -> &dyn Any {
            self
        }
        fn as_any_mut(&mut self) -> &mut dyn Any {
            self
        }
    }

    /// [`Slave::handle`] as it was, every request through the match of its call (the
    /// reference for the Data_Exchange fast path).
    fn reference_handle(s: &mut Slave, now: SimTime, req: Request) -> Option<Response> {
        let ab = s.codes.is_ab();
        let data = match req.call() {
            Call::DataExchange { address, data } => {
                let (sel, outputs) = if ab {
                    req.ab_payload()?
                } else {
                    (Select::A, data)
                };
                if !s.is_me(address, sel) || !s.data_exchange_enabled {
                    return None;
                }
                s.device.exchange(now, outputs)
            }
            Call::WriteParameter { address, parameter } => {
                let (sel, p) = if ab {
                    req.ab_payload()?
                } else {
                    (Select::A, parameter)
                };
                if !s.is_me(address, sel) {
                    return None;
                }
                s.parameter = p;
                s.data_exchange_enabled = true;
                s.device.write_parameter(now, p)
            }
            Call::AddressAssignment { new_address } => {
                if s.address.get() != 0 || new_address.get() == 0 {
                    return None;
                }
                s.address = new_address;
                s.nv_address = new_address;
                s.eeprom_busy_until = now + s.eeprom_write_time;
                ACK_0110
            }
            Call::WriteExtendedId1 { id1 } => {
                if s.address.get() != 0 {
                    return None;
                }
                s.codes.id1 = id1;
                s.nv_id1 = id1;
                s.eeprom_busy_until = now + s.eeprom_write_time;
                Nibble::ZERO
            }
            Call::DeleteAddress { address, select } => {
                if !s.is_me(address, select) {
                    return None;
                }
                s.address = Address::ZERO;
                Nibble::ZERO
            }
            Call::ResetSlave { address, select } => {
                if !s.is_me(address, select) {
                    return None;
                }
                s.reset();
                ACK_0110
            }
            Call::ReadIoConfiguration { address, select } if s.is_me(address, select) => s.codes.io,
            Call::ReadIdCode { address, select } if s.is_me(address, select) => s.codes.id,
            Call::ReadId1 { address, select } if s.is_me(address, select) => s.codes.id1,
            Call::ReadId2 { address, select } if s.is_me(address, select) => s.codes.id2,
            Call::ReadStatus { address, select } if s.is_me(address, select) => s.status(now),
            Call::BroadcastReset => {
                s.reset();
                return None;
            }
            _ => return None,
        };
        Some(Response::new(data))
    }

    /// Every field of the slave that a call may change, and its device's notes.
    fn state(s: &Slave) -> String {
        format!(
            "{:?} {:?} {:?} {:?} {:?} {} {:?} {:?}",
            s.address,
            s.nv_address,
            s.codes,
            s.nv_id1,
            s.parameter,
            s.data_exchange_enabled,
            s.eeprom_busy_until,
            s.device
        )
    }

    /// A valid request with the body CB A4..A0 I4..I0 `body` (11 bits), parity computed.
    fn request(body: u16) -> Request {
        let pb = (body.count_ones() & 1) as u16;
        Request::from_bits((body << 2) | (pb << 1) | 1).expect("a valid request")
    }

    /// A slave at `address` with `codes` and a recording device, Data_Exchange `enabled`.
    fn test_slave(address: u8, codes: SlaveCodes, enabled: bool) -> Slave {
        let address = Address::new(address).expect("an address");
        let mut s = Slave::new("s", address, codes, Box::<Recorder>::default());
        s.data_exchange_enabled = enabled;
        s.refresh();
        s
    }

    #[test]
    fn every_request_gets_the_reference_answer_and_effect() {
        let now = SimTime::from_millis(3);
        let mut checked = 0;
        for address in [0, 1, 7, 21, 31] {
            for id in [0x0, 0x7, SlaveCodes::ID_AB] {
                for id1 in [0x0, 0x7, 0x8, 0xF] {
                    for enabled in [false, true] {
                        let codes = SlaveCodes::new(7, id, id1, 0xF);
                        let slave = || test_slave(address, codes, enabled);
                        let (mut fast, mut slow) = (slave(), slave());
                        for body in 0..1u16 << 11 {
                            let req = request(body);
                            let answer = fast.handle(now, req);
                            assert_eq!(answer, reference_handle(&mut slow, now, req), "{req:?}");
                            assert_eq!(state(&fast), state(&slow), "{req:?}");
                            checked += answer.is_some() as u32;
                        }
                    }
                }
            }
        }
        assert!(checked > 0);
    }

    /// A device that lights a lamp from output bit 0 (a parameter write or a reset puts it
    /// out) and counts the lamp's changes.
    #[derive(Clone, Debug, Default)]
    struct Lamp {
        on: bool,
        changes: u64,
    }

    impl Lamp {
        fn set(&mut self, on: bool) {
            if on != self.on {
                self.on = on;
                self.changes += 1;
            }
        }
    }

    impl Peripheral for Lamp {
        fn exchange(&mut self, _now: SimTime, outputs: Nibble) -> Nibble {
            self.set(outputs.bit(0));
            Nibble::ZERO
        }
        fn write_parameter(&mut self, _now: SimTime, parameter: Nibble) -> Nibble {
            self.set(false);
            parameter
        }
        fn reset(&mut self) {
            self.set(false);
        }
        fn drive_changes(&self) -> Option<u64> {
            Some(self.changes)
        }
        fn as_any(&self) -> &dyn Any {
            self
        }
        fn as_any_mut(&mut self) -> &mut dyn Any {
            self
        }
    }

    /// Every request, to a slave whose lamp is lit and to one whose lamp is out: the slave
    /// notes a possible drive change exactly when the call moved the device's count; a device
    /// that does not count never moves one.
    #[test]
    fn a_call_that_moves_the_drive_count_is_noted() {
        let now = SimTime::from_millis(3);
        let address = Address::new(7).expect("7");
        let codes = SlaveCodes::new(7, 0xF, 0xF, 0xF);
        let (mut moved, mut kept) = (0, 0);
        for lit in [false, true] {
            for body in 0..1u16 << 11 {
                let mut s = Slave::new("lamp", address, codes, Box::<Lamp>::default());
                s.data_exchange_enabled = true;
                s.refresh();
                let lamp = |s: &Slave| {
                    s.device()
                        .as_any()
                        .downcast_ref::<Lamp>()
                        .expect("a lamp")
                        .changes
                };
                s.device_mut()
                    .as_any_mut()
                    .downcast_mut::<Lamp>()
                    .expect("a lamp")
                    .set(lit);
                let before = lamp(&s);
                let _ = s.handle(now, request(body));
                let noted = s.take_drive_moved();
                assert_eq!(noted, lamp(&s) != before, "lit {lit}, {:?}", request(body));
                assert!(!s.take_drive_moved(), "noted once");
                if noted {
                    moved += 1;
                } else {
                    kept += 1;
                }
            }
            let mut r = test_slave(7, codes, true);
            for body in 0..1u16 << 11 {
                let _ = r.handle(now, request(body));
                assert!(!r.take_drive_moved(), "{:?}", request(body));
            }
        }
        assert!(moved > 0 && kept > 0, "{moved} moved, {kept} kept");
    }

    proptest::proptest! {
        /// Runs of random requests, most of them to address 0 or to the slave's address (so
        /// that Write_Extended_ID1, Address_Assignment, Delete_Address, Write_Parameter and
        /// the resets follow one another in any order, which one pass over every request
        /// does not give), get the reference's answers and effects after every request.
        #[test]
        fn runs_of_requests_get_the_reference_answers_and_effects(
            address in 0..32u8,
            id in proptest::sample::select(vec![0x0u8, 0x7, SlaveCodes::ID_AB]),
            id1 in 0..16u8,
            enabled in proptest::prelude::any::<bool>(),
            run in proptest::collection::vec(
                (0..3u8, proptest::prelude::any::<bool>(), 0..32u16, 0..32u16),
                1..100,
            ),
        ) {
            let now = SimTime::from_millis(3);
            let codes = SlaveCodes::new(7, id, id1, 0xF);
            let slave = || test_slave(address, codes, enabled);
            let (mut fast, mut slow) = (slave(), slave());
            for (to, cb, other, info) in run {
                let a = match to {
                    0 => 0,
                    1 => u16::from(fast.address.get()),
                    _ => other,
                };
                let req = request(u16::from(cb) << 10 | a << 5 | info);
                let answer = fast.handle(now, req);
                proptest::prop_assert_eq!(answer, reference_handle(&mut slow, now, req));
                proptest::prop_assert_eq!(state(&fast), state(&slow));
            }
        }
    }
}
