//! What travels in a Zenoh sample, as rmw_zenoh puts it there: the payload is the message in
//! CDR (little endian, after the 4-byte encapsulation header `00 01 00 00`, the same bytes a
//! DDS sample carries), the attachment is the sample's sequence number, source timestamp and
//! source GID ([`Attachment`]); the key expression names the type by its ROS 2 type hash
//! ([`super::type_hash`]).

use std::sync::atomic::{AtomicI64, Ordering};

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

/// Why a payload could not be read as a message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WireError {
    /// Fewer bytes than the 4-byte encapsulation header.
    #[error("{0} bytes: shorter than a CDR header")]
    Short(usize),
    /// An encapsulation other than plain CDR (big or little endian).
    #[error("CDR encapsulation kind {0} is not plain CDR")]
    Encapsulation(u8),
    /// The body does not hold the message.
    #[error("CDR: {0}")]
    Cdr(#[from] cdr_encoding::Error),
}

/// A message from CDR bytes (big- or little-endian encapsulation).
pub fn decode<M: DeserializeOwned>(bytes: &[u8]) -> Result<M, WireError> {
    if bytes.len() < 4 {
        return Err(WireError::Short(bytes.len()));
    }
    let body = &bytes[4..];
    let r = match bytes[1] {
        1 => cdr_encoding::from_bytes::<M, LittleEndian>(body),
        0 => cdr_encoding::from_bytes::<M, byteorder::BigEndian>(body),
        k => return Err(WireError::Encapsulation(k)),
    };
    Ok(r?.0)
}

/// A writer's identity on the wire: its GID and the sequence number of its next sample, as
/// rmw_zenoh numbers each publisher's samples and each client's requests from 1. The GID
/// is the writer's name hashed, and the process id (no random draw): unique enough to pair
/// replies, the same for the same run.
#[derive(Debug)]
pub struct Source {
    gid: [u8; 16],
    seq: AtomicI64,
}

impl Source {
    /// The writer named `name` (a topic's or a client's) of this process.
    pub fn new(name: &str) -> Source {
        let mut gid = [0; 16];
        gid[..8].copy_from_slice(&crate::ros2::robot::id_hash(name).to_le_bytes());
        gid[8..12].copy_from_slice(&std::process::id().to_le_bytes());
        Source {
            gid,
            seq: AtomicI64::new(1),
        }
    }

    /// The GID.
    pub fn gid(&self) -> [u8; 16] {
        self.gid
    }

    /// The attachment of the next sample, stamped now.
    pub fn next(&self) -> Attachment {
        Attachment::now(self.seq.fetch_add(1, Ordering::Relaxed), self.gid)
    }
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
        assert!(matches!(decode::<M>(&b[..3]), Err(WireError::Short(3))));
        assert!(matches!(decode::<M>(&b[..10]), Err(WireError::Cdr(_))));
        let mut odd = b.clone();
        odd[1] = 7;
        assert!(matches!(
            decode::<M>(&odd),
            Err(WireError::Encapsulation(7))
        ));
    }

    #[test]
    fn a_source_numbers_its_samples_from_1_under_one_gid() {
        let (a, b) = (Source::new("/r1/exec_place"), Source::new("/r2/exec_place"));
        let (first, second) = (a.next(), a.next());
        assert_eq!((first.seq, second.seq), (1, 2));
        assert_eq!((first.gid, second.gid), (a.gid(), a.gid()));
        assert_ne!(a.gid(), b.gid());
        assert_eq!(&a.gid()[8..12], &std::process::id().to_le_bytes());
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
