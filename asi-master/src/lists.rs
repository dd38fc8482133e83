//! The master's slave lists and flags (docs/master.md; docs/asi.md §5.2, §5.3).
//!
//! A [`SlaveList`] is one bit per slave address in the Bihl+Wiedemann numbering (docs/asi.md
//! §5.2, `aasidrv.h`): bit 0..31 = slave 0/0A..31/31A, bit 32..63 = 0B..31B. LDS, LAS, LPS, LCS
//! and LPF are all of this type.

use asi_phy::SlaveAddr;
use core::fmt;

/// A set of slave addresses: LDS, LAS, LPS, LCS or LPF (docs/asi.md §5.2).
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct SlaveList(u64);

impl SlaveList {
    /// The empty list.
    pub const EMPTY: SlaveList = SlaveList(0);

    /// The list with the raw bits `bits` (bit 32 = 0B is dropped: it does not exist).
    pub const fn from_bits(bits: u64) -> SlaveList {
        SlaveList(bits & !(1 << 32))
    }

    /// The raw bits, bit 0..31 = 0A..31A, 32..63 = 0B..31B.
    pub const fn bits(self) -> u64 {
        self.0
    }

    /// `true` if `a` is in the list.
    pub const fn contains(self, a: SlaveAddr) -> bool {
        self.0 & (1 << a.index()) != 0
    }

    /// Adds or removes `a`.
    pub fn set(&mut self, a: SlaveAddr, on: bool) {
        if on {
            self.0 |= 1 << a.index();
        } else {
            self.0 &= !(1 << a.index());
        }
    }

    /// `true` if the list is empty.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Number of slaves in the list.
    pub const fn len(self) -> u32 {
        self.0.count_ones()
    }

    /// The list without address 0 (which can never be projected or activated).
    pub const fn without_zero(self) -> SlaveList {
        SlaveList(self.0 & !1)
    }

    /// The addresses in the list, A addresses ascending, then B.
    pub fn iter(self) -> impl Iterator<Item = SlaveAddr> {
        let mut rest = self.0;
        core::iter::from_fn(move || {
            if rest == 0 {
                return None;
            }
            let i = rest.trailing_zeros() as u8;
            rest &= rest - 1;
            SlaveAddr::from_index(i)
        })
    }

    /// The eight bytes of the list as the mailbox returns them: byte 0 holds bits 0..7.
    pub const fn to_bytes(self) -> [u8; 8] {
        self.0.to_le_bytes()
    }
}

impl FromIterator<SlaveAddr> for SlaveList {
    fn from_iter<T: IntoIterator<Item = SlaveAddr>>(iter: T) -> Self {
        let mut l = SlaveList::EMPTY;
        for a in iter {
            l.set(a, true);
        }
        l
    }
}

impl fmt::Debug for SlaveList {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SlaveList[{self}]")
    }
}

impl fmt::Display for SlaveList {
    /// The addresses separated by spaces: `1A 2A 10A 5B`; `-` for the empty list.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("-");
        }
        for (i, a) in self.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{a}")?;
        }
        Ok(())
    }
}

/// The master's execution-control flags, with the bit values of Bihl+Wiedemann `aasidrv.h`
/// (docs/asi.md §5.3).
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct EcFlags(u16);

impl EcFlags {
    /// Projected and actual configuration match.
    pub const CONFIG_OK: u16 = 0x01;
    /// A slave with address 0 exists.
    pub const LDS0: u16 = 0x02;
    /// Automatic addressing is allowed (enabled, protected mode, no wrong slave present).
    pub const AUTO_ADDRESS_ASSIGN: u16 = 0x04;
    /// Automatic addressing is possible now (exactly one projected slave is missing).
    pub const AUTO_ADDRESS_AVAILABLE: u16 = 0x08;
    /// Configuration mode is active (0 = protected mode).
    pub const CONFIGURATION_ACTIVE: u16 = 0x10;
    /// Normal operation has been reached.
    pub const NORMAL_OPERATION_ACTIVE: u16 = 0x20;
    /// AS-i power fail.
    pub const APF: u16 = 0x40;
    /// The offline phase is active.
    pub const OFFLINE_READY: u16 = 0x80;
    /// No slave reports a peripheral fault.
    pub const PERIPHERY_OK: u16 = 0x100;

    const NAMES: [(u16, &'static str); 9] = [
        (Self::CONFIG_OK, "Config_OK"),
        (Self::LDS0, "LDS.0"),
        (Self::AUTO_ADDRESS_ASSIGN, "Auto_Address_Assign"),
        (Self::AUTO_ADDRESS_AVAILABLE, "Auto_Address_Available"),
        (Self::CONFIGURATION_ACTIVE, "Configuration_Active"),
        (Self::NORMAL_OPERATION_ACTIVE, "Normal_Operation_Active"),
        (Self::APF, "APF"),
        (Self::OFFLINE_READY, "Offline_Ready"),
        (Self::PERIPHERY_OK, "Periphery_OK"),
    ];

    /// The flags from their raw bits.
    pub const fn from_bits(bits: u16) -> EcFlags {
        EcFlags(bits & 0x1FF)
    }

    /// The raw bits.
    pub const fn bits(self) -> u16 {
        self.0
    }

    /// `true` if every bit of `flag` is set.
    pub const fn has(self, flag: u16) -> bool {
        self.0 & flag == flag
    }

    /// Sets or clears `flag`.
    pub fn set(&mut self, flag: u16, on: bool) {
        if on {
            self.0 |= flag;
        } else {
            self.0 &= !flag;
        }
    }

    /// `Config_OK`.
    pub const fn config_ok(self) -> bool {
        self.has(Self::CONFIG_OK)
    }
    /// `LDS.0`.
    pub const fn lds0(self) -> bool {
        self.has(Self::LDS0)
    }
    /// `Auto_Address_Assign`.
    pub const fn auto_address_assign(self) -> bool {
        self.has(Self::AUTO_ADDRESS_ASSIGN)
    }
    /// `Auto_Address_Available`.
    pub const fn auto_address_available(self) -> bool {
        self.has(Self::AUTO_ADDRESS_AVAILABLE)
    }
    /// `Configuration_Active`.
    pub const fn configuration_active(self) -> bool {
        self.has(Self::CONFIGURATION_ACTIVE)
    }
    /// `Normal_Operation_Active`.
    pub const fn normal_operation_active(self) -> bool {
        self.has(Self::NORMAL_OPERATION_ACTIVE)
    }
    /// `APF`.
    pub const fn apf(self) -> bool {
        self.has(Self::APF)
    }
    /// `Offline_Ready`.
    pub const fn offline_ready(self) -> bool {
        self.has(Self::OFFLINE_READY)
    }
    /// `Periphery_OK`.
    pub const fn periphery_ok(self) -> bool {
        self.has(Self::PERIPHERY_OK)
    }
}

impl fmt::Debug for EcFlags {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "EcFlags[{self}]")
    }
}

impl fmt::Display for EcFlags {
    /// The names of the set flags joined by spaces, `-` if none.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for (bit, name) in Self::NAMES {
            if self.0 & bit != 0 {
                if !first {
                    f.write_str(" ")?;
                }
                first = false;
                f.write_str(name)?;
            }
        }
        if first {
            f.write_str("-")?;
        }
        Ok(())
    }
}

/// The host-interface flags the PLC sets (docs/asi.md §5.3, `aasidrv.h` HI flags).
///
/// **Decision** (the thesis is silent on how the PLC sets them): they travel in the flag nibble of
/// output word 0 (bits 15..12, where the input image has F3..F0), encoded so that an all-zero
/// output image means normal operation: bit 12 = 1 locks data exchange (Data_Exchange_Active
/// = 0), bit 13 = 1 asks for Offline, bit 14 = 1 disables automatic addressing
/// (Auto_Address_Enable = 0); bit 15 is reserved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct HostFlags {
    /// Data exchange with the slaves' output values (0 ⇒ the default 1111 is sent instead).
    pub data_exchange_active: bool,
    /// Go (and stay) offline.
    pub offline: bool,
    /// Automatic addressing of a replaced slave is allowed.
    pub auto_address_enable: bool,
}

impl Default for HostFlags {
    fn default() -> Self {
        HostFlags {
            data_exchange_active: true,
            offline: false,
            auto_address_enable: true,
        }
    }
}

impl HostFlags {
    /// Output word 0 bit that locks data exchange.
    pub const WORD0_LOCK_DATA_EXCHANGE: u16 = 1 << 12;
    /// Output word 0 bit that asks for offline.
    pub const WORD0_OFFLINE: u16 = 1 << 13;
    /// Output word 0 bit that disables automatic addressing.
    pub const WORD0_NO_AUTO_ADDRESS: u16 = 1 << 14;

    /// The host flags carried by output word 0.
    pub const fn from_output_word0(w: u16) -> HostFlags {
        HostFlags {
            data_exchange_active: w & Self::WORD0_LOCK_DATA_EXCHANGE == 0,
            offline: w & Self::WORD0_OFFLINE != 0,
            auto_address_enable: w & Self::WORD0_NO_AUTO_ADDRESS == 0,
        }
    }

    /// Output word 0's flag bits for these host flags (bits 11..0 are zero).
    pub const fn to_output_word0_bits(self) -> u16 {
        let mut w = 0;
        if !self.data_exchange_active {
            w |= Self::WORD0_LOCK_DATA_EXCHANGE;
        }
        if self.offline {
            w |= Self::WORD0_OFFLINE;
        }
        if !self.auto_address_enable {
            w |= Self::WORD0_NO_AUTO_ADDRESS;
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn list_bits_follow_the_bw_numbering() {
        let mut l = SlaveList::EMPTY;
        l.set(SlaveAddr::a(0).expect("0"), true);
        l.set(SlaveAddr::a(31).expect("31"), true);
        l.set(SlaveAddr::b(1).expect("1B"), true);
        assert_eq!(l.bits(), 1 | 1 << 31 | 1 << 33);
        assert_eq!(l.to_string(), "0A 31A 1B");
        assert_eq!(SlaveAddr::b(0), None);
        assert_eq!(SlaveAddr::from_index(32), None);
        assert_eq!(SlaveList::from_bits(1 << 32), SlaveList::EMPTY);
        assert_eq!(l.to_bytes()[0], 1);
        assert_eq!(l.to_bytes()[3], 0x80);
        assert_eq!(l.to_bytes()[4], 0x02);
    }

    #[test]
    fn flag_values_are_those_of_aasidrv_h() {
        let f = EcFlags::from_bits(0x1FF);
        assert!(f.config_ok() && f.lds0() && f.apf() && f.periphery_ok());
        assert_eq!(EcFlags::APF, 0x40);
        assert_eq!(EcFlags::OFFLINE_READY, 0x80);
        assert_eq!(
            EcFlags::from_bits(EcFlags::CONFIG_OK | EcFlags::PERIPHERY_OK).to_string(),
            "Config_OK Periphery_OK"
        );
    }

    #[test]
    fn a_zero_output_word_means_normal_host_flags() {
        assert_eq!(HostFlags::from_output_word0(0), HostFlags::default());
        let h = HostFlags {
            data_exchange_active: false,
            offline: true,
            auto_address_enable: false,
        };
        assert_eq!(h.to_output_word0_bits(), 0x7000);
        assert_eq!(HostFlags::from_output_word0(0x7ABC), h);
    }
}
