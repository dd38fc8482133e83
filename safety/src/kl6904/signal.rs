//! Signals of a KL6904 project: contact types, signal kinds and references (§4.1.2.3 of the KL6904
//! manual).

use core::fmt;
use core::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// How a module input reads its signal (§4.1.1, §4.4.1 of the KL6904 manual).
///
/// - `Break` (NC, break contact): used as is; for ESTOP and MON inputs a 0 demands the safe
///   state;
/// - `Make` (NO, make contact): inverted first; for ESTOP and MON inputs a 1 demands it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Contact {
    /// Break contact (normally closed): the signal is used as is.
    #[default]
    Break,
    /// Make contact (normally open): the signal is inverted.
    Make,
}

impl Contact {
    /// The signal as the module sees it: TRUE = healthy / no demand.
    pub const fn normalise(self, raw: bool) -> bool {
        match self {
            Contact::Break => raw,
            Contact::Make => !raw,
        }
    }

    /// `true` when `raw` demands the safe state.
    pub const fn demands(self, raw: bool) -> bool {
        !self.normalise(raw)
    }
}

/// The kinds of source a module input may be linked to (table 4-3 of the KL6904 manual).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SignalKind {
    /// A safe input of a TwinSAFE terminal, delivered by a TwinSAFE connection.
    TwinSafeIn,
    /// A standard (non-safe) PLC variable: a PLC output `%Q*` fed into the logic.
    StandardIn,
    /// An output of a function module or of a group (FB_ERR, COM_ERR, OUT_ERR).
    FbOut,
}

impl SignalKind {
    /// The name used in the KL6904 manual's tables.
    pub const fn name(self) -> &'static str {
        match self {
            SignalKind::TwinSafeIn => "TwinSAFE-In",
            SignalKind::StandardIn => "Standard-In",
            SignalKind::FbOut => "FB-Out",
        }
    }
}

impl fmt::Display for SignalKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The diagnostic outputs of a TwinSAFE group (table 3-2 of the KL6904 manual).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum GroupOutput {
    /// At least one module of the group has an error.
    FbErr,
    /// At least one connection of the group reports an error.
    ComErr,
    /// At least one local output of the group reports an error.
    OutErr,
}

impl GroupOutput {
    /// All three, in table order.
    pub const ALL: [GroupOutput; 3] =
        [GroupOutput::FbErr, GroupOutput::ComErr, GroupOutput::OutErr];

    /// The name in the KL6904 manual: `FB_ERR`, `COM_ERR`, `OUT_ERR`.
    pub const fn name(self) -> &'static str {
        match self {
            GroupOutput::FbErr => "FB_ERR",
            GroupOutput::ComErr => "COM_ERR",
            GroupOutput::OutErr => "OUT_ERR",
        }
    }
}

/// A channel of a TwinSAFE connection, by number (1-based) or by the name the project gives it.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ChannelRef {
    /// Channel number, 1-based as on the terminal.
    Number(u8),
    /// A channel name declared in the connection.
    Name(String),
}

impl fmt::Display for ChannelRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChannelRef::Number(n) => write!(f, "{n}"),
            ChannelRef::Name(s) => f.write_str(s),
        }
    }
}

/// Where a module input, a group input or an output gets its value from.
///
/// Written in a project file as a string:
///
/// | text | meaning | kind |
/// |---|---|---|
/// | `ts:<connection>.<channel>` | safe input channel of a connection (number or name) | TwinSAFE-In |
/// | `std:<variable>` | a standard PLC variable | Standard-In |
/// | `fb:<module>.<output>` | an output of a function module | FB-Out |
/// | `group:<group>.<FB_ERR\|COM_ERR\|OUT_ERR>` | a group's diagnostic output | FB-Out |
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum SignalRef {
    /// A safe input channel delivered by a TwinSAFE connection.
    TwinSafeIn {
        /// The connection's name.
        connection: String,
        /// The channel.
        channel: ChannelRef,
    },
    /// A standard PLC variable.
    StandardIn {
        /// The variable's name.
        name: String,
    },
    /// An output of a function module.
    FbOut {
        /// The module's name.
        module: String,
        /// The output's name, e.g. `EStopDelOut`.
        output: String,
    },
    /// A diagnostic output of a group.
    Group {
        /// The group's name.
        group: String,
        /// Which output.
        output: GroupOutput,
    },
}

impl SignalRef {
    /// `ts:<connection>.<channel>`.
    pub fn twinsafe(connection: &str, channel: impl Into<ChannelName>) -> Self {
        SignalRef::TwinSafeIn {
            connection: connection.to_owned(),
            channel: channel.into().0,
        }
    }

    /// `std:<name>`.
    pub fn standard(name: &str) -> Self {
        SignalRef::StandardIn {
            name: name.to_owned(),
        }
    }

    /// `fb:<module>.<output>`.
    pub fn fb(module: &str, output: &str) -> Self {
        SignalRef::FbOut {
            module: module.to_owned(),
            output: output.to_owned(),
        }
    }

    /// `group:<group>.<output>`.
    pub fn group(group: &str, output: GroupOutput) -> Self {
        SignalRef::Group {
            group: group.to_owned(),
            output,
        }
    }

    /// The kind of source this is.
    pub const fn kind(&self) -> SignalKind {
        match self {
            SignalRef::TwinSafeIn { .. } => SignalKind::TwinSafeIn,
            SignalRef::StandardIn { .. } => SignalKind::StandardIn,
            SignalRef::FbOut { .. } | SignalRef::Group { .. } => SignalKind::FbOut,
        }
    }
}

/// A channel given by number or by name, for [`SignalRef::twinsafe`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelName(ChannelRef);

impl From<u8> for ChannelName {
    fn from(n: u8) -> Self {
        ChannelName(ChannelRef::Number(n))
    }
}

impl From<&str> for ChannelName {
    fn from(s: &str) -> Self {
        ChannelName(ChannelRef::Name(s.to_owned()))
    }
}

impl fmt::Display for SignalRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SignalRef::TwinSafeIn {
                connection,
                channel,
            } => write!(f, "ts:{connection}.{channel}"),
            SignalRef::StandardIn { name } => write!(f, "std:{name}"),
            SignalRef::FbOut { module, output } => write!(f, "fb:{module}.{output}"),
            SignalRef::Group { group, output } => write!(f, "group:{group}.{}", output.name()),
        }
    }
}

/// Why a signal reference could not be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("`{text}` is not a signal: {reason}; write ts:<connection>.<channel>, std:<variable>, fb:<module>.<output> or group:<group>.<FB_ERR|COM_ERR|OUT_ERR>")]
pub struct ParseSignalError {
    /// The text as written.
    pub text: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

fn is_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

impl FromStr for SignalRef {
    type Err = ParseSignalError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let err = |reason| ParseSignalError {
            text: text.to_owned(),
            reason,
        };
        let (prefix, rest) = text
            .split_once(':')
            .ok_or_else(|| err("no `kind:` prefix"))?;
        let dotted = |rest: &str| -> Result<(String, String), ParseSignalError> {
            let (a, b) = rest
                .split_once('.')
                .ok_or_else(|| err("expected `<object>.<item>`"))?;
            if !is_name(a) || !is_name(b) {
                return Err(err("names are letters, digits, `_` and `-`"));
            }
            Ok((a.to_owned(), b.to_owned()))
        };
        match prefix {
            "ts" => {
                let (connection, channel) = dotted(rest)?;
                let channel = match channel.parse::<u8>() {
                    Ok(n) => ChannelRef::Number(n),
                    Err(_) => ChannelRef::Name(channel),
                };
                Ok(SignalRef::TwinSafeIn {
                    connection,
                    channel,
                })
            }
            "std" if is_name(rest) => Ok(SignalRef::StandardIn {
                name: rest.to_owned(),
            }),
            "std" => Err(err("names are letters, digits, `_` and `-`")),
            "fb" => {
                let (module, output) = dotted(rest)?;
                Ok(SignalRef::FbOut { module, output })
            }
            "group" => {
                let (group, output) = dotted(rest)?;
                let output = GroupOutput::ALL
                    .into_iter()
                    .find(|o| o.name() == output)
                    .ok_or_else(|| err("a group's outputs are FB_ERR, COM_ERR and OUT_ERR"))?;
                Ok(SignalRef::Group { group, output })
            }
            _ => Err(err("unknown kind prefix")),
        }
    }
}

impl Serialize for SignalRef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for SignalRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signal_refs_round_trip_through_text() {
        for text in [
            "ts:cabin_stop.1",
            "ts:cabinet.k1_aux",
            "std:err_ack",
            "fb:stop.EStopDelOut",
            "group:drive.COM_ERR",
        ] {
            let s: SignalRef = text.parse().expect(text);
            assert_eq!(s.to_string(), text);
        }
        assert_eq!(
            "ts:cabin_stop.2".parse::<SignalRef>(),
            Ok(SignalRef::twinsafe("cabin_stop", 2))
        );
    }

    #[test]
    fn bad_signal_refs_say_why() {
        for (text, reason) in [
            ("cabin_stop.1", "no `kind:` prefix"),
            ("io:x", "unknown kind prefix"),
            ("fb:stop", "expected `<object>.<item>`"),
            (
                "group:drive.ERR",
                "a group's outputs are FB_ERR, COM_ERR and OUT_ERR",
            ),
            ("std:a b", "names are letters, digits, `_` and `-`"),
        ] {
            let e = text.parse::<SignalRef>().expect_err(text);
            assert_eq!(e.reason, reason, "{text}");
            assert!(e.to_string().contains(text));
        }
    }

    #[test]
    fn contacts_invert_only_make() {
        assert!(Contact::Break.demands(false));
        assert!(!Contact::Break.demands(true));
        assert!(Contact::Make.demands(true));
        assert!(Contact::Make.normalise(false));
    }
}
