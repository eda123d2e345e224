//! The ROS 2 part of plan files (feature `ros2` uses it; plans parse it with or without the
//! feature): the `[ros2]` table and the `server` key of `ros2` places (`docs/ros2.md`),
//! resolved into the backend's [`Ros2Settings`].

use std::collections::BTreeMap;
use std::ops::Range;

use schemars::JsonSchema;
use serde::Deserialize;
use toml::Spanned;

use super::file::PlaceFile;
use super::resolve::out_of_range;
use crate::io::{LoadError, LoadErrorKind};
use crate::net::Net;
use crate::ros2::settings::{
    DEFAULT_SERVER, NAV2_SERVER, PlaceArgs, ROS2_ACTION, Ros2Settings, ServiceMapping, Transport,
};

/// The `[ros2]` table: how the ROS 2 backend joins DDS and watches robots.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Ros2File {
    /// The DDS domain id (0–232; default 0).
    #[schemars(with = "Option<u16>", range(max = 232))]
    pub domain_id: Option<Spanned<u16>>,
    /// Local IP addresses DDS may use (default `["127.0.0.1"]`: loopback only).
    #[schemars(with = "Option<Vec<String>>")]
    pub networks: Option<Vec<Spanned<String>>>,
    /// Seconds between a `plan-runner robot`'s heartbeats (default 0.1; 0: none, the
    /// supervisor then sees robots through DDS discovery alone).
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub heartbeat: Option<Spanned<f64>>,
    /// Seconds without a heartbeat after which a robot is lost (default 1.0).
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub lost_after: Option<Spanned<f64>>,
    /// Seconds the supervisor waits for every robot before it gives up (default 30).
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub startup: Option<Spanned<f64>>,
    /// How ExecPlace's services pair responses with requests: `"enhanced"` (default; RPC
    /// over DDS, inline QoS) or `"cyclone"` (a header in the payload, as ROS 2's
    /// rmw_cyclonedds_cpp does; for robots on Cyclone DDS).
    #[schemars(with = "Option<String>")]
    pub service_mapping: Option<Spanned<String>>,
    /// Whether the process's ROS 2 node publishes the ROS 2 layer's warnings and errors on
    /// `/rosout` (rcl_interfaces/msg/Log), as ROS 2 nodes do (default false;
    /// `--ros2-rosout` turns it on too).
    pub rosout: Option<bool>,
    /// How the supervisor and its robots meet: `"dds"` (default) or `"zenoh"` (through a
    /// Zenoh router, rmw_zenoh's layout; feature `zenoh`, `docs/zenoh.md`).
    #[schemars(with = "Option<String>")]
    pub transport: Option<Spanned<String>>,
    /// The Zenoh router to connect to with `transport = "zenoh"` (default
    /// `"tcp/127.0.0.1:7447"`; `--zenoh ENDPOINT` overrides it).
    pub zenoh: Option<String>,
}

/// The `[ros2]` table and the `server`, `target` and `args` keys of the places.
pub(super) fn resolve_ros2(
    net: &Net,
    file: Option<&Ros2File>,
    places: &BTreeMap<Spanned<String>, Spanned<PlaceFile>>,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<Ros2Settings, LoadError> {
    let mut s = Ros2Settings::default();
    if let Some(f) = file {
        ros2_table(f, &mut s, at)?;
    }
    for (name, role) in places {
        place_server(net, name, role.get_ref(), &mut s, at)?;
    }
    s.servers.sort_by_key(|&(p, _)| p);
    s.args.sort_by_key(|&(p, _)| p);
    Ok(s)
}

/// The `[ros2]` table's keys into `s`.
fn ros2_table(
    f: &Ros2File,
    s: &mut Ros2Settings,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<(), LoadError> {
    if let Some(d) = &f.domain_id {
        if *d.get_ref() > 232 {
            return Err(at(
                d.span(),
                out_of_range(
                    "domain_id",
                    "ros2",
                    f64::from(*d.get_ref()),
                    "must be in 0..=232",
                ),
            ));
        }
        s.domain_id = Some(*d.get_ref());
    }
    for n in f.networks.iter().flatten() {
        let ip = n.get_ref().trim().parse().map_err(|_| {
            at(
                n.span(),
                LoadErrorKind::Invalid(format!(
                    "ros2.networks: `{}` is not an IP address",
                    n.get_ref()
                )),
            )
        })?;
        s.networks.push(ip);
    }
    if let Some(m) = &f.service_mapping {
        s.service_mapping = ServiceMapping::parse(m.get_ref()).ok_or_else(|| {
            at(
                m.span(),
                LoadErrorKind::Invalid(format!(
                    "ros2.service_mapping: `{}` is not \"enhanced\" or \"cyclone\"",
                    m.get_ref()
                )),
            )
        })?;
    }
    s.rosout = f.rosout;
    if let Some(t) = &f.transport {
        s.transport = Transport::parse(t.get_ref()).ok_or_else(|| {
            at(
                t.span(),
                LoadErrorKind::Invalid(format!(
                    "ros2.transport: `{}` is not \"dds\" or \"zenoh\"",
                    t.get_ref()
                )),
            )
        })?;
    }
    s.zenoh.clone_from(&f.zenoh);
    for (key, v, slot) in [
        ("heartbeat", &f.heartbeat, &mut s.heartbeat),
        ("lost_after", &f.lost_after, &mut s.lost_after),
        ("startup", &f.startup, &mut s.startup),
    ] {
        if let Some(v) = v {
            let x = *v.get_ref();
            // `heartbeat = 0`: robots send none (the supervisor sees them through
            // discovery).
            let valid = if key == "heartbeat" {
                crate::limits::valid_wait(x)
            } else {
                crate::limits::valid_seconds(x)
            };
            if !valid {
                return Err(at(
                    v.span(),
                    out_of_range(key, "ros2", x, crate::limits::SECONDS_EXPECTED),
                ));
            }
            *slot = Some(x);
        }
    }
    Ok(())
}

/// Place `name`'s `server`, `target` and `args` keys into `s` (`ros2` places only).
fn place_server(
    net: &Net,
    name: &Spanned<String>,
    f: &PlaceFile,
    s: &mut Ros2Settings,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<(), LoadError> {
    let is_ros2 = f.action.as_ref().and_then(|a| a.get_ref().name()) == Some(ROS2_ACTION);
    let server = match &f.server {
        Some(srv) if !is_ros2 => {
            return Err(at(
                srv.span(),
                LoadErrorKind::Invalid(format!(
                    "place `{}`: `server` applies to places with action = \"{ROS2_ACTION}\" only",
                    name.get_ref()
                )),
            ));
        }
        Some(srv) => {
            let v = srv.get_ref();
            let ok = v.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !v.contains("__");
            if !ok {
                return Err(at(
                    srv.span(),
                    LoadErrorKind::Invalid(format!(
                        "place `{}`: server `{v}` is not a ROS 2 name (letters, digits and single underscores, starting with a letter)",
                        name.get_ref()
                    )),
                ));
            }
            v.clone()
        }
        None => DEFAULT_SERVER.to_string(),
    };
    let args = place_args(name.get_ref(), f, is_ros2, at)?;
    if let Some(srv) = &f.server
        && srv.get_ref() == NAV2_SERVER
        && args.target.is_none()
    {
        return Err(at(
            srv.span(),
            LoadErrorKind::Invalid(format!(
                "place `{}`: server \"{NAV2_SERVER}\" sends Nav2 goals: it needs a `target = [x, y]` or `[x, y, yaw]` (frame map)",
                name.get_ref()
            )),
        ));
    }
    if let Some(srv) = &f.server
        && srv.get_ref() == NAV2_SERVER
        && s.transport == Transport::Zenoh
    {
        return Err(at(
            srv.span(),
            LoadErrorKind::Invalid(format!(
                "place `{}`: server \"{NAV2_SERVER}\" sends Nav2 goals over DDS only, and the plan says transport = \"zenoh\"",
                name.get_ref()
            )),
        ));
    }
    if is_ros2 && let Some(p) = net.place_by_name(name.get_ref()) {
        s.servers.push((p, server));
        if args != PlaceArgs::default() {
            s.args.push((p, args));
        }
    }
    Ok(())
}

/// The `target` and `args` keys of place `name`: for `ros2` places only; a target is
/// `[x, y]` or `[x, y, yaw]` of finite numbers.
fn place_args(
    name: &str,
    f: &PlaceFile,
    is_ros2: bool,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<PlaceArgs, LoadError> {
    let only_ros2 = |key: &str, span: Range<usize>| {
        at(
            span,
            LoadErrorKind::Invalid(format!(
                "place `{name}`: `{key}` applies to places with action = \"{ROS2_ACTION}\" only"
            )),
        )
    };
    let mut out = PlaceArgs::default();
    if let Some(t) = &f.target {
        if !is_ros2 {
            return Err(only_ros2("target", t.span()));
        }
        let v = t.get_ref();
        out.target = match v[..] {
            [x, y] if x.is_finite() && y.is_finite() => Some([x, y, 0.0]),
            [x, y, yaw] if v.iter().all(|c| c.is_finite()) => Some([x, y, yaw]),
            _ => {
                return Err(at(
                    t.span(),
                    LoadErrorKind::Invalid(format!(
                        "place `{name}`: target must be [x, y] or [x, y, yaw] (finite numbers)"
                    )),
                ));
            }
        };
    }
    if let Some(a) = &f.args {
        if !is_ros2 {
            return Err(only_ros2("args", a.span()));
        }
        out.args = a
            .get_ref()
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
    }
    Ok(out)
}
