//! What travels in a Zenoh sample, as rmw_zenoh puts it there: the payload is the message in
//! CDR (little endian, after the 4-byte encapsulation header `00 01 00 00`, the same bytes a
//! DDS sample carries), the attachment is the sample's sequence number, source timestamp and
//! source GID ([`Attachment`]), and the key expression names the type by its ROS 2 type hash
//! ([`TypeHash`], REP-2016's `RIHS01_<sha256>`).

use byteorder::LittleEndian;
use serde::Serialize;
use serde::de::DeserializeOwned;
use sha2::{Digest, Sha256};

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
/// as zenoh-ext does (two little-endian i64, then the 16 bytes). A service reply echoes the
/// request's sequence number and GID: that is how a client pairs them.
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

    /// The 32 bytes on the wire.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(32);
        out.extend(self.seq.to_le_bytes());
        out.extend(self.stamp_ns.to_le_bytes());
        out.extend(self.gid);
        out
    }

    /// Reads the 32 bytes back.
    pub fn parse(b: &[u8]) -> Option<Attachment> {
        if b.len() < 32 {
            return None;
        }
        Some(Attachment {
            seq: i64::from_le_bytes(b[0..8].try_into().ok()?),
            stamp_ns: i64::from_le_bytes(b[8..16].try_into().ok()?),
            gid: b[16..32].try_into().ok()?,
        })
    }
}

/// A field type of a ROS 2 type description (`type_description_interfaces/msg/FieldType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// `int32`.
    Int32,
    /// `uint32`.
    Uint32,
    /// `uint64`.
    Uint64,
    /// `float64`.
    Float64,
    /// `string`.
    String,
    /// `uint32[]`.
    Uint32Seq,
    /// `string[]`.
    StringSeq,
    /// A nested message, by its full name (`builtin_interfaces/msg/Time`).
    Nested(&'static str),
}

impl Field {
    /// The `type_id` of REP-2016 (FieldType constants; an unbounded sequence adds 144).
    fn type_id(self) -> u8 {
        match self {
            Field::Nested(_) => 1,
            Field::Int32 => 6,
            Field::Uint32 => 7,
            Field::Uint64 => 9,
            Field::Float64 => 11,
            Field::String => 17,
            Field::Uint32Seq => 7 + 144,
            Field::StringSeq => 17 + 144,
        }
    }
}

/// A message type as REP-2016 describes it: its full name and its fields in order.
#[derive(Clone, Copy, Debug)]
pub struct TypeDescription {
    /// `package/msg/Name`.
    pub name: &'static str,
    /// `(field name, type)` in declaration order.
    pub fields: &'static [(&'static str, Field)],
}

/// `builtin_interfaces/msg/Time`.
pub const TIME: TypeDescription = TypeDescription {
    name: "builtin_interfaces/msg/Time",
    fields: &[("sec", Field::Int32), ("nanosec", Field::Uint32)],
};

impl TypeDescription {
    fn json(&self) -> String {
        let fields: Vec<String> = self
            .fields
            .iter()
            .map(|(name, f)| {
                let nested = match f {
                    Field::Nested(n) => n,
                    _ => "",
                };
                format!(
                    "{{\"name\": \"{name}\", \"type\": {{\"type_id\": {}, \"capacity\": 0, \"string_capacity\": 0, \"nested_type_name\": \"{nested}\"}}}}",
                    f.type_id()
                )
            })
            .collect();
        format!(
            "{{\"type_name\": \"{}\", \"fields\": [{}]}}",
            self.name,
            fields.join(", ")
        )
    }
}

/// A ROS 2 type hash, `RIHS01_` and 64 hex digits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TypeHash(pub String);

impl TypeHash {
    /// The RIHS01 hash of `t` whose nested types are `referenced`: SHA-256 of the JSON
    /// `rosidl_generator_type_description` hashes (Python's `json.dumps` with `, ` and `: `
    /// separators; fields without default values; referenced types sorted by name).
    pub fn of(t: &TypeDescription, referenced: &[TypeDescription]) -> TypeHash {
        let mut refs: Vec<&TypeDescription> = referenced.iter().collect();
        refs.sort_by_key(|r| r.name);
        let refs: Vec<String> = refs.iter().map(|r| r.json()).collect();
        let json = format!(
            "{{\"type_description\": {}, \"referenced_type_descriptions\": [{}]}}",
            t.json(),
            refs.join(", ")
        );
        let digest = Sha256::digest(json.as_bytes());
        let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
        TypeHash(format!("RIHS01_{hex}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn std_msgs_string_hashes_as_ros2_computes_it() {
        // The hash rmw_zenoh's documentation shows in `0/chatter/std_msgs::msg::dds_::String_/…`.
        let s = TypeDescription {
            name: "std_msgs/msg/String",
            fields: &[("data", Field::String)],
        };
        assert_eq!(
            TypeHash::of(&s, &[]).0,
            "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
        );
    }

    #[test]
    fn nested_types_hash_as_ros2_computes_them() {
        // The hashes ROS 2 (Jazzy) gives builtin_interfaces/msg/Time and std_msgs/msg/Header
        // (a nested Time and a string), as published type descriptions list them.
        assert_eq!(
            TypeHash::of(&TIME, &[]).0,
            "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197"
        );
        let header = TypeDescription {
            name: "std_msgs/msg/Header",
            fields: &[
                ("stamp", Field::Nested("builtin_interfaces/msg/Time")),
                ("frame_id", Field::String),
            ],
        };
        assert_eq!(
            TypeHash::of(&header, &[TIME]).0,
            "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01"
        );
    }

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
        assert_eq!(b.len(), 32);
        assert_eq!(&b[..8], &[3, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(Attachment::parse(&b), Some(a));
        assert_eq!(Attachment::parse(&b[..31]), None);
    }
}
