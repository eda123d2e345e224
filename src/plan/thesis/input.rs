//! Reading a thesis input: the JSON object, then the Python literal in each value, with
//! every name's line and column in the JSON file.

use std::path::Path;

use super::json::{self, Field, JsonStr, JsonValue};
use super::pylit::{self, Py, PyKind};
use super::{ActionEntry, KeyItem, Named, PolicyEntry, ThesisInput};
use crate::io::{LineIndex, LoadError, LoadErrorKind, Span};

/// Reads one input file; positions are computed against `text`.
pub(super) struct Reader<'a> {
    pub(super) path: &'a Path,
    pub(super) text: &'a str,
    /// Line starts of `text`, found on the first position asked for.
    pub(super) lines: std::cell::OnceCell<LineIndex>,
}

impl Reader<'_> {
    fn span(&self, offset: usize) -> Span {
        let bytes = self.text.as_bytes();
        self.lines
            .get_or_init(|| LineIndex::new(bytes))
            .locate(bytes, offset)
    }

    fn err(&self, offset: usize, kind: LoadErrorKind) -> LoadError {
        LoadError::at(self.path, self.span(offset), kind)
    }

    fn invalid(&self, offset: usize, msg: String) -> LoadError {
        self.err(offset, LoadErrorKind::Invalid(msg))
    }

    pub(super) fn input(&self) -> Result<ThesisInput, LoadError> {
        let fields = json::parse_object(self.text)
            .map_err(|e| self.invalid(e.offset, format!("JSON: {}", e.message)))?;
        let mut warnings = Vec::new();
        let mut input = ThesisInput {
            path: self.path.to_path_buf(),
            net: Named {
                name: String::new(),
                span: Span { line: 1, column: 1 },
            },
            places: Vec::new(),
            policy: Vec::new(),
            actions: Vec::new(),
            resources: Vec::new(),
            full_synchronization: None,
            project_path: None,
            warnings: Vec::new(),
        };
        let (mut has_net, mut has_places, mut has_policy) = (false, false, false);
        for Field { key, value } in &fields {
            let s = match value {
                JsonValue::Str(s) => s,
                JsonValue::Other(at) => {
                    return Err(self.invalid(
                        *at,
                        format!(
                            "`{}` must be a string (a Python literal in quotes)",
                            key.text
                        ),
                    ));
                }
            };
            match key.text.as_str() {
                "gspn" => {
                    input.net = Named {
                        name: s.text.clone(),
                        span: self.span(s.start),
                    };
                    has_net = true;
                }
                "places_tuple" => {
                    input.places = self.names(s, &self.literal(s)?, "places_tuple")?;
                    has_places = true;
                }
                "policy_dictionary" => {
                    input.policy = self.policy(s, &mut warnings)?;
                    has_policy = true;
                }
                "place_to_function_mapping" => self.functions(s, &mut input.actions)?,
                "place_to_client_mapping" => self.clients(s, &mut input.actions)?,
                "resources_list" => {
                    input.resources = self.names(s, &self.literal(s)?, "resources_list")?;
                }
                "full_synchronization" => match s.text.trim() {
                    "True" | "true" => input.full_synchronization = Some(true),
                    "False" | "false" => input.full_synchronization = Some(false),
                    other => {
                        return Err(self.invalid(
                            s.start,
                            format!("full_synchronization is `{other}`: expected True or False"),
                        ));
                    }
                },
                "project_path" => {
                    input.project_path = Some(Named {
                        name: s.text.clone(),
                        span: self.span(s.start),
                    });
                }
                other => warnings.push(format!("key `{other}` ignored")),
            }
        }
        for (has, what) in [
            (has_net, "`gspn`"),
            (has_places, "`places_tuple`"),
            (has_policy, "`policy_dictionary`"),
        ] {
            if !has {
                // Blamed on the object's closing `}`, where the key is missing from (the
                // object parsed, so it is the last character but whitespace).
                let close = self.text.trim_end().len().saturating_sub(1);
                return Err(self.err(
                    close,
                    LoadErrorKind::Missing {
                        what: what.into(),
                        name: None,
                    },
                ));
            }
        }
        input.warnings = warnings;
        Ok(input)
    }

    /// Parses the Python literal inside JSON string `s`.
    fn literal(&self, s: &JsonStr) -> Result<Py, LoadError> {
        pylit::parse(&s.text).map_err(|e| {
            self.invalid(
                s.file_offset(e.offset),
                format!("Python literal: {}", e.message),
            )
        })
    }

    fn named(&self, s: &JsonStr, v: &Py, what: &str) -> Result<Named, LoadError> {
        match &v.kind {
            PyKind::Str(name) => Ok(Named {
                name: name.clone(),
                span: self.span(s.file_offset(v.at)),
            }),
            other => Err(self.invalid(
                s.file_offset(v.at),
                format!(
                    "{what}: expected a name in quotes, found {}",
                    other.describe()
                ),
            )),
        }
    }

    fn names(&self, s: &JsonStr, v: &Py, what: &str) -> Result<Vec<Named>, LoadError> {
        match &v.kind {
            PyKind::Tuple(items) | PyKind::List(items) => {
                items.iter().map(|i| self.named(s, i, what)).collect()
            }
            other => Err(self.invalid(
                s.file_offset(v.at),
                format!(
                    "{what}: expected a tuple or list of names, found {}",
                    other.describe()
                ),
            )),
        }
    }

    fn dict<'p>(&self, s: &JsonStr, v: &'p Py, what: &str) -> Result<&'p [(Py, Py)], LoadError> {
        match &v.kind {
            PyKind::Dict(items) => Ok(items),
            other => Err(self.invalid(
                s.file_offset(v.at),
                format!("{what}: expected a dict, found {}", other.describe()),
            )),
        }
    }

    fn functions(&self, s: &JsonStr, out: &mut Vec<ActionEntry>) -> Result<(), LoadError> {
        let v = self.literal(s)?;
        for (k, f) in self.dict(s, &v, "place_to_function_mapping")? {
            let place = self.named(s, k, "place_to_function_mapping")?;
            let action = self.named(s, f, "place_to_function_mapping")?.name;
            out.push(ActionEntry {
                place,
                action,
                action_type: None,
            });
        }
        Ok(())
    }

    fn clients(&self, s: &JsonStr, out: &mut Vec<ActionEntry>) -> Result<(), LoadError> {
        let v = self.literal(s)?;
        for (k, c) in self.dict(s, &v, "place_to_client_mapping")? {
            let place = self.named(s, k, "place_to_client_mapping")?;
            let parts = self.names(s, c, "place_to_client_mapping")?;
            let [action_type, server] = parts.as_slice() else {
                return Err(self.invalid(
                    s.file_offset(c.at),
                    format!(
                        "place_to_client_mapping of `{}`: expected ['ActionType', 'server_name'], found {} items",
                        place.name,
                        parts.len()
                    ),
                ));
            };
            out.push(ActionEntry {
                place,
                action: server.name.clone(),
                action_type: Some(action_type.name.clone()),
            });
        }
        Ok(())
    }

    fn policy(
        &self,
        s: &JsonStr,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<PolicyEntry>, LoadError> {
        let v = self.literal(s)?;
        let mut entries = Vec::new();
        for (k, choice) in self.dict(s, &v, "policy_dictionary")? {
            let items = match &k.kind {
                PyKind::Tuple(items) | PyKind::List(items) => items.as_slice(),
                // `('-')` is '-' in Python: a one-place key.
                _ => std::slice::from_ref(k),
            };
            let mut key = Vec::with_capacity(items.len());
            for item in items {
                key.push(self.key_item(s, item, warnings)?);
            }
            let mut choose = Vec::new();
            for (t, p) in self.dict(s, choice, "policy_dictionary value")? {
                let t = self.named(s, t, "policy_dictionary transition")?;
                let prob = match p.kind {
                    PyKind::Int(i) => i as f64,
                    PyKind::Float(f) => f,
                    ref other => {
                        return Err(self.err(
                            s.file_offset(p.at),
                            LoadErrorKind::NotANumber {
                                what: "probability",
                                name: t.name.clone(),
                                value: other.describe().to_string(),
                            },
                        ));
                    }
                };
                choose.push((t, prob));
            }
            entries.push(PolicyEntry {
                span: self.span(s.file_offset(k.at)),
                key,
                choose,
            });
        }
        Ok(entries)
    }

    fn key_item(
        &self,
        s: &JsonStr,
        v: &Py,
        warnings: &mut Vec<String>,
    ) -> Result<KeyItem, LoadError> {
        let at = s.file_offset(v.at);
        match &v.kind {
            PyKind::Int(i) => u32::try_from(*i).map(KeyItem::Count).map_err(|_| {
                self.err(
                    at,
                    LoadErrorKind::OutOfRange {
                        what: "token count",
                        name: "policy key".into(),
                        value: i.to_string(),
                        expected: "must be an integer ≥ 0",
                    },
                )
            }),
            PyKind::Str(t) if t == "-" => Ok(KeyItem::Free),
            PyKind::Str(t) => match t.trim().parse::<u32>() {
                Ok(c) => {
                    warnings.push(format!(
                        "policy key at {}: '{t}' is a string; read as the count {c} (the thesis \
                         code compared it with the integer and never matched)",
                        self.span(at)
                    ));
                    Ok(KeyItem::Count(c))
                }
                Err(_) => Err(self.err(
                    at,
                    LoadErrorKind::NotANumber {
                        what: "token count",
                        name: "policy key".into(),
                        value: t.clone(),
                    },
                )),
            },
            other => Err(self.invalid(
                at,
                format!(
                    "policy key: expected a token count or '-', found {}",
                    other.describe()
                ),
            )),
        }
    }
}
