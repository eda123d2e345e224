//! Interfaces v2: the `.msg`/`.action` files of `ros2/gspn_msgs` are the one definition; this
//! test parses them (with its own small parser) and checks that the Rust types
//! (`gspn::ros2::msgs`, walked through serde in field order, which is their CDR layout) and
//! the Python robot's and listener's Cyclone DDS types carry the same fields, types and
//! constants, so the copies cannot drift apart again.

use std::collections::BTreeMap;

use gspn::ros2::msgs::{
    self, Drift, ExecPlaceFeedback, ExecPlaceGoal, ExecPlaceResult, Firing, Header, Heartbeat,
    KeyValue, Marking, PoseStamped, RunState, schema,
};
use serde::Serialize;

use crate::ros2_support::repo;

/// One parsed `.msg` section: fields `(type, name)` and constants `(type, name, value)`.
#[derive(Debug, Default)]
struct Def {
    fields: Vec<(String, String)>,
    constants: Vec<(String, String, String)>,
}

fn parse(text: &str) -> Def {
    let mut d = Def::default();
    for line in text.lines() {
        let line = line.split('#').next().unwrap().trim();
        if line.is_empty() {
            continue;
        }
        let (ty, rest) = line.split_once(char::is_whitespace).expect(line);
        let rest = rest.trim();
        if let Some((name, value)) = rest.split_once('=') {
            d.constants
                .push((ty.into(), name.trim().into(), value.trim().into()));
        } else {
            // A default value may follow the name.
            let name = rest.split_whitespace().next().unwrap();
            d.fields.push((ty.into(), name.into()));
        }
    }
    d
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(repo(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

const PRIMITIVES: &[&str] = &[
    "bool", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32",
    "float64", "string",
];

/// A message's fields flattened to `path: primitive` lines, nested messages expanded (the
/// standard ones from their ROS 2 definitions, gspn's from the files on disk).
fn flatten_msg(def: &Def, pkg: &str, prefix: &str, out: &mut Vec<String>) {
    for (ty, name) in &def.fields {
        let (base, array) = match ty.split_once('[') {
            Some((b, _)) => (b, "[]"),
            None => (ty.as_str(), ""),
        };
        let path = format!("{prefix}{name}{array}");
        if PRIMITIVES.contains(&base) {
            out.push(format!("{path}: {base}"));
            continue;
        }
        let full = if base.contains('/') {
            base.to_string()
        } else {
            format!("{pkg}/{base}")
        };
        let (p, _) = full.split_once('/').unwrap();
        let text = if p == "gspn_msgs" {
            read(&format!(
                "ros2/gspn_msgs/msg/{}.msg",
                full.rsplit('/').next().unwrap()
            ))
        } else {
            schema::definition(&full)
                .unwrap_or_else(|| panic!("unknown type {full}"))
                .to_string()
        };
        flatten_msg(&parse(&text), p, &format!("{path}."), out);
    }
}

fn msg_fields(def: &Def) -> Vec<String> {
    let mut out = Vec::new();
    flatten_msg(def, "gspn_msgs", "", &mut out);
    out
}

/// A serde serializer that writes down each field's path and ROS primitive type instead of
/// its value (sequences through their first element: give it one).
#[derive(Default)]
struct Tracer {
    path: Vec<String>,
    out: Vec<String>,
}

#[derive(Debug)]
struct TraceError(String);
impl std::fmt::Display for TraceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for TraceError {}
impl serde::ser::Error for TraceError {
    fn custom<T: std::fmt::Display>(m: T) -> Self {
        TraceError(m.to_string())
    }
}

impl Tracer {
    fn leaf(&mut self, ty: &str) -> Result<(), TraceError> {
        self.out.push(format!("{}: {ty}", self.path.concat()));
        Ok(())
    }
    fn unsupported(&self, what: &str) -> Result<(), TraceError> {
        Err(TraceError(format!("{what} at {}", self.path.concat())))
    }
}

struct Seq<'a> {
    t: &'a mut Tracer,
    first: bool,
}

impl serde::ser::SerializeSeq for Seq<'_> {
    type Ok = ();
    type Error = TraceError;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<(), TraceError> {
        if std::mem::replace(&mut self.first, false) {
            v.serialize(&mut *self.t)?;
        }
        Ok(())
    }
    fn end(self) -> Result<(), TraceError> {
        let t = self.t;
        if self.first {
            t.unsupported("an empty sequence (give the sample one element)")?;
        }
        t.path.pop();
        Ok(())
    }
}

impl serde::ser::SerializeStruct for &mut Tracer {
    type Ok = ();
    type Error = TraceError;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), TraceError> {
        let dot = if self.path.is_empty() { "" } else { "." };
        self.path.push(format!("{dot}{key}"));
        v.serialize(&mut **self)?;
        self.path.pop();
        Ok(())
    }
    fn end(self) -> Result<(), TraceError> {
        Ok(())
    }
}

type Never = serde::ser::Impossible<(), TraceError>;

impl<'a> serde::Serializer for &'a mut Tracer {
    type Ok = ();
    type Error = TraceError;
    type SerializeSeq = Seq<'a>;
    type SerializeTuple = Never;
    type SerializeTupleStruct = Never;
    type SerializeTupleVariant = Never;
    type SerializeMap = Never;
    type SerializeStruct = Self;
    type SerializeStructVariant = Never;

    fn serialize_bool(self, _: bool) -> Result<(), TraceError> {
        self.leaf("bool")
    }
    fn serialize_i8(self, _: i8) -> Result<(), TraceError> {
        self.leaf("int8")
    }
    fn serialize_i16(self, _: i16) -> Result<(), TraceError> {
        self.leaf("int16")
    }
    fn serialize_i32(self, _: i32) -> Result<(), TraceError> {
        self.leaf("int32")
    }
    fn serialize_i64(self, _: i64) -> Result<(), TraceError> {
        self.leaf("int64")
    }
    fn serialize_u8(self, _: u8) -> Result<(), TraceError> {
        self.leaf("uint8")
    }
    fn serialize_u16(self, _: u16) -> Result<(), TraceError> {
        self.leaf("uint16")
    }
    fn serialize_u32(self, _: u32) -> Result<(), TraceError> {
        self.leaf("uint32")
    }
    fn serialize_u64(self, _: u64) -> Result<(), TraceError> {
        self.leaf("uint64")
    }
    fn serialize_f32(self, _: f32) -> Result<(), TraceError> {
        self.leaf("float32")
    }
    fn serialize_f64(self, _: f64) -> Result<(), TraceError> {
        self.leaf("float64")
    }
    fn serialize_char(self, _: char) -> Result<(), TraceError> {
        self.unsupported("char")
    }
    fn serialize_str(self, _: &str) -> Result<(), TraceError> {
        self.leaf("string")
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), TraceError> {
        self.unsupported("bytes")
    }
    fn serialize_none(self) -> Result<(), TraceError> {
        self.unsupported("Option")
    }
    fn serialize_some<T: ?Sized + Serialize>(self, _: &T) -> Result<(), TraceError> {
        self.unsupported("Option")
    }
    fn serialize_unit(self) -> Result<(), TraceError> {
        self.unsupported("()")
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), TraceError> {
        self.unsupported("a unit struct")
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
    ) -> Result<(), TraceError> {
        self.unsupported("an enum")
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<(), TraceError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), TraceError> {
        self.unsupported("an enum")
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Seq<'a>, TraceError> {
        self.path.push("[]".into());
        Ok(Seq {
            t: self,
            first: true,
        })
    }
    fn serialize_tuple(self, _: usize) -> Result<Never, TraceError> {
        Err(TraceError("tuple".into()))
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Never, TraceError> {
        Err(TraceError("tuple struct".into()))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Never, TraceError> {
        Err(TraceError("enum".into()))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Never, TraceError> {
        Err(TraceError("map".into()))
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, TraceError> {
        Ok(self)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Never, TraceError> {
        Err(TraceError("enum".into()))
    }
}

fn rust_fields<T: Serialize>(v: &T) -> Vec<String> {
    let mut t = Tracer::default();
    v.serialize(&mut t).unwrap();
    t.out
}

/// Cyclone DDS (Python) `IdlStruct`s of a file: class name → (DDS type name, fields
/// `(name, type)`).
type PyStructs = BTreeMap<String, (String, Vec<(String, String)>)>;

/// The `IdlStruct`s of the Python file `rel`.
fn python_structs(rel: &str) -> PyStructs {
    let text = read(rel);
    let mut out = BTreeMap::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let Some(rest) = line.strip_prefix("class ") else {
            continue;
        };
        // The header may span lines: `class X(\n    IdlStruct, typename="…"\n):`.
        let mut header = rest.to_string();
        while !header.trim_end().ends_with(':') {
            header.push_str(lines.next().unwrap().trim());
        }
        let Some((name, args)) = header.split_once('(') else {
            continue;
        };
        let Some(ty) = args.split("typename=\"").nth(1) else {
            continue;
        };
        let ty = ty.split('"').next().unwrap().to_string();
        let mut fields = Vec::new();
        while let Some(l) = lines.peek() {
            let Some(f) = l.strip_prefix("    ") else {
                break;
            };
            let (n, t) = f.split_once(':').unwrap();
            fields.push((n.trim().to_string(), t.trim().to_string()));
            lines.next();
        }
        out.insert(name.trim().to_string(), (ty, fields));
    }
    out
}

fn flatten_python(structs: &PyStructs, class: &str, prefix: &str, out: &mut Vec<String>) {
    for (name, ty) in &structs[class].1 {
        let (ty, array) = match ty.strip_prefix("sequence[") {
            Some(t) => (t.trim_end_matches(']'), "[]"),
            None => (ty.as_str(), ""),
        };
        let path = format!("{prefix}{name}{array}");
        match ty {
            "str" => out.push(format!("{path}: string")),
            t if PRIMITIVES.contains(&t) => out.push(format!("{path}: {t}")),
            t => flatten_python(structs, t, &format!("{path}."), out),
        }
    }
}

fn python_fields(structs: &PyStructs, class: &str, dds_type: &str) -> Vec<String> {
    assert_eq!(structs[class].0, dds_type, "Python class {class}");
    let mut out = Vec::new();
    flatten_python(structs, class, "", &mut out);
    out
}

/// `NAME = value` assignments of a Python file (module level).
fn python_constants(rel: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for line in read(rel).lines() {
        // `A, B = 1, 2` too.
        let Some((names, values)) = line.split_once(" = ") else {
            continue;
        };
        if !names
            .chars()
            .all(|c| c.is_ascii_uppercase() || c == '_' || c == ',' || c == ' ')
        {
            continue;
        }
        for (n, v) in names.split(',').zip(values.split(',')) {
            out.insert(n.trim().to_string(), v.trim().to_string());
        }
    }
    out
}

fn sample_header() -> Header {
    Header::default()
}

#[test]
fn the_msg_files_the_rust_types_and_the_python_robot_agree() {
    let firing = Firing {
        header: sample_header(),
        model_time: 0.0,
        seq: 1,
        transition: "t".into(),
        marking: vec![1],
        robots: vec!["r1".into()],
    };
    let marking = Marking {
        header: sample_header(),
        model_time: 0.0,
        seq: 0,
        places: vec!["p".into()],
        tokens: vec![1],
    };
    let drift = Drift {
        header: sample_header(),
        model_time: 0.0,
        transition: String::new(),
        place: String::new(),
        observed: 0.0,
        predicted: 0.0,
        interval_low: 0.0,
        interval_high: 0.0,
        n: 0,
        p_value: 0.0,
        text: String::new(),
    };
    let run = RunState {
        state: RunState::RUNNING,
        stopped: String::new(),
        firings: 0,
    };
    let heartbeat = Heartbeat {
        robot: "r1".into(),
        seq: 0,
    };
    let goal = ExecPlaceGoal {
        place: "p".into(),
        agent: 0,
        has_target: true,
        target: PoseStamped::on_map(1.0, 2.0, 0.0),
        args: vec![KeyValue::default()],
    };
    let result = ExecPlaceResult::cancelled();
    let feedback = ExecPlaceFeedback { elapsed: 0.0 };

    let msg = |n: &str| parse(&read(&format!("ros2/gspn_msgs/msg/{n}.msg")));
    let cases: Vec<(&str, Vec<String>)> = vec![
        ("Firing", rust_fields(&firing)),
        ("Marking", rust_fields(&marking)),
        ("Drift", rust_fields(&drift)),
        ("RunState", rust_fields(&run)),
        ("Heartbeat", rust_fields(&heartbeat)),
    ];
    for (name, rust) in &cases {
        assert_eq!(&msg_fields(&msg(name)), rust, "gspn_msgs/msg/{name}");
    }
    assert_eq!(
        msg_fields(&msg("Firing"))[..3],
        [
            "header.stamp.sec: int32",
            "header.stamp.nanosec: uint32",
            "header.frame_id: string"
        ]
    );

    let action = read("ros2/gspn_msgs/action/ExecPlace.action");
    let parts: Vec<Def> = action.split("\n---\n").map(parse).collect();
    assert_eq!(parts.len(), 3, "goal, result, feedback");
    assert_eq!(msg_fields(&parts[0]), rust_fields(&goal), "ExecPlace goal");
    assert_eq!(
        msg_fields(&parts[1]),
        rust_fields(&result),
        "ExecPlace result"
    );
    assert_eq!(
        msg_fields(&parts[2]),
        rust_fields(&feedback),
        "ExecPlace feedback"
    );
    assert!(
        rust_fields(&goal).contains(&"target.pose.orientation.w: float64".to_string()),
        "the goal carries a geometry_msgs/PoseStamped"
    );

    // Constants: the files' against the Rust ones and the Python robot's.
    let consts = |d: &Def| -> Vec<(String, u8)> {
        d.constants
            .iter()
            .map(|(t, n, v)| {
                assert_eq!(t, "uint8", "{n}");
                (n.clone(), v.parse().unwrap())
            })
            .collect()
    };
    assert_eq!(
        consts(&parts[1]),
        [
            ("FIRE".to_string(), ExecPlaceResult::FIRE),
            ("DECIDE".to_string(), ExecPlaceResult::DECIDE),
            ("FAILED".to_string(), ExecPlaceResult::FAILED),
            ("CANCELLED".to_string(), ExecPlaceResult::CANCELLED),
        ]
    );
    assert_eq!(
        consts(&msg("RunState")),
        [
            ("RUNNING".to_string(), RunState::RUNNING),
            ("OVER".to_string(), RunState::OVER),
        ]
    );
    let robot = "ros2/examples/python_robot.py";
    let py = python_constants(robot);
    for (n, v) in consts(&parts[1]) {
        assert_eq!(py[&n], v.to_string(), "{robot}: {n}");
    }
    assert_eq!(
        py["RUN_OVER"],
        RunState::OVER.to_string(),
        "{robot}: RUN_OVER"
    );

    // The Python robot's and the listener's types, by their DDS names.
    let structs = python_structs(robot);
    for (class, dds, rust) in [
        (
            "Goal",
            "gspn_msgs::action::dds_::ExecPlace_Goal_",
            rust_fields(&goal),
        ),
        (
            "Result",
            "gspn_msgs::action::dds_::ExecPlace_Result_",
            rust_fields(&result),
        ),
        (
            "Feedback",
            "gspn_msgs::action::dds_::ExecPlace_Feedback_",
            rust_fields(&feedback),
        ),
        (
            "Heartbeat",
            &msgs::heartbeat_type().dds_msg_type(),
            rust_fields(&heartbeat),
        ),
        (
            "RunState",
            &msgs::run_state_type().dds_msg_type(),
            rust_fields(&run),
        ),
    ] {
        assert_eq!(
            python_fields(&structs, class, dds),
            rust,
            "{robot}: {class}"
        );
    }
    let listener = python_structs("tests/ros2/firings_listener.py");
    assert_eq!(
        python_fields(&listener, "Firing", &msgs::firing_type().dds_msg_type()),
        rust_fields(&firing),
        "firings_listener.py: Firing"
    );
}

#[test]
fn the_package_says_its_version_and_builds_every_file() {
    let xml = read("ros2/gspn_msgs/package.xml");
    assert!(
        xml.contains(&format!("<version>{}</version>", msgs::INTERFACES_VERSION)),
        "package.xml version is not {}",
        msgs::INTERFACES_VERSION
    );
    let cmake = read("ros2/gspn_msgs/CMakeLists.txt");
    let mut files: Vec<String> = std::fs::read_dir(repo("ros2/gspn_msgs/msg"))
        .unwrap()
        .map(|e| format!("msg/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    files.push("action/ExecPlace.action".into());
    for f in &files {
        assert!(
            cmake.contains(&format!("\"{f}\"")),
            "CMakeLists.txt lacks {f}"
        );
    }
    // Every package a definition uses is a dependency of the package.
    for pkg in [
        "std_msgs",
        "geometry_msgs",
        "diagnostic_msgs",
        "builtin_interfaces",
    ] {
        assert!(xml.contains(&format!("<depend>{pkg}</depend>")), "{pkg}");
        assert!(
            cmake.contains(&format!("find_package({pkg} REQUIRED)")),
            "{pkg}"
        );
    }
    // The definitions compiled into the binary (for MCAP schemas) are these files.
    assert_eq!(
        schema::definition("gspn_msgs/msg/Firing"),
        Some(read("ros2/gspn_msgs/msg/Firing.msg").as_str())
    );
}
