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

/// A field type of a ROS 2 type description (`type_description_interfaces/msg/FieldType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field<'a> {
    /// `int8`.
    Int8,
    /// `uint8`.
    Uint8,
    /// `bool`.
    Bool,
    /// `int32`.
    Int32,
    /// `uint32`.
    Uint32,
    /// `int64`.
    Int64,
    /// `uint64`.
    Uint64,
    /// `float64`.
    Float64,
    /// `string`.
    String,
    /// `uint8[N]`.
    Uint8Array(u64),
    /// `int32[]`.
    Int32Seq,
    /// `uint32[]`.
    Uint32Seq,
    /// `string[]`.
    StringSeq,
    /// A nested message, by its full name (`builtin_interfaces/msg/Time`).
    Nested(&'a str),
    /// `Nested[]`.
    NestedSeq(&'a str),
    /// `Nested[<=N]`.
    NestedBoundedSeq(&'a str, u64),
}

impl Field<'_> {
    /// REP-2016's `(type_id, capacity, nested_type_name)`: the FieldType constants, an array
    /// adds 48, a bounded sequence 96, an unbounded one 144.
    fn type_id(self) -> (u8, u64) {
        match self {
            Field::Int8 => (2, 0),
            Field::Uint8 => (3, 0),
            Field::Int32 => (6, 0),
            Field::Uint32 => (7, 0),
            Field::Int64 => (8, 0),
            Field::Uint64 => (9, 0),
            Field::Float64 => (11, 0),
            Field::Bool => (15, 0),
            Field::String => (17, 0),
            Field::Uint8Array(n) => (3 + 48, n),
            Field::Int32Seq => (6 + 144, 0),
            Field::Uint32Seq => (7 + 144, 0),
            Field::StringSeq => (17 + 144, 0),
            Field::Nested(_) => (1, 0),
            Field::NestedSeq(_) => (1 + 144, 0),
            Field::NestedBoundedSeq(_, n) => (1 + 96, n),
        }
    }

    /// The nested type's full name; empty for a plain type.
    fn nested_name(&self) -> &str {
        match self {
            Field::Nested(n) | Field::NestedSeq(n) | Field::NestedBoundedSeq(n, _) => n,
            _ => "",
        }
    }
}

/// A message type as REP-2016 describes it: its full name and its fields in order.
#[derive(Clone, Copy, Debug)]
pub struct TypeDescription<'a> {
    /// `package/msg/Name`.
    pub name: &'a str,
    /// `(field name, type)` in declaration order.
    pub fields: &'a [(&'a str, Field<'a>)],
}

/// `builtin_interfaces/msg/Time`.
pub const TIME: TypeDescription<'static> = TypeDescription {
    name: "builtin_interfaces/msg/Time",
    fields: &[("sec", Field::Int32), ("nanosec", Field::Uint32)],
};

/// `unique_identifier_msgs/msg/UUID`.
pub const UUID: TypeDescription<'static> = TypeDescription {
    name: "unique_identifier_msgs/msg/UUID",
    fields: &[("uuid", Field::Uint8Array(16))],
};

/// `service_msgs/msg/ServiceEventInfo`: the `info` of every service's `_Event` message.
pub const SERVICE_EVENT_INFO: TypeDescription<'static> = TypeDescription {
    name: "service_msgs/msg/ServiceEventInfo",
    fields: &[
        ("event_type", Field::Uint8),
        ("stamp", Field::Nested("builtin_interfaces/msg/Time")),
        ("client_gid", Field::Uint8Array(16)),
        ("sequence_number", Field::Int64),
    ],
};

impl TypeDescription<'_> {
    fn json(&self) -> String {
        let fields: Vec<String> = self
            .fields
            .iter()
            .map(|(name, f)| {
                let (id, capacity) = f.type_id();
                format!(
                    "{{\"name\": \"{name}\", \"type\": {{\"type_id\": {id}, \"capacity\": {capacity}, \"string_capacity\": 0, \"nested_type_name\": \"{}\"}}}}",
                    f.nested_name()
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
    /// The RIHS01 hash of `t` whose nested types are `referenced` (all of them, nested ones
    /// included): SHA-256 of the JSON `rosidl_generator_type_description` hashes (Python's
    /// `json.dumps` with `, ` and `: ` separators; fields without default values; referenced
    /// types sorted by name, each once).
    pub fn of(t: &TypeDescription, referenced: &[TypeDescription]) -> TypeHash {
        let mut refs: Vec<&TypeDescription> = referenced.iter().collect();
        refs.sort_by_key(|r| r.name);
        refs.dedup_by_key(|r| r.name);
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

    /// The hash of service `name` (`pkg/srv/Name`, or `pkg/action/Name_SendGoal` for an
    /// action's): ROS 2 describes a service as three fields, `request_message`,
    /// `response_message` and `event_message`, the last an `_Event` message (a
    /// `ServiceEventInfo` and at most one request and one response); `referenced` are the
    /// types the request and response use.
    pub fn of_service(
        name: &str,
        request: &[(&str, Field)],
        response: &[(&str, Field)],
        referenced: &[TypeDescription],
    ) -> TypeHash {
        let (req, resp, event) = (
            format!("{name}_Request"),
            format!("{name}_Response"),
            format!("{name}_Event"),
        );
        let event_fields = [
            ("info", Field::Nested(SERVICE_EVENT_INFO.name)),
            ("request", Field::NestedBoundedSeq(&req, 1)),
            ("response", Field::NestedBoundedSeq(&resp, 1)),
        ];
        let top_fields = [
            ("request_message", Field::Nested(&req)),
            ("response_message", Field::Nested(&resp)),
            ("event_message", Field::Nested(&event)),
        ];
        let mut refs = vec![
            TypeDescription {
                name: &req,
                fields: request,
            },
            TypeDescription {
                name: &resp,
                fields: response,
            },
            TypeDescription {
                name: &event,
                fields: &event_fields,
            },
            SERVICE_EVENT_INFO,
            TIME,
        ];
        refs.extend_from_slice(referenced);
        let top = TypeDescription {
            name,
            fields: &top_fields,
        };
        TypeHash::of(&top, &refs)
    }
}

/// `action_msgs/msg/GoalInfo`.
const GOAL_INFO: TypeDescription<'static> = TypeDescription {
    name: "action_msgs/msg/GoalInfo",
    fields: &[
        ("goal_id", Field::Nested("unique_identifier_msgs/msg/UUID")),
        ("stamp", Field::Nested("builtin_interfaces/msg/Time")),
    ],
};

/// The hash of `action_msgs/srv/CancelGoal`, every action's `cancel_goal` service.
pub fn cancel_goal_hash() -> TypeHash {
    TypeHash::of_service(
        "action_msgs/srv/CancelGoal",
        &[("goal_info", Field::Nested(GOAL_INFO.name))],
        &[
            ("return_code", Field::Int8),
            ("goals_canceling", Field::NestedSeq(GOAL_INFO.name)),
        ],
        &[GOAL_INFO, UUID],
    )
}

/// The hashes of the `send_goal` and `get_result` services of action `name`
/// (`pkg/action/Name`) whose goal and result messages are `goal` and `result` (types
/// without nested ones): ROS 2 makes them `Name_SendGoal` (a UUID and the goal → accepted
/// and a stamp) and `Name_GetResult` (a UUID → an int8 status and the result).
pub fn action_hashes(
    name: &str,
    goal: &TypeDescription,
    result: &TypeDescription,
) -> (TypeHash, TypeHash) {
    let send_goal = TypeHash::of_service(
        &format!("{name}_SendGoal"),
        &[
            ("goal_id", Field::Nested(UUID.name)),
            ("goal", Field::Nested(goal.name)),
        ],
        &[
            ("accepted", Field::Bool),
            ("stamp", Field::Nested(TIME.name)),
        ],
        &[UUID, *goal],
    );
    let get_result = TypeHash::of_service(
        &format!("{name}_GetResult"),
        &[("goal_id", Field::Nested(UUID.name))],
        &[
            ("status", Field::Int8),
            ("result", Field::Nested(result.name)),
        ],
        &[UUID, *result],
    );
    (send_goal, get_result)
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
    fn service_types_hash_as_ros2_computes_them() {
        // rmw_zenoh's design.md shows `2/add_two_ints/example_interfaces::srv::dds_::AddTwoInts_/RIHS01_e118de6b…`.
        assert_eq!(
            TypeHash::of_service(
                "example_interfaces/srv/AddTwoInts",
                &[("a", Field::Int64), ("b", Field::Int64)],
                &[("sum", Field::Int64)],
                &[],
            )
            .0,
            "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"
        );
        // The hashes rosidl generates (Jazzy, `*__description.c`) for ServiceEventInfo, UUID,
        // action_msgs/srv/CancelGoal, and the send_goal and get_result services of the
        // tutorial action `Fibonacci` (int32 order --- int32[] sequence --- …).
        assert_eq!(
            TypeHash::of(&SERVICE_EVENT_INFO, &[TIME]).0,
            "RIHS01_41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45"
        );
        assert_eq!(
            TypeHash::of(&UUID, &[]).0,
            "RIHS01_1b8e8aca958cbea28fe6ef60bf6c19b683c97a9ef60bb34752067d0f2f7ab437"
        );
        assert_eq!(
            cancel_goal_hash().0,
            "RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a"
        );
        let goal = TypeDescription {
            name: "custom_action_interfaces/action/Fibonacci_Goal",
            fields: &[("order", Field::Int32)],
        };
        let result = TypeDescription {
            name: "custom_action_interfaces/action/Fibonacci_Result",
            fields: &[("sequence", Field::Int32Seq)],
        };
        let (send_goal, get_result) =
            action_hashes("custom_action_interfaces/action/Fibonacci", &goal, &result);
        assert_eq!(
            send_goal.0,
            "RIHS01_cd44195cea6407c31072909245178934e410f8ce3ffca90ab35a8e77a5dd08d7"
        );
        assert_eq!(
            get_result.0,
            "RIHS01_2d01fbf73115b49b28af7e932bc7ff5ac9c94c19b9f71769dd81242a2667925a"
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
