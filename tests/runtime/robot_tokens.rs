//! Robot plans refuse, at load, a net that can create or destroy robot tokens once resource
//! places are set aside — a structural check, one pass over the transitions.

use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{FailurePolicy, Role};
use gspn::runtime::{Outcome, Runtime, RuntimeError, action_fn};

fn robot(name: &str) -> Role {
    Role::Action {
        name: name.into(),
        timeout: None,
        on_failure: FailurePolicy::Stop,
        robot: Some("r1".into()),
    }
}

#[tokio::test]
async fn a_fork_of_robot_tokens_is_refused_naming_the_transition() {
    let mut b = NetBuilder::new("fork");
    let p = b.place("p", 1);
    let q = b.place("q", 0);
    let t = b.exponential("split", 1.0, Servers::Single);
    b.input(p, t, 1);
    b.output(t, q, 2);
    let err = Runtime::builder(b.build().unwrap())
        .action("go", action_fn(|_| async { Outcome::Decide }))
        .role(p, robot("go"))
        .spawn()
        .unwrap_err();
    match err {
        RuntimeError::RobotTokens { transition, change } => {
            assert_eq!((transition.as_str(), change), ("split", 1));
        }
        e => panic!("unexpected {e}"),
    }
}

#[tokio::test]
async fn tokens_taken_from_a_resource_place_do_not_count() {
    // A robot takes the charger (a resource) and gives it back: robot tokens are conserved.
    let mut b = NetBuilder::new("charger");
    let work = b.place("work", 1);
    let charge = b.place("charge", 0);
    let charger = b.place("charger", 1);
    let plug = b.exponential("plug", 1.0, Servers::Single);
    let unplug = b.exponential("unplug", 1.0, Servers::Single);
    b.input(work, plug, 1);
    b.input(charger, plug, 1);
    b.output(plug, charge, 1);
    b.input(charge, unplug, 1);
    b.output(unplug, work, 1);
    b.output(unplug, charger, 1);
    let h = Runtime::builder(b.build().unwrap())
        .action("go", action_fn(|_| async { Outcome::Decide }))
        .role(work, robot("go"))
        .role(charger, Role::Resource)
        .max_firings(10)
        .seed(1)
        .spawn()
        .unwrap();
    assert_eq!(h.wait().await.firings, 10);
}
