//! What travels in a Zenoh sample, as rmw_zenoh puts it there: the payload is the message in
//! CDR (little endian, after the 4-byte encapsulation header `00 01 00 00`, the same bytes a
//! DDS sample carries), the attachment is the sample's sequence number, source timestamp and
//! source GID ([`Attachment`]); the key expression names the type by its ROS 2 type hash
//! ([`super::type_hash`]).

use byteorder::LittleEndian;
use serde::Serialize;
use serde::de::DeserializeOwned;

/// CDR little endian, no options: the encapsulation header of every payload.
const CDR_LE: [u8; 4] = [0, 1, 0, 0];

/// `m` in CDR with its encapsulation header.
pub fn encode<M: Serialize>(m: &M) -> Vec<u8> {
    let mut out = CDR_LE.to_vec();
    // Our messages are strings, numbers and sequences of them: CDR cannot refuse them.
    out.extend(cdr_encoding::to_vec::<M, LittleEndian>(m).unwrap_or_default());
    out
}

/// A message from CDR bytes (big- or little-endian encapsulation).
pub fn decode<M: DeserializeOwned>(bytes: &[u8]) -> Result<M, String> {
    if bytes.len() < 4 {
        return Err(format!("{} bytes: shorter than a CDR header", bytes.len()));
    }
    let body = &bytes[4..];
    let r = match bytes[1] {
        1 => cdr_encoding::from_bytes::<M, LittleEndian>(body),
        0 => cdr_encoding::from_bytes::<M, byteorder::BigEndian>(body),
        k => return Err(format!("CDR encapsulation kind {k} is not plain CDR")),
    };
    r.map(|(m, _)| m).map_err(|e| format!("CDR: {e}"))
}

/// rmw_zenoh's attachment: the writer's sequence number (1, 2, … per publisher or client),
/// the source timestamp (ns since the Unix epoch) and the writer's 16-byte GID, serialised
/// as zenoh-ext does (rmw_zenoh ≥ 0.6, `attachment_helpers.cpp`): two little-endian i64,
/// then the GID as a sequence (its length 16 as one LEB128 byte, then the bytes): 33 bytes.
/// A service reply echoes the request's sequence number and GID: that is how a client pairs
/// them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Attachment {
    /// The writer's sequence number.
    pub seq: i64,
    /// When it was written, ns since the Unix epoch.
    pub stamp_ns: i64,
    /// The writer's GID.
    pub gid: [u8; 16],
}

impl Attachment {
    /// The attachment of sample `seq` of writer `gid`, stamped now.
    pub fn now(seq: i64, gid: [u8; 16]) -> Attachment {
        let d = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        Attachment {
            seq,
            stamp_ns: i64::try_from(d.as_nanos()).unwrap_or(i64::MAX),
            gid,
        }
    }

    /// The 33 bytes on the wire.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(ATTACHMENT_LEN);
        out.extend(self.seq.to_le_bytes());
        out.extend(self.stamp_ns.to_le_bytes());
        out.push(GID_LEN);
        out.extend(self.gid);
        out
    }

    /// Reads the 33 bytes back (`None`: not an rmw_zenoh attachment).
    pub fn parse(b: &[u8]) -> Option<Attachment> {
        if b.len() != ATTACHMENT_LEN || b[16] != GID_LEN {
            return None;
        }
        Some(Attachment {
            seq: i64::from_le_bytes(b[0..8].try_into().ok()?),
            stamp_ns: i64::from_le_bytes(b[8..16].try_into().ok()?),
            gid: b[17..33].try_into().ok()?,
        })
    }
}

/// The GID's length as zenoh-ext writes a sequence's (LEB128: one byte).
const GID_LEN: u8 = 16;
/// Two i64, the GID's length, the GID.
const ATTACHMENT_LEN: usize = 8 + 8 + 1 + 16;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payloads_are_cdr_behind_the_little_endian_header() {
        #[derive(Serialize, serde::Deserialize, Debug, PartialEq)]
        struct M {
            seq: u64,
            name: String,
        }
        let m = M {
            seq: 7,
            name: "go".into(),
        };
        let b = encode(&m);
        // header, u64 7 (aligned at 0 of the body), then length 3 and "go\0".
        assert_eq!(
            b,
            [
                0, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, b'g', b'o', 0
            ]
        );
        assert_eq!(decode::<M>(&b).unwrap(), m);
        assert!(decode::<M>(&b[..3]).unwrap_err().contains("shorter"));
    }

    #[test]
    fn an_attachment_reads_back() {
        let a = Attachment {
            seq: 3,
            stamp_ns: -2,
            gid: [9; 16],
        };
        let b = a.to_bytes();
        // What PyPI eclipse-zenoh 1.10.2 gives for
        // `zenoh.ext.z_serialize((Int64(3), Int64(-2), [UInt8(9)] * 16))`.
        let mut want = vec![3, 0, 0, 0, 0, 0, 0, 0];
        want.extend([0xfe, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 16]);
        want.extend([9; 16]);
        assert_eq!(b, want);
        assert_eq!(Attachment::parse(&b), Some(a));
        assert_eq!(Attachment::parse(&b[..32]), None);
    }
}
