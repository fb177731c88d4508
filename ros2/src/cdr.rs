//! The payload of every rmw_zenoh sample: XCDR1 (plain CDR) with the 4-byte encapsulation header, `00 01 00 00`
//! for little-endian (what every ROS 2 publisher sends) or `00 00 00 00` for big-endian, alignment counted from the
//! end of the header. The body is the `cdr-encoding` crate's (RustDDS's serde CDR); only the header is ours. That
//! crate reads from a slice and checks every length against what is left, so a forged length fails instead of
//! allocating.

use byteorder::{BigEndian, LittleEndian};
use serde::Serialize;
use serde::de::DeserializeOwned;

/// The encapsulation header of little-endian plain CDR (`CDR_LE`).
pub(crate) const CDR_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// A payload that cannot be encoded or decoded.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    /// Fewer than 4 bytes: no encapsulation header.
    #[error("payload: {0} bytes, shorter than the 4-byte encapsulation header")]
    TooShort(usize),
    /// An encapsulation other than plain CDR (XCDR2, parameter lists).
    #[error("payload: encapsulation {0:02x}{1:02x} is not plain CDR (0000 big-endian or 0001 little-endian)")]
    Encapsulation(u8, u8),
    /// The body does not decode as the message.
    #[error("payload: {0}")]
    Body(#[from] cdr_encoding::Error),
}

/// Encodes `value` as little-endian plain CDR with its encapsulation header.
pub fn encode<T: Serialize>(value: &T) -> Result<Vec<u8>, CdrError> {
    let mut out = CDR_LE.to_vec();
    cdr_encoding::to_writer::<T, LittleEndian, _>(&mut out, value)?;
    Ok(out)
}

/// Decodes a payload with its encapsulation header (little- or big-endian plain CDR); bytes after the message
/// (the padding some writers add to a multiple of 4) are ignored.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CdrError> {
    let Some((header, body)) = bytes.split_first_chunk::<4>() else {
        return Err(CdrError::TooShort(bytes.len()));
    };
    match header {
        [0x00, 0x01, _, _] => Ok(cdr_encoding::from_bytes::<T, LittleEndian>(body)?.0),
        [0x00, 0x00, _, _] => Ok(cdr_encoding::from_bytes::<T, BigEndian>(body)?.0),
        [a, b, _, _] => Err(CdrError::Encapsulation(*a, *b)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::std_msgs::Header;

    #[test]
    fn a_header_round_trips_with_its_alignment() {
        let h = Header {
            stamp: crate::msgs::builtin_interfaces::Time { sec: 7, nanosec: 9 },
            frame_id: "world".into(),
        };
        let bytes = encode(&h).unwrap();
        // header, sec, nanosec, string length 6 (with its terminator), "world\0"
        assert_eq!(&bytes[..4], &CDR_LE);
        assert_eq!(&bytes[4..16], &[7, 0, 0, 0, 9, 0, 0, 0, 6, 0, 0, 0]);
        assert_eq!(&bytes[16..], b"world\0");
        assert_eq!(decode::<Header>(&bytes).unwrap(), h);
    }

    #[test]
    fn bad_payloads_are_errors() {
        assert!(matches!(decode::<Header>(&[0, 1]), Err(CdrError::TooShort(2))));
        assert!(matches!(decode::<Header>(&[0, 7, 0, 0, 1, 2, 3, 4]), Err(CdrError::Encapsulation(0, 7))));
        // A string length far beyond the payload fails without allocating it.
        let forged = [0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0xff, 0xff, 0xff, 0xff];
        assert!(matches!(decode::<Header>(&forged), Err(CdrError::Body(_))));
    }
}
