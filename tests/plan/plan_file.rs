//! Plan files: every plan in plans/ loads; mistakes are refused with the plan's line and
//! column; the committed JSON Schema matches the reader's types.
//!
//! Regenerate the schema after changing the plan types:
//! `GSPN_UPDATE_SCHEMA=1 cargo test --all-features --test plan`.

use std::path::{Path, PathBuf};

use gspn::io::{LoadError, LoadErrorKind, ReadOptions};
use gspn::plan::{json_schema, read_plan};
use gspn::policy::Pattern;
use gspn::runtime::{FailurePolicy, Role};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A temporary directory holding `plan.toml` (with `text`) and the quickstart's net.
fn with_plan(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("plans/nets/two_robot_patrol.xml"),
        dir.path().join("patrol.xml"),
    )
    .unwrap();
    let path = dir.path().join("plan.toml");
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

fn load(text: &str) -> Result<gspn::plan::Plan, LoadError> {
    let (_dir, path) = with_plan(text);
    read_plan(&path, &ReadOptions::default())
}

fn err_at(text: &str) -> (u32, u32, LoadErrorKind) {
    let e = load(text).unwrap_err();
    let s = e.span.unwrap_or_else(|| panic!("no span: {e}"));
    (s.line, s.column, e.kind)
}

#[test]
fn the_json_schema_in_docs_is_up_to_date() {
    let path = repo("docs/plan.schema.json");
    let schema = json_schema();
    if std::env::var_os("GSPN_UPDATE_SCHEMA").is_some() {
        std::fs::write(&path, &schema).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == schema,
        "docs/plan.schema.json is stale: run `GSPN_UPDATE_SCHEMA=1 cargo test --all-features --test plan`"
    );
    let v: serde_json::Value = serde_json::from_str(&schema).unwrap();
    assert_eq!(v["title"], "gspn plan");
    assert_eq!(v["required"], serde_json::json!(["net"]));
    for key in [
        "net",
        "page",
        "params",
        "seed",
        "time_scale",
        "places",
        "policy",
        "stop",
    ] {
        assert!(v["properties"].get(key).is_some(), "schema lacks `{key}`");
    }
}

#[test]
fn every_plan_in_plans_loads() {
    let mut n = 0;
    for entry in std::fs::read_dir(repo("plans")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let plan = read_plan(&path, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            plan.seed.is_some(),
            "{}: plans/ plans set a seed",
            path.display()
        );
        n += 1;
    }
    assert!(n >= 8, "{n} plans");
}

#[test]
fn the_quickstart_plan_is_what_the_readme_promises() {
    let plan = read_plan(&repo("plans/quickstart.toml"), &ReadOptions::default()).unwrap();
    let net = &plan.net;
    assert_eq!((net.place_count(), net.transition_count()), (5, 6));
    assert_eq!(net.initial_tokens(), 3);
    assert_eq!(plan.net_path, repo("plans/nets/two_robot_patrol.xml"));
    assert_eq!(plan.seed, Some(42));
    assert_eq!(plan.stop.max_firings, Some(500));
    let charger = net.place_by_name("Charger").unwrap();
    assert_eq!(plan.role(charger), Some(&Role::Resource));
    let rules = plan.policy.rules();
    assert_eq!(rules.len(), 3);
    assert!(matches!(rules[0].pattern, Pattern::Exact(_)));
    // After T_A_done (robot 1 deciding, robot 2 on B, charger free): the exact rule
    // applies, before the partial rule `Decide = 1, Patrol_A = 0` that also matches.
    let mut m = vec![0; net.place_count()];
    for name in ["Patrol_B", "Decide", "Charger"] {
        m[net.place_by_name(name).unwrap().index()] = 1;
    }
    assert_eq!(plan.policy.rule_for(&m, &net.firable(&m)).unwrap().0, 0);
    let firable = net.firable(&m);
    let d = plan.policy.distribution(&m, &firable).unwrap();
    let p_charge = d
        .iter()
        .find(|(t, _)| net.transition(*t).name == "t_charge")
        .unwrap()
        .1;
    assert!((p_charge - 0.3).abs() < 1e-9);
}

#[test]
fn plan_options_reach_the_net_reader() {
    // `page` and `params` from the plan; `--page`/`--param` override them.
    let plan = read_plan(&repo("plans/cyc3.toml"), &ReadOptions::default()).unwrap();
    assert_eq!(plan.page.as_deref(), Some("cyc3"));
    assert_eq!(plan.net.initial_tokens(), 2);
    let e = read_plan(
        &repo("plans/cyc3.toml"),
        &ReadOptions {
            page: Some("nope".into()),
            params: vec![],
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("nope"), "{e}");
    let n2 = read_plan(&repo("plans/fms.toml"), &ReadOptions::default()).unwrap();
    let n4 = read_plan(
        &repo("plans/fms.toml"),
        &ReadOptions {
            page: None,
            params: vec![("N".into(), "4".into())],
        },
    )
    .unwrap();
    assert!(n4.net.initial_tokens() > n2.net.initial_tokens());
}

/// Regression (issue 32, item 9): `net = "/etc/passwd"` was refused as the net file's
/// mistake, without a line; a file that is no net at all is the plan's `net = …` line.
#[test]
fn a_net_of_no_known_kind_is_refused_at_the_plans_net_line() {
    let (dir, _) = with_plan("net = \"patrol.xml\"\n");
    let path = dir.path().join("other.toml");
    std::fs::write(dir.path().join("empty.xml"), "\n").unwrap();
    for (net, why) in [
        ("/etc/passwd", "unknown format ``"),
        ("empty.xml", "empty"),
        ("plan.toml", "a plan file is not a net file"),
    ] {
        std::fs::write(&path, format!("seed = 1\nnet = \"{net}\"\n")).unwrap();
        let e = read_plan(&path, &ReadOptions::default()).unwrap_err();
        assert_eq!(e.path, path, "{e}");
        assert_eq!(e.span.map(|s| (s.line, s.column)), Some((2, 7)), "{e}");
        let text = e.to_string();
        assert!(text.contains(&format!("net file `{net}`")), "{text}");
        assert!(text.contains(why), "{text}");
    }
}

#[test]
fn the_net_path_is_relative_to_the_plan() {
    let (dir, _) = with_plan("net = \"patrol.xml\"\n");
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let path = dir.path().join("sub/plan.toml");
    std::fs::write(&path, "net = \"../patrol.xml\"\n").unwrap();
    let plan = read_plan(&path, &ReadOptions::default()).unwrap();
    assert_eq!(plan.net.place_count(), 5);
    std::fs::write(&path, "seed = 1\nnet = \"patrol.xml\"\n").unwrap();
    let e = read_plan(&path, &ReadOptions::default()).unwrap_err();
    assert_eq!(e.span.map(|s| (s.line, s.column)), Some((2, 7)));
    assert!(e.to_string().contains("not found"), "{e}");
}

#[test]
fn an_unknown_place_in_a_role_is_refused_at_its_name() {
    let (l, c, k) = err_at("net = \"patrol.xml\"\n\n[places.Patrol_C]\naction = \"patrol\"\n");
    assert_eq!((l, c), (3, 9));
    assert_eq!(
        k,
        LoadErrorKind::UnknownNode {
            what: "place",
            name: "Patrol_C".into()
        }
    );
    let (l, c, k) = err_at(
        "net = \"patrol.xml\"\n[places.Patrol_A]\naction = \"patrol\"\non_failure = \"fire t_go_Z\"\n",
    );
    assert_eq!((l, c), (4, 14));
    assert_eq!(
        k,
        LoadErrorKind::UnknownNode {
            what: "transition",
            name: "t_go_Z".into()
        }
    );
}

#[test]
fn an_unknown_place_or_transition_in_a_rule_is_refused_at_its_name() {
    let (l, c, k) = err_at(
        "net = \"patrol.xml\"\n[[policy]]\nmarking = { Decide = 1, Dock = 0 }\npartial = true\nchoose = { t_go_A = 1.0 }\n",
    );
    assert_eq!((l, c), (3, 25));
    assert_eq!(
        k,
        LoadErrorKind::UnknownNode {
            what: "place",
            name: "Dock".into()
        }
    );
    let (l, c, k) = err_at(
        "net = \"patrol.xml\"\n[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { t_go_A = 0.5, t_go_C = 0.5 }\n",
    );
    assert_eq!((l, c), (5, 26));
    assert_eq!(
        k,
        LoadErrorKind::UnknownNode {
            what: "transition",
            name: "t_go_C".into()
        }
    );
}

#[test]
fn bad_probabilities_are_refused() {
    let (l, c, k) = err_at(
        "net = \"patrol.xml\"\n[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { t_go_A = -0.5, t_go_B = 1.5 }\n",
    );
    assert_eq!((l, c), (5, 21));
    assert!(k.to_string().contains("must be in [0, 1]"), "{k}");
    let (l, _, k) = err_at(
        "net = \"patrol.xml\"\n\n[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { t_go_A = 0.5, t_go_B = 0.4 }\n",
    );
    assert_eq!(l, 3);
    assert!(k.to_string().contains("sum to 0.9"), "{k}");
    let (l, c, k) = err_at(
        "net = \"patrol.xml\"\n[[policy]]\nmarking = { Decide = 1 }\nchoose = { T_A_done = 1.0 }\n",
    );
    assert_eq!((l, c), (4, 12));
    assert!(k.to_string().contains("exponential"), "{k}");
}

#[test]
fn bad_predicates_are_refused_inside_the_string() {
    let (l, c, k) = err_at("net = \"patrol.xml\"\n[stop]\nwhen = \"Patrol_A == 0 && Dock > 1\"\n");
    assert_eq!((l, c), (3, 26));
    assert_eq!(
        k,
        LoadErrorKind::UnknownNode {
            what: "place",
            name: "Dock".into()
        }
    );
    let (l, c, k) = err_at("net = \"patrol.xml\"\n[stop]\nwhen = \"Patrol_A >< 0\"\n");
    assert_eq!(l, 3);
    assert!(c > 9, "column {c}");
    assert!(k.to_string().starts_with("stop.when:"), "{k}");
}

#[test]
fn roles_timeouts_and_failure_policies_resolve() {
    let plan = load(
        "net = \"patrol.xml\"\n[places.Patrol_A]\naction = \"patrol\"\ntimeout = 12.5\non_failure = \"fire T_A_done\"\n\
         [places.Patrol_B]\naction = \"patrol\"\non_failure = \"retry 3\"\n[places.Charger]\nrole = \"resource\"\n\
         [stop]\nwhen = \"Charging == 1\"\ntime_limit = 50.0\n",
    )
    .unwrap();
    let net = &plan.net;
    let a = net.place_by_name("Patrol_A").unwrap();
    let t = net.transition_by_name("T_A_done").unwrap();
    assert_eq!(
        plan.role(a),
        Some(&Role::Action {
            name: "patrol".into(),
            timeout: Some(12.5),
            on_failure: FailurePolicy::Fire(t),
            robot: None,
        })
    );
    let b = net.place_by_name("Patrol_B").unwrap();
    assert!(matches!(
        plan.role(b),
        Some(Role::Action {
            on_failure: FailurePolicy::Retry(3),
            ..
        })
    ));
    let when = plan.stop.when.as_ref().unwrap();
    let mut m = vec![0; net.place_count()];
    assert!(!when.eval(&m));
    m[net.place_by_name("Charging").unwrap().index()] = 1;
    assert!(when.eval(&m));
    assert_eq!(plan.stop.time_limit, Some(50.0));
}

/// A `[map]` key written below a `[map.locations.NAME]` header belongs to that location in
/// TOML: refused at its line (by `run`, `simulate` and `analyze` alike: they read plans
/// through one reader), saying where it belongs.
#[test]
fn a_map_key_under_a_location_header_is_refused_saying_where_it_belongs() {
    let text = "net = \"patrol.xml\"\n[map]\npatrol = [\"L1\"]\n\n[map.locations.L1]\nx = 0.0\ny = 0.0\n\nedges = [[\"L1\", \"L1\"]]\n";
    let (l, c, k) = err_at(text);
    assert_eq!((l, c), (9, 1));
    let LoadErrorKind::Invalid(message) = k else {
        panic!("{k:?}")
    };
    assert!(message.starts_with("unknown field `edges`"), "{message}");
    assert!(
        message.contains("`edges` belongs to [map]")
            && message.contains("move it above the first [map.locations.…] table"),
        "{message}"
    );
    // Above the location tables it is read.
    let fixed = "net = \"patrol.xml\"\n[map]\npatrol = [\"L1\"]\nedges = [[\"L1\", \"L1\"]]\n\n[map.locations.L1]\nx = 0.0\ny = 0.0\n";
    let (_dir, path) = with_plan(fixed);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(gspn::plan::PlanFile::parse(&path, &text).is_ok());
}

/// Issue 30, snag 7: policy rules were numbered from 0 in these messages and from 1 in
/// `check`'s; both count from 1 in file order now.
#[test]
fn policy_errors_number_rules_from_1_like_check() {
    let (l, _, k) = err_at(
        "net = \"patrol.xml\"\n[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { t_go_A = 1.0 }\n\n[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { t_go_A = 0.5, t_go_B = 0.4 }\n",
    );
    assert_eq!(l, 7);
    assert!(
        k.to_string()
            .contains("rule 2: the probabilities sum to 0.9"),
        "{k}"
    );
}

/// Every key of the plan file's schema (the reader's own type, with unknown keys refused),
/// as `section.key` paths: `places.action.command`, `map.robot.radius`, …
fn schema_keys() -> Vec<String> {
    fn walk(
        node: &serde_json::Value,
        defs: &serde_json::Value,
        path: &str,
        out: &mut Vec<String>,
        depth: usize,
    ) {
        if depth > 8 {
            return;
        }
        if let Some(r) = node.get("$ref").and_then(|r| r.as_str()) {
            let name = r.rsplit('/').next().unwrap();
            walk(&defs[name], defs, path, out, depth + 1);
        }
        if let Some(props) = node.get("properties").and_then(|p| p.as_object()) {
            for (k, v) in props {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                out.push(p.clone());
                walk(v, defs, &p, out, depth + 1);
            }
        }
        for key in ["items", "additionalProperties"] {
            if let Some(v) = node.get(key) {
                walk(v, defs, path, out, depth + 1);
            }
        }
        for key in ["anyOf", "oneOf", "allOf"] {
            for v in node
                .get(key)
                .and_then(|v| v.as_array())
                .into_iter()
                .flatten()
            {
                walk(v, defs, path, out, depth + 1);
            }
        }
    }
    let schema: serde_json::Value = serde_json::from_str(&json_schema()).unwrap();
    let mut out = Vec::new();
    walk(&schema, &schema["$defs"], "", &mut out, 0);
    out.sort();
    out.dedup();
    out
}

/// Issue 30, snag 5: `[rewards.NAME]` (`marked`, `per_token`, `transitions`),
/// `controllable` and `wait` were missing from docs/plans.md's key table. Every key the
/// reader accepts is named in that table (the `[map]` keys in its own section's example).
#[test]
fn every_key_the_plan_reader_accepts_is_in_the_docs() {
    let docs = std::fs::read_to_string(repo("docs/plans.md")).unwrap();
    let keys_section = &docs[docs.find("\n## Keys").unwrap()..];
    let table: String = keys_section[..keys_section[1..].find("\n#").unwrap()]
        .lines()
        .filter(|l| l.starts_with('|'))
        .collect::<Vec<_>>()
        .join("\n");
    let map_section = &docs[docs.find("\n## Simulated robots").unwrap()..];
    let map_section = &map_section[..map_section[1..].find("\n## ").unwrap()];
    let keys = schema_keys();
    assert!(keys.len() > 60, "{keys:?}");
    let mut missing = Vec::new();
    for path in &keys {
        let key = path.rsplit('.').next().unwrap();
        let documented = if path.starts_with("map.") {
            map_section.contains(&format!("{key} ="))
                || map_section.contains(&format!("`{key}`"))
                || map_section.contains(&format!(".{key}."))
        } else {
            table.contains(&format!("`{key}`"))
                || table.contains(&format!("`[{key}]`"))
                || table.contains(&format!("`[{key}.NAME]`"))
                || table.contains(&format!("`[[{key}]]`"))
        };
        if !documented {
            missing.push(path.clone());
        }
    }
    assert!(
        missing.is_empty(),
        "keys missing from docs/plans.md: {missing:?}"
    );
    for key in [
        "rewards",
        "rewards.marked",
        "rewards.per_token",
        "rewards.transitions",
        "controllable",
        "wait",
    ] {
        assert!(keys.contains(&key.to_string()), "{key} in {keys:?}");
    }
}
