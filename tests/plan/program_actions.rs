//! `action = { command | worker }` and `[workers.NAME]` in a plan file: what they resolve to,
//! and every mistake refused at its line and column; an action name that is not known is a
//! load error naming it, the nearest known name and the list of known actions.

use std::path::{Path, PathBuf};

use gspn::io::{LoadError, ReadOptions};
use gspn::plan::{Plan, ProgramAction, read_plan};
use gspn::runtime::Role;

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

const HEAD: &str = "net = \"patrol.xml\"\n";

fn load(dir: &Path, text: &str) -> Result<Plan, LoadError> {
    std::fs::copy(
        repo("plans/nets/two_robot_patrol.xml"),
        dir.join("patrol.xml"),
    )
    .unwrap();
    let path = dir.join("plan.toml");
    std::fs::write(&path, format!("{HEAD}{text}")).unwrap();
    read_plan(&path, &ReadOptions::default())
}

/// The error of a plan made of `HEAD` + `text`: line, column, message.
fn err_at(text: &str) -> (u32, u32, String) {
    let dir = tempfile::tempdir().unwrap();
    let e = load(dir.path(), text).unwrap_err();
    let s = e.span.unwrap_or_else(|| panic!("no span: {e}"));
    (s.line, s.column, e.kind.to_string())
}

fn action_name(plan: &Plan, place: &str) -> String {
    match plan.role(plan.net.place_by_name(place).unwrap()) {
        Some(Role::Action { name, .. }) => name.clone(),
        r => panic!("{place}: {r:?}"),
    }
}

#[test]
fn commands_and_workers_resolve_to_registered_names_and_share_a_worker() {
    let dir = tempfile::tempdir().unwrap();
    let plan = load(
        dir.path(),
        "[places.Patrol_A]\naction = { command = [\"sh\", \"-c\", \"echo {place}\"], cwd = \"scripts\", env = { K = \"v\" }, timeout = 2.5, kill_grace = 0.5 }\n\
         [places.Patrol_B]\naction = { worker = \"robot\", name = \"patrol\" }\n\
         [places.Decide]\naction = { worker = \"robot\", name = \"choose\" }\n\
         [places.Charging]\naction = { worker = [\"python3\", \"w.py\"], name = \"charge\" }\n\
         [workers.robot]\ncommand = [\"python3\", \"robot_actions.py\"]\nenv = { MODE = \"sim\" }\nkill_grace = 1.0\n",
    )
    .unwrap();
    assert_eq!(
        action_name(&plan, "Patrol_A"),
        "command `sh -c echo {place}`"
    );
    assert_eq!(
        action_name(&plan, "Patrol_B"),
        "worker `robot` action `patrol`"
    );
    assert_eq!(
        action_name(&plan, "Decide"),
        "worker `robot` action `choose`"
    );
    assert_eq!(
        action_name(&plan, "Charging"),
        "worker `python3 w.py` action `charge`"
    );
    assert_eq!(plan.programs.len(), 4);
    assert_eq!(
        plan.programs
            .iter()
            .find(|p| p.worker_action.is_none())
            .unwrap(),
        &ProgramAction {
            name: "command `sh -c echo {place}`".into(),
            argv: vec!["sh".into(), "-c".into(), "echo {place}".into()],
            worker_action: None,
            cwd: Some(dir.path().join("scripts")),
            env: vec![("K".into(), "v".into())],
            timeout: Some(2.5),
            kill_grace: Some(0.5),
        }
    );
    // One program per distinct action; both `robot` actions carry the entry's settings.
    let robot: Vec<&ProgramAction> = plan
        .programs
        .iter()
        .filter(|p| p.name.starts_with("worker `robot`"))
        .collect();
    assert_eq!(robot.len(), 2);
    for p in robot {
        assert_eq!(p.argv, ["python3", "robot_actions.py"]);
        assert_eq!(p.env, [("MODE".to_string(), "sim".to_string())]);
        assert_eq!(p.kill_grace, Some(1.0));
        assert_eq!(p.cwd.as_deref(), Some(dir.path().join(".").as_path()));
    }
    plan.check_actions(&[]).unwrap();
}

#[test]
fn program_mistakes_are_refused_at_the_action() {
    let (l, c, m) = err_at("[places.Patrol_A]\naction = { comand = [\"true\"] }\n");
    assert_eq!((l, c), (3, 12), "{m}");
    assert!(m.contains("unknown field `comand`"), "{m}");

    let (l, c, m) = err_at("[places.Patrol_A]\naction = { worker = [\"python3\", \"w.py\"] }\n");
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(
        m.contains("a `worker` needs the `name` of its action"),
        "{m}"
    );

    let (l, c, m) = err_at(
        "[places.Patrol_A]\naction = { command = [\"true\"], worker = [\"w\"], name = \"x\" }\n",
    );
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(m.contains("exactly one of `command` and `worker`"), "{m}");

    let (l, c, m) = err_at("\n[places.Patrol_B]\naction = { command = [] }\n");
    assert_eq!((l, c), (4, 10), "{m}");
    assert!(m.contains("the program is empty"), "{m}");

    let (l, c, m) =
        err_at("[places.Patrol_A]\naction = { command = [\"true\"], timeout = -1.0 }\n");
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(m.contains("`timeout` = -1"), "{m}");

    let (l, c, m) = err_at(
        "[places.Patrol_A]\naction = { worker = \"robt\", name = \"patrol\" }\n[workers.robot]\ncommand = [\"w\"]\n",
    );
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(
        m.contains("worker `robt` is not in [workers] (known: robot)"),
        "{m}"
    );

    let (l, c, m) = err_at(
        "[places.Patrol_A]\naction = { worker = \"robot\", name = \"p\", cwd = \"x\" }\n[workers.robot]\ncommand = [\"w\"]\n",
    );
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(m.contains("go in [workers.robot]"), "{m}");

    let (l, c, m) = err_at("[workers.robot]\ncommand = [\" \"]\n");
    assert_eq!((l, c), (2, 1), "{m}");
    assert!(m.contains("workers.robot: the program is empty"), "{m}");

    let (l, c, m) = err_at("[workers.robot]\ncommand = [\"w\"]\nuser = \"me\"\n");
    assert_eq!((l, c), (4, 1), "{m}");
    assert!(m.contains("unknown field `user`"), "{m}");

    let (l, c, m) = err_at("[places.Patrol_A]\naction = 3\n");
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(m.contains("an action name (a string) or a program"), "{m}");

    // A built-in written wrongly: at its value.
    let (l, c, m) = err_at("[places.Patrol_A]\naction = \"fire t_go_A\"\n");
    assert_eq!((l, c), (3, 10), "{m}");
    assert!(
        m.contains("`t_go_A` is not an output transition of `Patrol_A`"),
        "{m}"
    );
}

#[test]
fn an_unknown_action_name_is_refused_with_the_nearest_known_one() {
    let dir = tempfile::tempdir().unwrap();
    let plan = load(
        dir.path(),
        "[places.Patrol_A]\naction = \"wait\"\n\n[places.Patrol_B]\naction   = \"wiat 2\"\n",
    )
    .unwrap();
    let e = plan.check_actions(&[]).unwrap_err();
    let s = e.span.unwrap();
    assert_eq!((s.line, s.column), (6, 12), "{e}");
    assert_eq!(e.path, dir.path().join("plan.toml"));
    let m = e.kind.to_string();
    assert!(
        m.starts_with("place `Patrol_B`: unknown action `wiat 2` (did you mean `wait`?); known actions: `wait [S]`, `log MSG`, `fire T [after S]`, `ros2`"),
        "{m}"
    );

    // A library user who registers the name passes it; a name far from every known one
    // gets no suggestion.
    let plan = load(dir.path(), "[places.Decide]\naction = \"plan_route\"\n").unwrap();
    plan.check_actions(&["plan_route"]).unwrap();
    let m = plan
        .check_actions(&["inspect"])
        .unwrap_err()
        .kind
        .to_string();
    assert!(
        m.starts_with("place `Decide`: unknown action `plan_route`; known actions:")
            && m.contains("`inspect`"),
        "{m}"
    );
}

#[test]
fn every_plan_in_plans_names_only_known_actions() {
    let mut n = 0;
    for entry in glob_plans(&repo("plans")) {
        let plan = read_plan(&entry, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", entry.display()));
        plan.check_actions(&[])
            .unwrap_or_else(|e| panic!("{}: {e}", entry.display()));
        n += 1;
    }
    assert!(n >= 11, "{n} plans");
}

fn glob_plans(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(glob_plans(&p));
        } else if p.extension().is_some_and(|x| x == "toml") {
            out.push(p);
        }
    }
    out.sort();
    out
}
