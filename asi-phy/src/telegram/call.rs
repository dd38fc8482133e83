//! What a request asks for: the call table, by classifying a request and by building one.

use super::fields::{Address, Nibble, Select};
use super::frames::Request;
use core::fmt;

/// What a request asks for (docs/master.md table; docs/asi.md §4).
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
    /// A code that is no call of docs/master.md (reserved or manufacturer-specific), with its bits.
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

impl Request {
    /// Classifies the request (docs/master.md table). Every bit pattern has an answer: codes that are
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
