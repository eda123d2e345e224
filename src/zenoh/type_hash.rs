//! ROS 2 type hashes (REP-2016's `RIHS01_<sha256>`), which rmw_zenoh puts in every key
//! expression and liveliness token, computed from the interfaces' own definitions: the
//! `gspn_msgs` files and the standard messages of [`crate::ros2::msgs::schema`], so a change
//! of a `.msg` file changes its hash here too, with no copy of the fields to keep in step.
//!
//! A type's description is its name and its fields (name, type id, capacities, nested type
//! name; no constants, no default values); the hash is SHA-256 of the JSON of that
//! description and of every type it uses, directly or not (sorted by name), as
//! `rosidl_generator_type_description` writes it. A service is described as three fields —
//! its request, its response and an `_Event` message — and an action's parts
//! (`_SendGoal`, `_GetResult`, `_FeedbackMessage`) as ROS 2 generates them.

use std::collections::BTreeMap;
use std::sync::LazyLock;

use sha2::{Digest, Sha256};

use crate::ros2::msgs::schema;

/// Why a type could not be described.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TypeError {
    /// A type (by full name) whose definition is not known.
    #[error("no definition of ROS 2 type `{0}`")]
    Unknown(String),
    /// A field line of a definition that is not `type name [default]`.
    #[error("ROS 2 type `{ty}`: cannot read field `{line}`")]
    BadField {
        /// The type being described.
        ty: String,
        /// The line.
        line: String,
    },
    /// A `.action` or `.srv` definition without its `---` separators.
    #[error("ROS 2 type `{0}`: expected parts separated by `---`")]
    Parts(String),
}

/// A field's type as `type_description_interfaces/msg/FieldType` gives it.
#[derive(Clone, Debug, PartialEq, Eq)]
struct FieldType {
    /// The FieldType constant; an array adds 48, a bounded sequence 96, a sequence 144.
    id: u8,
    /// An array's length or a bounded sequence's bound; 0 otherwise.
    capacity: u64,
    /// A bounded string's bound; 0 otherwise.
    string_capacity: u64,
    /// The nested type's full name (`builtin_interfaces/msg/Time`); empty for a primitive.
    nested: String,
}

/// The FieldType constant of a primitive (`char` is a `uint8`, as rosidl maps it).
fn primitive_id(ty: &str) -> Option<u8> {
    Some(match ty {
        "int8" => 2,
        "uint8" | "char" => 3,
        "int16" => 4,
        "uint16" => 5,
        "int32" => 6,
        "uint32" => 7,
        "int64" => 8,
        "uint64" => 9,
        "float32" => 10,
        "float64" => 11,
        "bool" => 15,
        "byte" => 16,
        "string" => 17,
        "wstring" => 18,
        _ => return None,
    })
}

/// The nested type `ty` (`Pose`, `geometry_msgs/Pose`, `gspn_msgs/action/ExecPlace_Goal`)
/// as a full name, seen from package `pkg`.
fn full_name(ty: &str, pkg: &str) -> String {
    match ty.split('/').collect::<Vec<_>>()[..] {
        [t] => format!("{pkg}/msg/{t}"),
        [p, t] => format!("{p}/msg/{t}"),
        _ => ty.to_string(),
    }
}

impl FieldType {
    /// The type of a field written `ty` (`uint32[]`, `KeyValue[<=4]`, `string<=8`,
    /// `uint8[16]`) in package `pkg`.
    fn parse(ty: &str, pkg: &str) -> Option<FieldType> {
        let (base, suffix) = match ty.find('[') {
            Some(i) => (&ty[..i], Some(ty[i + 1..].strip_suffix(']')?)),
            None => (ty, None),
        };
        let (base, string_capacity) = match base.split_once("<=") {
            Some((b, n)) => (b, n.parse().ok()?),
            None => (base, 0),
        };
        let (mut id, nested) = match primitive_id(base) {
            // A bounded string is BOUNDED_STRING (21), a bounded wstring 22.
            Some(id) if string_capacity > 0 => (id + 4, String::new()),
            Some(id) => (id, String::new()),
            None => (1, full_name(base, pkg)),
        };
        let capacity = match suffix {
            None => 0,
            Some("") => {
                id += 144;
                0
            }
            Some(s) => match s.strip_prefix("<=") {
                Some(n) => {
                    id += 96;
                    n.parse().ok()?
                }
                None => {
                    id += 48;
                    s.parse().ok()?
                }
            },
        };
        Some(FieldType {
            id,
            capacity,
            string_capacity,
            nested,
        })
    }
}

/// A type as REP-2016 describes it: its full name and its fields in order.
#[derive(Clone, Debug, PartialEq, Eq)]
struct TypeDescription {
    name: String,
    fields: Vec<(String, FieldType)>,
}

impl TypeDescription {
    /// The fields of `def`, the definition of type `name` (`pkg/msg/Name`, …): constants,
    /// comments and default values left out.
    fn parse(name: &str, def: &str) -> Result<TypeDescription, TypeError> {
        let pkg = name.split('/').next().unwrap_or_default();
        let mut fields = Vec::new();
        for line in def.lines() {
            let line = line.split('#').next().unwrap_or_default().trim();
            if line.is_empty() {
                continue;
            }
            let (ty, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
            // `int8 NAME = 1`: a constant, not a field.
            if rest.contains('=') {
                continue;
            }
            let Some(field) = rest.split_whitespace().next() else {
                return Err(TypeError::BadField {
                    ty: name.to_string(),
                    line: line.to_string(),
                });
            };
            let ft = FieldType::parse(ty, pkg).ok_or_else(|| TypeError::BadField {
                ty: name.to_string(),
                line: line.to_string(),
            })?;
            fields.push((field.to_string(), ft));
        }
        Ok(TypeDescription {
            name: name.to_string(),
            fields,
        })
    }

    fn json(&self) -> String {
        let fields: Vec<String> = self
            .fields
            .iter()
            .map(|(name, f)| {
                format!(
                    "{{\"name\": \"{name}\", \"type\": {{\"type_id\": {}, \"capacity\": {}, \"string_capacity\": {}, \"nested_type_name\": \"{}\"}}}}",
                    f.id, f.capacity, f.string_capacity, f.nested
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

/// The types hashes are computed from, by full name.
#[derive(Clone, Debug, Default)]
pub struct Types(BTreeMap<String, TypeDescription>);

impl Types {
    /// Every type of [`schema`]: the `gspn_msgs` messages, the ExecPlace action's parts,
    /// the standard messages and services they use.
    pub fn known() -> Result<Types, TypeError> {
        let mut t = Types::default();
        for (name, def) in schema::GSPN.iter().chain(schema::STANDARD) {
            t.message(name, def)?;
        }
        for (name, def) in schema::STANDARD_SERVICES {
            let (req, resp) = def
                .split_once("\n---\n")
                .ok_or_else(|| TypeError::Parts(name.to_string()))?;
            t.service(name, req, resp)?;
        }
        t.action("gspn_msgs/action/ExecPlace", schema::EXEC_PLACE)?;
        Ok(t)
    }

    fn message(&mut self, name: &str, def: &str) -> Result<(), TypeError> {
        let d = TypeDescription::parse(name, def)?;
        self.0.insert(name.to_string(), d);
        Ok(())
    }

    /// Service `name` (`pkg/srv/Name`) from its request and response definitions: its
    /// `_Request`, `_Response` and `_Event` messages and the service type itself.
    fn service(&mut self, name: &str, request: &str, response: &str) -> Result<(), TypeError> {
        let (req, resp, event) = (
            format!("{name}_Request"),
            format!("{name}_Response"),
            format!("{name}_Event"),
        );
        self.message(&req, request)?;
        self.message(&resp, response)?;
        self.message(
            &event,
            &format!(
                "service_msgs/ServiceEventInfo info\n{req}[<=1] request\n{resp}[<=1] response\n"
            ),
        )?;
        self.message(
            name,
            &format!("{req} request_message\n{resp} response_message\n{event} event_message\n"),
        )
    }

    /// Action `name` (`pkg/action/Name`) from its definition (goal, result, feedback): its
    /// three messages, the `_SendGoal` and `_GetResult` services and the `_FeedbackMessage`
    /// its feedback topic carries.
    fn action(&mut self, name: &str, def: &str) -> Result<(), TypeError> {
        let parts: Vec<&str> = def.split("\n---\n").collect();
        let [goal, result, feedback] = parts[..] else {
            return Err(TypeError::Parts(name.to_string()));
        };
        for (part, d) in [("Goal", goal), ("Result", result), ("Feedback", feedback)] {
            self.message(&format!("{name}_{part}"), d)?;
        }
        let uuid = "unique_identifier_msgs/UUID goal_id\n";
        self.service(
            &format!("{name}_SendGoal"),
            &format!("{uuid}{name}_Goal goal\n"),
            "bool accepted\nbuiltin_interfaces/Time stamp\n",
        )?;
        self.service(
            &format!("{name}_GetResult"),
            uuid,
            &format!("int8 status\n{name}_Result result\n"),
        )?;
        self.message(
            &format!("{name}_FeedbackMessage"),
            &format!("{uuid}{name}_Feedback feedback\n"),
        )
    }

    /// The RIHS01 hash of type `name`: SHA-256 of the JSON `rosidl_generator_type_description`
    /// hashes (Python's `json.dumps` with `, ` and `: ` separators; the type, then every type
    /// it uses, sorted by name, each once).
    pub fn hash(&self, name: &str) -> Result<TypeHash, TypeError> {
        let top = self.get(name)?;
        let mut used: BTreeMap<&str, &TypeDescription> = BTreeMap::new();
        let mut todo: Vec<&str> = nested(top).collect();
        while let Some(n) = todo.pop() {
            if used.contains_key(n) {
                continue;
            }
            let d = self.get(n)?;
            used.insert(n, d);
            todo.extend(nested(d));
        }
        let refs: Vec<String> = used.values().map(|d| d.json()).collect();
        let json = format!(
            "{{\"type_description\": {}, \"referenced_type_descriptions\": [{}]}}",
            top.json(),
            refs.join(", ")
        );
        let digest = Sha256::digest(json.as_bytes());
        let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
        Ok(TypeHash(format!("RIHS01_{hex}")))
    }

    fn get(&self, name: &str) -> Result<&TypeDescription, TypeError> {
        self.0
            .get(name)
            .ok_or_else(|| TypeError::Unknown(name.to_string()))
    }
}

/// The types the fields of `d` nest.
fn nested(d: &TypeDescription) -> impl Iterator<Item = &str> {
    d.fields
        .iter()
        .map(|(_, f)| f.nested.as_str())
        .filter(|n| !n.is_empty())
}

/// The hash of a known type ([`Types::known`]), computed once.
pub fn hash_of(name: &str) -> Result<TypeHash, TypeError> {
    static KNOWN: LazyLock<Result<Types, TypeError>> = LazyLock::new(Types::known);
    KNOWN.as_ref().map_err(Clone::clone)?.hash(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(defs: &[(&str, &str)]) -> Types {
        let mut t = Types::known().unwrap();
        for (n, d) in defs {
            t.message(n, d).unwrap();
        }
        t
    }

    #[test]
    fn messages_hash_as_ros2_computes_them() {
        // The hashes ROS 2 (Jazzy) gives these types, as rmw_zenoh's design.md
        // (`0/chatter/std_msgs::msg::dds_::String_/…`) and the generated
        // `*__description.c` files list them.
        let t = with(&[("std_msgs/msg/String", "string data\n")]);
        for (name, hash) in [
            (
                "std_msgs/msg/String",
                "df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
            ),
            (
                "builtin_interfaces/msg/Time",
                "b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
            ),
            (
                "std_msgs/msg/Header",
                "f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01",
            ),
            (
                "geometry_msgs/msg/PoseStamped",
                "10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
            ),
            (
                "unique_identifier_msgs/msg/UUID",
                "1b8e8aca958cbea28fe6ef60bf6c19b683c97a9ef60bb34752067d0f2f7ab437",
            ),
            (
                "service_msgs/msg/ServiceEventInfo",
                "41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45",
            ),
            (
                "action_msgs/msg/GoalStatusArray",
                "6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e",
            ),
        ] {
            assert_eq!(t.hash(name).unwrap().0, format!("RIHS01_{hash}"), "{name}");
        }
    }

    #[test]
    fn services_and_actions_hash_as_ros2_computes_them() {
        let mut t = Types::known().unwrap();
        // rmw_zenoh's design.md: `2/add_two_ints/example_interfaces::srv::dds_::AddTwoInts_/RIHS01_e118de6b…`.
        t.service(
            "example_interfaces/srv/AddTwoInts",
            "int64 a\nint64 b\n",
            "int64 sum\n",
        )
        .unwrap();
        // The tutorial action of ROS 2's documentation.
        t.action(
            "custom_action_interfaces/action/Fibonacci",
            "int32 order\n---\nint32[] sequence\n---\nint32[] partial_sequence\n",
        )
        .unwrap();
        for (name, hash) in [
            (
                "example_interfaces/srv/AddTwoInts",
                "e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a",
            ),
            (
                "action_msgs/srv/CancelGoal",
                "573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a",
            ),
            (
                "custom_action_interfaces/action/Fibonacci_SendGoal",
                "cd44195cea6407c31072909245178934e410f8ce3ffca90ab35a8e77a5dd08d7",
            ),
            (
                "custom_action_interfaces/action/Fibonacci_GetResult",
                "2d01fbf73115b49b28af7e932bc7ff5ac9c94c19b9f71769dd81242a2667925a",
            ),
        ] {
            assert_eq!(t.hash(name).unwrap().0, format!("RIHS01_{hash}"), "{name}");
        }
    }

    #[test]
    fn every_part_of_the_interfaces_has_a_hash() {
        for name in [
            "gspn_msgs/msg/Firing",
            "gspn_msgs/msg/Marking",
            "gspn_msgs/msg/RunState",
            "gspn_msgs/msg/Drift",
            "gspn_msgs/msg/Heartbeat",
            "gspn_msgs/action/ExecPlace_SendGoal",
            "gspn_msgs/action/ExecPlace_GetResult",
            "gspn_msgs/action/ExecPlace_FeedbackMessage",
        ] {
            let h = hash_of(name).unwrap().0;
            assert!(h.starts_with("RIHS01_") && h.len() == 7 + 64, "{name}: {h}");
        }
        assert_eq!(
            hash_of("gspn_msgs/msg/Nope"),
            Err(TypeError::Unknown("gspn_msgs/msg/Nope".into()))
        );
    }

    #[test]
    fn field_types_read_as_rep_2016_numbers_them() {
        let f = |s| FieldType::parse(s, "p").unwrap();
        assert_eq!((f("uint8[16]").id, f("uint8[16]").capacity), (51, 16));
        assert_eq!(f("string[]").id, 161);
        assert_eq!((f("Pose[<=3]").id, f("Pose[<=3]").capacity), (97, 3));
        assert_eq!(f("Pose").nested, "p/msg/Pose");
        assert_eq!((f("string<=8").id, f("string<=8").string_capacity), (21, 8));
        assert_eq!(FieldType::parse("uint8[x]", "p"), None);
        let d = TypeDescription::parse("p/msg/Q", "int8 A = 1\nfloat64 w 1 # default\n").unwrap();
        assert_eq!(d.fields.len(), 1);
        assert!(matches!(
            TypeDescription::parse("p/msg/Q", "float64\n"),
            Err(TypeError::BadField { .. })
        ));
    }
}
