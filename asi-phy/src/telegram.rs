//! AS-i telegrams: the 14-bit master request and the 7-bit slave response (SPEC §1, §2;
//! reference/asi.md §2.1, §4; seed 003 §2.2.2).
//!
//! Both are validated representations over plain integers, in transmission order with the first
//! bit sent in the most significant used position:
//!
//! ```text
//! Request  (u16, bits 13..0):  ST CB A4 A3 A2 A1 A0 I4 I3 I2 I1 I0 PB EB
//! Response (u8,  bits  6..0):  ST I3 I2 I1 I0 PB EB
//! ```
//!
//! ST is always 0, EB always 1, and the parity is even: CB + A4..A0 + I4..I0 + PB (request) and
//! I3..I0 + PB (response) hold an even number of ones. A value of these types is always a
//! telegram a correct transmitter could send.

use core::fmt;

/// A 4-bit value: slave data D3..D0, a parameter P3..P0, a code or status S3..S0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Nibble(u8);

impl Nibble {
    /// 0000.
    pub const ZERO: Nibble = Nibble(0);
    /// 1111 (the default output value of a master, reference/asi.md §5.1).
    pub const ALL: Nibble = Nibble(0xF);

    /// `v` as a nibble, or `None` if `v > 15`.
    pub const fn new(v: u8) -> Option<Nibble> {
        if v <= 0xF {
            Some(Nibble(v))
        } else {
            None
        }
    }

    /// The low four bits of `v` (the rest is discarded on purpose).
    pub const fn from_low_bits(v: u8) -> Nibble {
        Nibble(v & 0xF)
    }

    /// The value 0..=15.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// Bit `i` (0 = D0 .. 3 = D3); `false` for `i > 3`.
    pub const fn bit(self, i: u8) -> bool {
        i < 4 && self.0 & (1 << i) != 0
    }

    /// This nibble with bit `i` (0..=3) set to `value`; unchanged for `i > 3`.
    pub const fn with_bit(self, i: u8, value: bool) -> Nibble {
        if i > 3 {
            return self;
        }
        if value {
            Nibble(self.0 | (1 << i))
        } else {
            Nibble(self.0 & !(1 << i))
        }
    }
}

impl fmt::Display for Nibble {
    /// Four binary digits, D3 first: `1010`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04b}", self.0)
    }
}

/// A 5-bit slave address A4..A0, 0..=31. Address 0 is the delivery address of new slaves;
/// 31 with the broadcast code is the broadcast call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Address(u8);

impl Address {
    /// Address 0, where new slaves are delivered.
    pub const ZERO: Address = Address(0);

    /// `v` as an address, or `None` if `v > 31`.
    pub const fn new(v: u8) -> Option<Address> {
        if v <= 31 {
            Some(Address(v))
        } else {
            None
        }
    }

    /// The address 0..=31.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// Every address 1..=31 in ascending order (the order of the data exchange phase).
    pub fn slaves() -> impl Iterator<Item = Address> {
        (1..=31).map(Address)
    }
}

impl fmt::Display for Address {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// The A/B select of extended addressing (SPEC §2; reference/asi.md §4.2). A standard slave
/// answers the `A` encodings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Select {
    /// The A slave, or a standard (non A/B) slave.
    #[default]
    A,
    /// The B slave of an address.
    B,
}

impl fmt::Display for Select {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Select::A => "A",
            Select::B => "B",
        })
    }
}

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
    /// Address 0B does not exist (reference/asi.md §4.2).
    #[error("address 0B does not exist")]
    ZeroB,
}

/// A master request, 14 bits: ST CB A4..A0 I4..I0 PB EB (SPEC §1).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Request(u16);

/// A slave response, 7 bits: ST I3..I0 PB EB (SPEC §1).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Response(u8);

/// The I field of a request with its A/B select bit in I3.
const fn with_i3(low3: u8, i4: bool, i3: bool) -> u8 {
    ((i4 as u8) << 4) | ((i3 as u8) << 3) | (low3 & 0b111)
}

impl Request {
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
    /// 1 for A and 0 for B (SPEC §2 decision).
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

    /// Classifies the request (SPEC §2 table). Every bit pattern has an answer: codes that are
    /// no call keep their raw fields in [`Call::Unknown`].
    ///
    /// Overlapping encodings are resolved as a slave IC does: at address 0 a CB = 0 call is
    /// Address_Assignment and a CB = 1 call with I4 = 0 is Write_Extended_ID1.
    pub const fn call(self) -> Call {
        let address = self.address();
        let info = self.info();
        let i4 = info & 0x10 != 0;
        let i3 = info & 0x08 != 0;
        let low3 = info & 0b111;
        let data = Nibble(info & 0xF);
        if !self.cb() {
            return if address.0 == 0 {
                Call::AddressAssignment {
                    new_address: Address(info),
                }
            } else if i4 {
                Call::WriteParameter {
                    address,
                    parameter: data,
                }
            } else {
                Call::DataExchange { address, data }
            };
        }
        let sel = if i3 { Select::B } else { Select::A };
        let inv = if i3 { Select::A } else { Select::B };
        if !i4 {
            return if address.0 == 0 {
                Call::WriteExtendedId1 { id1: data }
            } else if low3 == 0 {
                Call::DeleteAddress {
                    address,
                    select: sel,
                }
            } else {
                Call::Unknown {
                    cb: true,
                    address,
                    info,
                }
            };
        }
        // Address 0B does not exist: the B encodings at address 0 are no call.
        let read_ok = address.0 != 0 || !i3;
        let inv_ok = address.0 != 0 || i3;
        match low3 {
            0b000 if read_ok => Call::ReadIoConfiguration {
                address,
                select: sel,
            },
            0b001 if read_ok => Call::ReadIdCode {
                address,
                select: sel,
            },
            0b010 if read_ok => Call::ReadId1 {
                address,
                select: sel,
            },
            0b011 if read_ok => Call::ReadId2 {
                address,
                select: sel,
            },
            0b100 if inv_ok => Call::ResetSlave {
                address,
                select: inv,
            },
            0b110 if inv_ok => Call::ReadStatus {
                address,
                select: inv,
            },
            0b101 if address.0 == 31 && !i3 => Call::BroadcastReset,
            _ => Call::Unknown {
                cb: true,
                address,
                info,
            },
        }
    }

    /// For a Data_Exchange or Write_Parameter to an A/B slave: the select bit in I3 (1 = A) and
    /// the three data bits D2..D0. `None` for other calls.
    pub const fn ab_payload(self) -> Option<(Select, Nibble)> {
        match self.call() {
            Call::DataExchange { data, .. }
            | Call::WriteParameter {
                parameter: data, ..
            } => {
                let select = if data.0 & 0x8 != 0 {
                    Select::A
                } else {
                    Select::B
                };
                Some((select, Nibble(data.0 & 0b111)))
            }
            _ => None,
        }
    }
}

impl Response {
    /// Number of bits in a response.
    pub const BITS: u32 = 7;

    /// The response carrying `data` in I3..I0; computes the parity bit.
    pub const fn new(data: Nibble) -> Response {
        let pb = (data.0.count_ones() & 1) as u8;
        Response((data.0 << 2) | (pb << 1) | 1)
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

/// What a request asks for (SPEC §2 table; reference/asi.md §4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Call {
    /// Data_Exchange: outputs in, inputs back. For an A/B slave I3 is the select bit
    /// (see [`Request::ab_payload`]).
    DataExchange {
        /// Slave address 1..=31.
        address: Address,
        /// I3..I0 as sent.
        data: Nibble,
    },
    /// Write_Parameter: the slave echoes its parameter response.
    WriteParameter {
        /// Slave address 1..=31.
        address: Address,
        /// I3..I0 as sent.
        parameter: Nibble,
    },
    /// Address_Assignment to the slave at address 0; answer 0110.
    AddressAssignment {
        /// The address it takes.
        new_address: Address,
    },
    /// Write_Extended_ID1 to the slave at address 0; answer 0000.
    WriteExtendedId1 {
        /// The new ID1.
        id1: Nibble,
    },
    /// Delete_Address; answer 0000.
    DeleteAddress {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Reset_Slave; answer 0110.
    ResetSlave {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Read_IO_Configuration; answer the IO code.
    ReadIoConfiguration {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Read_ID_Code; answer the ID code.
    ReadIdCode {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Read_ID1; answer the extended ID code 1.
    ReadId1 {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Read_ID2; answer the extended ID code 2.
    ReadId2 {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Read_Status; answer S3..S0.
    ReadStatus {
        /// Slave address.
        address: Address,
        /// A/B select.
        select: Select,
    },
    /// Broadcast reset; no answer.
    BroadcastReset,
    /// A code that is no call of SPEC §2 (reserved or manufacturer-specific), with its bits.
    Unknown {
        /// The control bit.
        cb: bool,
        /// A4..A0.
        address: Address,
        /// I4..I0.
        info: u8,
    },
}

impl Call {
    /// The request that carries this call (the inverse of [`Request::call`]); `None` for a
    /// call whose fields no request can carry (for example Data_Exchange at address 0).
    pub const fn request(self) -> Option<Request> {
        let r = match self {
            Call::DataExchange { address, data } => Request::data_exchange(address, data),
            Call::WriteParameter { address, parameter } => {
                Request::write_parameter(address, parameter)
            }
            Call::AddressAssignment { new_address } => Ok(Request::address_assignment(new_address)),
            Call::WriteExtendedId1 { id1 } => Ok(Request::write_extended_id1(id1)),
            Call::DeleteAddress { address, select } => Request::delete_address(address, select),
            Call::ResetSlave { address, select } => Request::reset_slave(address, select),
            Call::ReadIoConfiguration { address, select } => {
                Request::read_io_configuration(address, select)
            }
            Call::ReadIdCode { address, select } => Request::read_id_code(address, select),
            Call::ReadId1 { address, select } => Request::read_id1(address, select),
            Call::ReadId2 { address, select } => Request::read_id2(address, select),
            Call::ReadStatus { address, select } => Request::read_status(address, select),
            Call::BroadcastReset => Ok(Request::broadcast_reset()),
            Call::Unknown { cb, address, info } => Request::from_fields(cb, address, info),
        };
        match r {
            Ok(r) => Some(r),
            Err(_) => None,
        }
    }

    /// The call's name as the AS-i documents spell it.
    pub const fn name(&self) -> &'static str {
        match self {
            Call::DataExchange { .. } => "Data_Exchange",
            Call::WriteParameter { .. } => "Write_Parameter",
            Call::AddressAssignment { .. } => "Address_Assignment",
            Call::WriteExtendedId1 { .. } => "Write_Extended_ID1",
            Call::DeleteAddress { .. } => "Delete_Address",
            Call::ResetSlave { .. } => "Reset_Slave",
            Call::ReadIoConfiguration { .. } => "Read_IO_Configuration",
            Call::ReadIdCode { .. } => "Read_ID_Code",
            Call::ReadId1 { .. } => "Read_ID1",
            Call::ReadId2 { .. } => "Read_ID2",
            Call::ReadStatus { .. } => "Read_Status",
            Call::BroadcastReset => "Broadcast_Reset",
            Call::Unknown { .. } => "Unknown",
        }
    }
}

impl fmt::Display for Call {
    /// The readable form of traces and logs: `Data_Exchange 5 out=1010`, `Read_ID1 7B`,
    /// `Read_Status 2A`, `Address_Assignment new=12`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = self.name();
        match self {
            Call::DataExchange { address, data } => write!(f, "{name} {address} out={data}"),
            Call::WriteParameter { address, parameter } => {
                write!(f, "{name} {address} P={parameter}")
            }
            Call::AddressAssignment { new_address } => write!(f, "{name} new={new_address}"),
            Call::WriteExtendedId1 { id1 } => write!(f, "{name} ID1={id1}"),
            Call::DeleteAddress { address, select }
            | Call::ResetSlave { address, select }
            | Call::ReadIoConfiguration { address, select }
            | Call::ReadIdCode { address, select }
            | Call::ReadId1 { address, select }
            | Call::ReadId2 { address, select }
            | Call::ReadStatus { address, select } => write!(f, "{name} {address}{select}"),
            Call::BroadcastReset => f.write_str(name),
            Call::Unknown { cb, address, info } => {
                write!(f, "{name} CB={} A={address} I={info:05b}", *cb as u8)
            }
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn a(v: u8) -> Address {
        Address::new(v).expect("test address")
    }

    fn n(v: u8) -> Nibble {
        Nibble::new(v).expect("test nibble")
    }

    /// The literal strings of SAP5 Table 6 (reference/asi.md §1.3) and SPEC §1's vectors.
    #[test]
    fn bit_strings_match_the_datasheet_literals() {
        assert_eq!(Request::broadcast_reset().bits(), 0b01111111010111);
        assert_eq!(
            Request::broadcast_reset().to_string(),
            "0 1 11111 10101 1 1"
        );
        let dexg = Request::data_exchange(a(5), n(0b1010)).expect("valid");
        assert_eq!(dexg.to_string(), "0 0 00101 01010 0 1");
        assert_eq!(Response::new(n(0b0110)).bits(), 0b0011001);
        assert_eq!(Response::new(n(0b0000)).bits(), 0b0000001);
    }

    /// The information-field codes of reference/asi.md §4 (hex view, standard mode).
    #[test]
    fn command_codes_match_the_call_table() {
        let cases: [(Result<Request, TelegramError>, u8); 6] = [
            (Request::read_io_configuration(a(7), Select::A), 0x10),
            (Request::read_id_code(a(7), Select::A), 0x11),
            (Request::read_id1(a(7), Select::A), 0x12),
            (Request::read_id2(a(7), Select::A), 0x13),
            (Request::reset_slave(a(7), Select::A), 0x1C),
            (Request::read_status(a(7), Select::A), 0x1E),
        ];
        for (req, info) in cases {
            let req = req.expect("valid");
            assert!(req.cb());
            assert_eq!(req.info(), info, "{:?}", req.call());
        }
        let dela = Request::delete_address(a(7), Select::A).expect("valid");
        assert_eq!((dela.cb(), dela.info()), (true, 0x00));
        // B slaves: reads carry Sel = 1 in I3, Reset and Status carry ~Sel = 0.
        assert_eq!(
            Request::read_id1(a(7), Select::B).expect("valid").info(),
            0x1A
        );
        assert_eq!(
            Request::read_status(a(7), Select::B).expect("valid").info(),
            0x16
        );
        assert_eq!(
            Request::reset_slave(a(7), Select::B).expect("valid").info(),
            0x14
        );
        assert_eq!(
            Request::delete_address(a(7), Select::B)
                .expect("valid")
                .info(),
            0x08
        );
    }

    #[test]
    fn ab_data_exchange_carries_the_select_bit_in_i3() {
        let ra = Request::data_exchange_ab(a(9), Select::A, n(0b101)).expect("valid");
        let rb = Request::data_exchange_ab(a(9), Select::B, n(0b101)).expect("valid");
        assert_eq!(ra.info(), 0b01101);
        assert_eq!(rb.info(), 0b00101);
        assert_eq!(ra.ab_payload(), Some((Select::A, n(0b101))));
        assert_eq!(rb.ab_payload(), Some((Select::B, n(0b101))));
        assert_eq!(
            Request::data_exchange_ab(a(9), Select::A, n(0b1000)),
            Err(TelegramError::FieldOutOfRange {
                field: "A/B outputs D2..D0",
                value: 8,
                max: 7
            })
        );
    }

    #[test]
    fn constructors_reject_what_no_telegram_can_say() {
        assert_eq!(
            Request::data_exchange(Address::ZERO, Nibble::ZERO),
            Err(TelegramError::AddressZero {
                call: "Data_Exchange"
            })
        );
        assert_eq!(
            Request::read_id_code(Address::ZERO, Select::B),
            Err(TelegramError::ZeroB)
        );
        assert!(Request::read_id_code(Address::ZERO, Select::A).is_ok());
        assert_eq!(Address::new(32), None);
        assert_eq!(Nibble::new(16), None);
    }

    #[test]
    fn from_bits_names_the_broken_rule() {
        let good = Request::data_exchange(a(5), n(0b1010))
            .expect("valid")
            .bits();
        assert_eq!(
            Request::from_bits(good),
            Request::data_exchange(a(5), n(0b1010))
        );
        assert_eq!(
            Request::from_bits(good | 1 << 13),
            Err(TelegramError::StartBit)
        );
        assert_eq!(Request::from_bits(good & !1), Err(TelegramError::EndBit));
        assert_eq!(
            Request::from_bits(good ^ 0b10),
            Err(TelegramError::Parity {
                expected: 0,
                received: 1
            })
        );
        assert_eq!(
            Request::from_bits(good | 1 << 14),
            Err(TelegramError::TooLong {
                len: 14,
                received: good | 1 << 14
            })
        );
        assert_eq!(
            Response::from_bits(0b0011011),
            Err(TelegramError::Parity {
                expected: 0,
                received: 1
            })
        );
    }

    /// Every one of the 2^11 valid requests: classification and construction are inverse.
    #[test]
    fn every_request_classifies_and_rebuilds() {
        let mut unknown = 0;
        for body in 0u16..1 << 11 {
            let req = Request::from_fields(
                body & 0x400 != 0,
                a(((body >> 5) & 0x1F) as u8),
                (body & 0x1F) as u8,
            )
            .expect("in range");
            assert_eq!(Request::from_bits(req.bits()), Ok(req));
            let call = req.call();
            if matches!(call, Call::Unknown { .. }) {
                unknown += 1;
            }
            assert_eq!(call.request(), Some(req), "{call:?}");
        }
        // CB=1, I4=0, A≠0 with I2..I0 ≠ 0: 31·2·7 = 434; CB=1, I4=1: x111 at every address
        // (64), x101 except 31/I3=0 (63), Sel=B reads at address 0 (4), ~Sel=B at 0 (2).
        assert_eq!(unknown, 434 + 64 + 63 + 4 + 2);
    }

    #[test]
    fn every_response_round_trips() {
        for v in 0..16 {
            let r = Response::new(n(v));
            assert_eq!(Response::from_bits(r.bits()), Ok(r));
            assert_eq!(r.data().get(), v);
            assert_eq!((r.bits() >> 1).count_ones() % 2, 0);
        }
    }
}
