//! The two telegrams, [`Request`] and [`Response`], as validated bit patterns, and why a bit
//! pattern is not one ([`TelegramError`]).

use super::fields::{Address, Nibble, Select};
use core::fmt;

/// Why a bit pattern or a set of fields is not a telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TelegramError {
    /// Bits are set above the telegram's length (14 for a request, 7 for a response).
    #[error("{received:#x} has bits set above the {len}-bit telegram")]
    TooLong {
        /// The telegram length in bits.
        len: u8,
        /// The raw value.
        received: u16,
    },
    /// The start bit is 1.
    #[error("start bit is 1, must be 0")]
    StartBit,
    /// The end bit is 0.
    #[error("end bit is 0, must be 1")]
    EndBit,
    /// The parity bit does not make the number of ones even.
    #[error("parity bit is {received}, even parity needs {expected}")]
    Parity {
        /// The parity bit even parity needs.
        expected: u8,
        /// The parity bit received.
        received: u8,
    },
    /// A field value does not fit the field.
    #[error("{field} = {value} is out of range 0..={max}")]
    FieldOutOfRange {
        /// The field's name.
        field: &'static str,
        /// The value given.
        value: u8,
        /// The largest value the field holds.
        max: u8,
    },
    /// The call cannot address slave 0: its encoding at address 0 is a different call.
    #[error("{call} cannot address slave 0 (that encoding is another call)")]
    AddressZero {
        /// The call's name.
        call: &'static str,
    },
    /// Address 0B does not exist (docs/asi.md §4.2).
    #[error("address 0B does not exist")]
    ZeroB,
}

/// A master request, 14 bits: ST CB A4..A0 I4..I0 PB EB (docs/physical-layer.md).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Request(u16);

/// A slave response, 7 bits: ST I3..I0 PB EB (docs/physical-layer.md).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Response(u8);

/// The I field of a request with its A/B select bit in I3.
const fn with_i3(low3: u8, i4: bool, i3: bool) -> u8 {
    ((i4 as u8) << 4) | ((i3 as u8) << 3) | (low3 & 0b111)
}

/// The number of pulses a telegram of `n` bits `w` (first bit highest) that starts with a 0 and
/// ends with a 1, as requests and responses do, has on the line: the mid-bit edge of every bit,
/// one before the start bit (the line idles high), one between two equal neighbours, and the
/// return to idle after the end bit. For the tables below.
const fn framed_pulses(w: u16, n: u32) -> u8 {
    let changes = ((w ^ (w >> 1)) & ((1 << (n - 1)) - 1)).count_ones();
    (n + 1 + (n - 1 - changes) + 1) as u8
}

/// The pulses of every request, by body (CB, address, information: bits 12..2).
static REQUEST_PULSES: [u8; 1 << 11] = {
    let mut t = [0u8; 1 << 11];
    let mut body = 0;
    while body < 1 << 11 {
        let pb = (body as u16).count_ones() as u16 & 1;
        t[body] = framed_pulses(((body as u16) << 2) | (pb << 1) | 1, Request::BITS);
        body += 1;
    }
    t
};

/// The pulses of every response, by its raw bits (data I3..I0 in bits 5..2): the table by
/// data, repeated for every value of the other bits, so that a look-up takes the bits as they
/// are. A response holds 7 bits; the table covers all 256 values of its byte, so the look-up
/// needs no bounds check.
static RESPONSE_PULSES: [u8; 256] = {
    let mut by_data = [0u8; 16];
    let mut d = 0;
    while d < 16 {
        let pb = (d as u8).count_ones() as u8 & 1;
        by_data[d] = framed_pulses((((d as u8) << 2) | (pb << 1) | 1) as u16, Response::BITS);
        d += 1;
    }
    let mut t = [0u8; 256];
    let mut b = 0;
    while b < 256 {
        t[b] = by_data[(b >> 2) & 0xF];
        b += 1;
    }
    t
};

/// The response to every data nibble, with its parity bit: [`Response::new`] looks it up
/// instead of counting the bits (asi-lift builds for baseline x86-64, without a popcount
/// instruction).
const RESPONSES: [u8; 16] = {
    let mut t = [0u8; 16];
    let mut d = 0;
    while d < 16 {
        let pb = (d as u8).count_ones() as u8 & 1;
        t[d] = ((d as u8) << 2) | (pb << 1) | 1;
        d += 1;
    }
    t
};

impl Request {
    /// The number of pulses of the request on the line, looked up: the bus's quick
    /// transactions make a frame of every request, and working it out from the bits took a
    /// software popcount (asi-lift builds for baseline x86-64). Held to the encoder's train
    /// ([`crate::Transmission::pulses`]) for every request by the telegram tests.
    #[inline]
    pub fn pulses(self) -> u32 {
        u32::from(REQUEST_PULSES[usize::from(self.0 >> 2) & 0x7FF])
    }

    /// Number of bits in a request.
    pub const BITS: u32 = 14;

    /// A request from its fields; computes the parity bit.
    pub const fn from_fields(
        cb: bool,
        address: Address,
        info: u8,
    ) -> Result<Request, TelegramError> {
        if info > 31 {
            return Err(TelegramError::FieldOutOfRange {
                field: "I4..I0",
                value: info,
                max: 31,
            });
        }
        let body = ((cb as u16) << 10) | ((address.0 as u16) << 5) | info as u16;
        let pb = (body.count_ones() & 1) as u16;
        Ok(Request((body << 2) | (pb << 1) | 1))
    }

    /// Checks a raw 14-bit pattern (bit 13 = ST .. bit 0 = EB).
    pub const fn from_bits(bits: u16) -> Result<Request, TelegramError> {
        if bits >> 14 != 0 {
            return Err(TelegramError::TooLong {
                len: 14,
                received: bits,
            });
        }
        if bits & (1 << 13) != 0 {
            return Err(TelegramError::StartBit);
        }
        if bits & 1 == 0 {
            return Err(TelegramError::EndBit);
        }
        let body = (bits >> 2) & 0x7FF;
        let expected = (body.count_ones() & 1) as u8;
        let received = ((bits >> 1) & 1) as u8;
        if expected != received {
            return Err(TelegramError::Parity { expected, received });
        }
        Ok(Request(bits))
    }

    /// The raw 14 bits, ST in bit 13.
    pub const fn bits(self) -> u16 {
        self.0
    }

    /// The control bit CB: 0 for data, parameter and address calls, 1 for commands.
    pub const fn cb(self) -> bool {
        self.0 & (1 << 12) != 0
    }

    /// The address field A4..A0.
    pub const fn address(self) -> Address {
        Address(((self.0 >> 7) & 0x1F) as u8)
    }

    /// The information field I4..I0.
    pub const fn info(self) -> u8 {
        ((self.0 >> 2) & 0x1F) as u8
    }

    /// The parity bit PB.
    pub const fn parity_bit(self) -> bool {
        self.0 & 0b10 != 0
    }

    /// Data_Exchange with a standard slave: outputs D3..D0 in I3..I0.
    pub const fn data_exchange(
        address: Address,
        outputs: Nibble,
    ) -> Result<Request, TelegramError> {
        if address.0 == 0 {
            return Err(TelegramError::AddressZero {
                call: "Data_Exchange",
            });
        }
        Request::from_fields(false, address, outputs.0)
    }

    /// Data_Exchange with an A/B slave: three outputs D2..D0; I3 carries the select bit,
    /// 1 for A and 0 for B (docs/master.md decision).
    pub const fn data_exchange_ab(
        address: Address,
        select: Select,
        outputs: Nibble,
    ) -> Result<Request, TelegramError> {
        if address.0 == 0 {
            return Err(TelegramError::AddressZero {
                call: "Data_Exchange",
            });
        }
        if outputs.0 > 7 {
            return Err(TelegramError::FieldOutOfRange {
                field: "A/B outputs D2..D0",
                value: outputs.0,
                max: 7,
            });
        }
        let i3 = matches!(select, Select::A);
        Request::from_fields(false, address, with_i3(outputs.0, false, i3))
    }

    /// Write_Parameter to a standard slave: P3..P0 in I3..I0.
    pub const fn write_parameter(
        address: Address,
        parameter: Nibble,
    ) -> Result<Request, TelegramError> {
        if address.0 == 0 {
            return Err(TelegramError::AddressZero {
                call: "Write_Parameter",
            });
        }
        Request::from_fields(false, address, 0x10 | parameter.0)
    }

    /// Write_Parameter to an A/B slave: P2..P0, select bit in I3 (1 = A, 0 = B).
    pub const fn write_parameter_ab(
        address: Address,
        select: Select,
        parameter: Nibble,
    ) -> Result<Request, TelegramError> {
        if address.0 == 0 {
            return Err(TelegramError::AddressZero {
                call: "Write_Parameter",
            });
        }
        if parameter.0 > 7 {
            return Err(TelegramError::FieldOutOfRange {
                field: "A/B parameter P2..P0",
                value: parameter.0,
                max: 7,
            });
        }
        let i3 = matches!(select, Select::A);
        Request::from_fields(false, address, with_i3(parameter.0, true, i3))
    }

    /// Address_Assignment: the slave at address 0 takes `new_address` (CB 0, A 00000).
    pub const fn address_assignment(new_address: Address) -> Request {
        Request::raw(false, 0, new_address.0)
    }

    /// Write_Extended_ID1 to the slave at address 0 (CB 1, A 00000, I4 0).
    pub const fn write_extended_id1(id1: Nibble) -> Request {
        Request::raw(true, 0, id1.0)
    }

    /// Delete_Address: the slave goes to address 0 (I = 0 Sel 000).
    pub const fn delete_address(
        address: Address,
        select: Select,
    ) -> Result<Request, TelegramError> {
        if address.0 == 0 {
            return Err(TelegramError::AddressZero {
                call: "Delete_Address",
            });
        }
        let sel = matches!(select, Select::B);
        Ok(Request::raw(true, address.0, with_i3(0b000, false, sel)))
    }

    /// Reset_Slave (I = 1 ~Sel 100: 11100 for A or standard slaves).
    pub const fn reset_slave(address: Address, select: Select) -> Result<Request, TelegramError> {
        Request::command(address, select, 0b100, true)
    }

    /// Read_IO_Configuration (I = 1 Sel 000).
    pub const fn read_io_configuration(
        address: Address,
        select: Select,
    ) -> Result<Request, TelegramError> {
        Request::command(address, select, 0b000, false)
    }

    /// Read_ID_Code (I = 1 Sel 001).
    pub const fn read_id_code(address: Address, select: Select) -> Result<Request, TelegramError> {
        Request::command(address, select, 0b001, false)
    }

    /// Read_ID1, the extended ID code 1 (I = 1 Sel 010).
    pub const fn read_id1(address: Address, select: Select) -> Result<Request, TelegramError> {
        Request::command(address, select, 0b010, false)
    }

    /// Read_ID2, the extended ID code 2 (I = 1 Sel 011).
    pub const fn read_id2(address: Address, select: Select) -> Result<Request, TelegramError> {
        Request::command(address, select, 0b011, false)
    }

    /// Read_Status, S3..S0 (I = 1 ~Sel 110: 11110 for A or standard slaves).
    pub const fn read_status(address: Address, select: Select) -> Result<Request, TelegramError> {
        Request::command(address, select, 0b110, true)
    }

    /// The broadcast reset (CB 1, A 11111, I 10101); no slave answers.
    pub const fn broadcast_reset() -> Request {
        Request::raw(true, 31, 0b10101)
    }

    /// `true` for the broadcast reset: the one call every slave takes, told without decoding
    /// the call (a request's bits determine its call, and this is the one request that is it).
    pub const fn is_broadcast_reset(self) -> bool {
        self.0 == Request::broadcast_reset().0
    }

    /// The address and the I3..I0 bits of a Data_Exchange (CB 0, I4 0, an address other than
    /// 0: at 0 a CB 0 call is Address_Assignment), told from the bits without decoding the
    /// whole call; `None` for every other call. For an A/B slave, I3 is the select bit
    /// ([`Request::ab_payload`]).
    ///
    /// Two tests of the bits: CB (bit 12) and I4 (bit 6) both clear, the address (bits 11..7)
    /// not 0; held to the call decoder for every request by the telegram tests.
    #[inline]
    pub const fn as_data_exchange(self) -> Option<(Address, Nibble)> {
        if self.0 & (1 << 12 | 1 << 6) != 0 || self.0 & 0x1F << 7 == 0 {
            return None;
        }
        Some((self.address(), Nibble(self.info() & 0xF)))
    }

    /// A command call with I4 = 1; `inverted` for the calls that carry ~Sel in I3.
    const fn command(
        address: Address,
        select: Select,
        low3: u8,
        inverted: bool,
    ) -> Result<Request, TelegramError> {
        let b = matches!(select, Select::B);
        if b && address.0 == 0 {
            return Err(TelegramError::ZeroB);
        }
        Ok(Request::raw(
            true,
            address.0,
            with_i3(low3, true, b != inverted),
        ))
    }

    /// A request from fields already known to be in range.
    const fn raw(cb: bool, address: u8, info: u8) -> Request {
        let body = ((cb as u16) << 10) | (((address & 0x1F) as u16) << 5) | (info & 0x1F) as u16;
        let pb = (body.count_ones() & 1) as u16;
        Request((body << 2) | (pb << 1) | 1)
    }
}

impl Response {
    /// Number of bits in a response.
    pub const BITS: u32 = 7;

    /// The number of pulses of the response on the line, looked up as
    /// [`Request::pulses`] is.
    #[inline]
    pub fn pulses(self) -> u32 {
        u32::from(RESPONSE_PULSES[usize::from(self.0)])
    }

    /// The response carrying `data` in I3..I0; computes the parity bit.
    pub const fn new(data: Nibble) -> Response {
        // A nibble holds 4 bits; the mask only lets the compiler see it.
        Response(RESPONSES[(data.0 & 0xF) as usize])
    }

    /// Checks a raw 7-bit pattern (bit 6 = ST .. bit 0 = EB).
    pub const fn from_bits(bits: u8) -> Result<Response, TelegramError> {
        if bits >> 7 != 0 {
            return Err(TelegramError::TooLong {
                len: 7,
                received: bits as u16,
            });
        }
        if bits & (1 << 6) != 0 {
            return Err(TelegramError::StartBit);
        }
        if bits & 1 == 0 {
            return Err(TelegramError::EndBit);
        }
        let expected = (((bits >> 2) & 0xF).count_ones() & 1) as u8;
        let received = (bits >> 1) & 1;
        if expected != received {
            return Err(TelegramError::Parity { expected, received });
        }
        Ok(Response(bits))
    }

    /// The raw 7 bits, ST in bit 6.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// The information I3..I0.
    pub const fn data(self) -> Nibble {
        Nibble((self.0 >> 2) & 0xF)
    }

    /// The parity bit PB.
    pub const fn parity_bit(self) -> bool {
        self.0 & 0b10 != 0
    }
}

impl fmt::Debug for Request {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Request({self})")
    }
}

impl fmt::Display for Request {
    /// The 14 bits grouped as ST CB A I PB EB: `0 0 00101 01010 0 1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0;
        write!(
            f,
            "0 {} {:05b} {:05b} {} 1",
            (b >> 12) & 1,
            (b >> 7) & 0x1F,
            (b >> 2) & 0x1F,
            (b >> 1) & 1
        )
    }
}

impl fmt::Debug for Response {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Response({self})")
    }
}

impl fmt::Display for Response {
    /// The 7 bits grouped as ST I PB EB: `0 0110 0 1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "0 {:04b} {} 1", (self.0 >> 2) & 0xF, (self.0 >> 1) & 1)
    }
}
