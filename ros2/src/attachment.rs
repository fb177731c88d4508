//! The attachment rmw_zenoh puts on every sample: the publisher's sequence number, the source timestamp
//! (nanoseconds since the epoch) and the publisher's 16-byte GID, in zenoh-ext's serialization. As read in
//! ros2/rmw_zenoh's `rmw_zenoh_cpp/src/detail/attachment_helpers.cpp` (commit
//! `534747dca92adf15e1b1b975123037ca278db5ba`): `i64` little-endian, `i64` little-endian, then the GID as a
//! zenoh-ext sequence (its length as LEB128, `0x10`, then the 16 bytes: zenoh-cpp serializes a `std::array` as a
//! sequence). Earlier revisions (commit `038b5a4fbb337e8033a7474a4a788fa381204c3c`) put each value after its name
//! as a zenoh-ext string (`sequence_number`, `source_timestamp`, `source_gid`); [`Attachment::decode`] reads both.

/// The attachment of one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Attachment {
    /// The publisher's count of messages, from 1.
    pub sequence_number: i64,
    /// When the message was published, nanoseconds since the epoch.
    pub source_timestamp: i64,
    /// The publisher's GID ([`crate::liveliness::gid`]).
    pub source_gid: [u8; 16],
}

impl Attachment {
    /// The bytes rmw_zenoh writes (its current layout, without names).
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(33);
        out.extend_from_slice(&self.sequence_number.to_le_bytes());
        out.extend_from_slice(&self.source_timestamp.to_le_bytes());
        out.push(16);
        out.extend_from_slice(&self.source_gid);
        out
    }

    /// Reads either layout; none for anything else.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let mut r = Reader(bytes);
        let named = r.0.first() == Some(&15) && r.0.get(1..16) == Some(b"sequence_number".as_slice());
        r.name(named, "sequence_number")?;
        let sequence_number = i64::from_le_bytes(r.take(8)?.try_into().ok()?);
        r.name(named, "source_timestamp")?;
        let source_timestamp = i64::from_le_bytes(r.take(8)?.try_into().ok()?);
        r.name(named, "source_gid")?;
        (r.len()? == 16).then_some(())?;
        let source_gid = r.take(16)?.try_into().ok()?;
        r.0.is_empty().then_some(Self { sequence_number, source_timestamp, source_gid })
    }
}

struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, rest) = self.0.split_at_checked(n)?;
        self.0 = rest;
        Some(head)
    }

    /// In the named layout, the zenoh-ext string `name`; nothing in the other.
    fn name(&mut self, named: bool, name: &str) -> Option<()> {
        if named {
            let n = self.len()?;
            (self.take(n)? == name.as_bytes()).then_some(())?;
        }
        Some(())
    }

    /// A LEB128 length (at most 4 bytes here).
    fn len(&mut self) -> Option<usize> {
        let mut n = 0usize;
        for shift in [0, 7, 14, 21] {
            let b = *self.take(1)?.first()?;
            n |= usize::from(b & 0x7f) << shift;
            if b & 0x80 == 0 {
                return Some(n);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_layouts_are_read_and_the_current_one_written() {
        let a = Attachment {
            sequence_number: 3,
            source_timestamp: 1_764_100_000_000_000_000,
            source_gid: [7; 16],
        };
        let bytes = a.encode();
        assert_eq!(bytes.len(), 33);
        assert_eq!(&bytes[..8], &[3, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(bytes[16], 16);
        assert_eq!(Attachment::decode(&bytes), Some(a));
        let mut named = Vec::new();
        for (name, value) in [("sequence_number", &bytes[..8]), ("source_timestamp", &bytes[8..16])] {
            named.push(name.len() as u8);
            named.extend_from_slice(name.as_bytes());
            named.extend_from_slice(value);
        }
        named.push(10);
        named.extend_from_slice(b"source_gid");
        named.extend_from_slice(&bytes[16..]);
        assert_eq!(Attachment::decode(&named), Some(a));
        assert_eq!(Attachment::decode(&bytes[..32]), None);
        assert_eq!(Attachment::decode(&[bytes.as_slice(), &[0]].concat()), None);
    }
}
