//! Names as ROS does them: `--ros-args` on `run` and `robot` (`-r __ns:=/fleet_a`,
//! `-r __node:=name`, `-p key:=value`) and the names of topics and actions under the
//! namespace, so two plans share a domain without a crossed message.
//!
//! | name | without a namespace | with `__ns:=/fleet_a` |
//! |---|---|---|
//! | nodes | `/gspn/supervisor`, `/gspn/robot_r1` | `/fleet_a/gspn/supervisor`, … |
//! | topics | `/gspn/firings`, `/gspn/marking`, … | `/fleet_a/gspn/firings`, … |
//! | ExecPlace | `/r1/exec_place` | `/fleet_a/r1/exec_place` |
//!
//! Every name is relative to the node's namespace (`<ns>/gspn`): [`topic`] and [`action`]
//! resolve them, so a node made with [`super::DdsConfig::node`] carries its namespace to
//! every entity it creates.

use ros2_client::{Name, Node};

use super::Ros2Error;

/// The namespace of gspn's nodes under the run's namespace `ns` (`""` = the root).
pub fn node_namespace(ns: &str) -> String {
    format!("{ns}/gspn")
}

/// The run's namespace of `node` (`""` for the root): its namespace without `/gspn`.
fn run_namespace(node: &Node) -> &str {
    let ns = node.namespace();
    ns.strip_suffix("/gspn").unwrap_or(ns)
}

/// The topic `default` (one of `/gspn/...`, as [`super::msgs`] names them) under `node`'s
/// namespace; a name outside `/gspn` (such as `/rosout`) stays as it is.
pub fn topic(node: &Node, default: &str) -> Result<Name, Ros2Error> {
    let full = match default.strip_prefix("/gspn/") {
        Some(rel) => format!("{}/{rel}", node.namespace()),
        None => default.to_string(),
    };
    Name::parse(&full).map_err(Ros2Error::dds)
}

/// The ExecPlace action `server` of `robot` under `node`'s run namespace.
pub fn action(node: &Node, robot: &str, server: &str) -> Result<Name, Ros2Error> {
    Name::new(&format!("{}/{robot}", run_namespace(node)), server).map_err(Ros2Error::dds)
}

/// What `--ros-args` says.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RosArgs {
    /// `-r __ns:=/fleet_a`: the run's namespace (`""` = the root).
    pub namespace: Option<String>,
    /// `-r __node:=name`: the node's name.
    pub node: Option<String>,
    /// `-p key:=value`, in order.
    pub params: Vec<(String, String)>,
}

/// Whether `s` is a ROS 2 name token: letters, digits, underscores, not starting with a
/// digit.
fn is_token(s: &str) -> bool {
    s.chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Why `--ros-args` was refused, naming the offending argument.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RosArgsError {
    /// A flag other than `-r`/`--remap`, `-p`/`--param`.
    #[error(
        "--ros-args: `{0}` is not supported (use -r __ns:=/NS, -r __node:=NAME, -p KEY:=VALUE)"
    )]
    Unsupported(String),
    /// `-r` or `-p` last, without its rule.
    #[error("--ros-args: {0} needs FROM:=TO")]
    MissingRule(String),
    /// A rule without `:=`.
    #[error("--ros-args: {flag} `{rule}`: expected FROM:=TO")]
    NotARule {
        /// The flag.
        flag: String,
        /// The rule as written.
        rule: String,
    },
    /// `-p NAME:=…` with a name that is no ROS 2 token.
    #[error("--ros-args: -p `{rule}`: `{name}` is not a parameter name")]
    ParameterName {
        /// The rule as written.
        rule: String,
        /// The name.
        name: String,
    },
    /// `-r __ns:=…` with a namespace that is not absolute or not made of tokens.
    #[error(
        "--ros-args: -r `{0}`: a namespace is absolute, `/` and tokens (letters, digits, underscores)"
    )]
    Namespace(String),
    /// `-r __node:=…` with a name that is no ROS 2 token.
    #[error("--ros-args: -r `{rule}`: `{name}` is not a node name")]
    NodeName {
        /// The rule as written.
        rule: String,
        /// The name.
        name: String,
    },
    /// A remap of anything but `__ns` and `__node`.
    #[error(
        "--ros-args: -r `{0}`: only __ns and __node can be remapped (gspn's topics follow the namespace)"
    )]
    Remap(String),
    /// A `-p` parameter that is unknown or whose value does not fit it.
    #[error("--ros-args: -p `{key}:={value}`: {reason}")]
    Parameter {
        /// The parameter's name.
        key: String,
        /// Its value as written.
        value: String,
        /// What was expected.
        reason: String,
    },
}

impl RosArgs {
    /// Parses the arguments after `--ros-args` (up to a `--`): `-r`/`--remap FROM:=TO` with
    /// FROM `__ns` or `__node`, `-p`/`--param NAME:=VALUE`. Anything else is refused, naming
    /// it.
    pub fn parse(args: &[String]) -> Result<RosArgs, RosArgsError> {
        let mut out = RosArgs::default();
        let mut it = args.iter();
        while let Some(flag) = it.next() {
            if flag == "--" {
                break;
            }
            let kind = match flag.as_str() {
                "-r" | "--remap" => "remap",
                "-p" | "--param" => "param",
                other => return Err(RosArgsError::Unsupported(other.to_string())),
            };
            let Some(rule) = it.next() else {
                return Err(RosArgsError::MissingRule(flag.clone()));
            };
            let Some((from, to)) = rule.split_once(":=") else {
                return Err(RosArgsError::NotARule {
                    flag: flag.clone(),
                    rule: rule.clone(),
                });
            };
            if kind == "param" {
                if !is_token(from) {
                    return Err(RosArgsError::ParameterName {
                        rule: rule.clone(),
                        name: from.to_string(),
                    });
                }
                out.params.push((from.to_string(), to.to_string()));
                continue;
            }
            match from {
                "__ns" => {
                    let ns = to.trim_end_matches('/');
                    let ok =
                        to.starts_with('/') && (ns.is_empty() || ns[1..].split('/').all(is_token));
                    if !ok {
                        return Err(RosArgsError::Namespace(rule.clone()));
                    }
                    out.namespace = Some(ns.to_string());
                }
                "__node" | "__name" => {
                    if !is_token(to) {
                        return Err(RosArgsError::NodeName {
                            rule: rule.clone(),
                            name: to.to_string(),
                        });
                    }
                    out.node = Some(to.to_string());
                }
                _ => return Err(RosArgsError::Remap(rule.clone())),
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn ros_args_give_a_namespace_a_node_name_and_parameters() {
        let a = RosArgs::parse(&args(
            "-r __ns:=/fleet_a --remap __node:=r1 -p lost_after:=0.5 --param rosout:=true",
        ))
        .unwrap();
        assert_eq!(
            a,
            RosArgs {
                namespace: Some("/fleet_a".into()),
                node: Some("r1".into()),
                params: vec![
                    ("lost_after".into(), "0.5".into()),
                    ("rosout".into(), "true".into())
                ],
            }
        );
        assert_eq!(
            RosArgs::parse(&args("-r __ns:=/"))
                .unwrap()
                .namespace
                .as_deref(),
            Some("")
        );
        assert_eq!(
            RosArgs::parse(&args("-r __ns:=/a/b_2/"))
                .unwrap()
                .namespace
                .as_deref(),
            Some("/a/b_2")
        );
        assert_eq!(node_namespace("/fleet_a"), "/fleet_a/gspn");
        assert_eq!(node_namespace(""), "/gspn");
    }

    #[test]
    fn what_ros_args_cannot_mean_is_refused_naming_it() {
        let e = |s: &str| RosArgs::parse(&args(s)).unwrap_err().to_string();
        assert_eq!(
            e("-r __ns:=fleet_a"),
            "--ros-args: -r `__ns:=fleet_a`: a namespace is absolute, `/` and tokens (letters, digits, underscores)"
        );
        assert_eq!(
            e("-r chatter:=talk"),
            "--ros-args: -r `chatter:=talk`: only __ns and __node can be remapped (gspn's topics follow the namespace)"
        );
        assert_eq!(
            e("--enclave /x"),
            "--ros-args: `--enclave` is not supported (use -r __ns:=/NS, -r __node:=NAME, -p KEY:=VALUE)"
        );
        assert_eq!(e("-p"), "--ros-args: -p needs FROM:=TO");
        assert_eq!(e("-p x=1"), "--ros-args: -p `x=1`: expected FROM:=TO");
        assert_eq!(
            e("-r __node:=9r"),
            "--ros-args: -r `__node:=9r`: `9r` is not a node name"
        );
    }
}
