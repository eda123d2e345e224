//! Storm's explicit DRN format for a [`DecisionModel`] (a Markov automaton with rewards), so
//! Storm can check our results: `storm --explicit-drn model.drn --prop 'R{"r"}max=? [LRA]'`
//! or `stormpy.build_model_from_drn`.
//!
//! Markovian states carry their exit rate (`!rate`) and one action whose branches are the
//! jump probabilities; instant states carry `!0` and one action per choice, named after the
//! transition fired (`race`, `wait` for the other choices). Each reward model gives a state
//! reward (the rate earned per unit of time in Markovian states) and an action reward (the
//! impulse earned when the choice is taken). Dead markings are Markovian self-loops of rate
//! 1 that earn nothing.
//!
//! ```
//! use gspn::analysis::decision::{Controls, DecisionModel, RewardSpec};
//! use gspn::io::drn;
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("flip");
//! let (p, q) = (b.place("p", 1), b.place("q", 0));
//! let go = b.exponential("go", 2.0, Servers::Single);
//! let back = b.immediate("back", 0.0, 1);
//! b.input(p, go, 1); b.output(go, q, 1); b.input(q, back, 1); b.output(back, p, 1);
//! let net = b.build().unwrap();
//! let model = DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default()).unwrap();
//! let mut spec = RewardSpec { name: "r".into(), ..Default::default() };
//! spec.transitions.push((back, 1.5));
//! let text = drn::to_string(&net, &model, &[("r", &model.rewards(&spec))], &[]);
//! assert!(text.contains("state 0 !2 [0] init\n\taction delay [0]\n\t\t1 : 1\n"));
//! assert!(text.contains("state 1 !0 [0]\n\taction back [1.5]\n\t\t0 : 1\n"));
//! ```

use std::fmt::Write as _;

use crate::analysis::decision::{Action, DecisionModel, Kind, Rewards};
use crate::net::Net;

/// An action name Storm accepts: the transition's name with spaces made `_`.
fn name(net: &Net, a: Action) -> String {
    match a {
        Action::Fire(t) => net
            .transition(t)
            .name
            .chars()
            .map(|c| if c.is_whitespace() { '_' } else { c })
            .collect(),
        Action::Race => "race".into(),
        Action::Wait => "wait".into(),
        Action::Delay => "delay".into(),
    }
}

/// The model in DRN: `rewards` as named reward models, `labels` as named state sets (`init`
/// is always written).
pub fn to_string(
    net: &Net,
    model: &DecisionModel,
    rewards: &[(&str, &Rewards)],
    labels: &[(&str, &[bool])],
) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "// exported by gspn from net {}", net.name());
    out.push_str("@type: Markov Automaton\n@value_type: double\n@parameters\n\n@reward_models\n");
    let names: Vec<String> = rewards
        .iter()
        .map(|(n, _)| n.replace(char::is_whitespace, "_"))
        .collect();
    let _ = writeln!(out, "{}", names.join(" "));
    let _ = writeln!(
        out,
        "@nr_states\n{}\n@nr_choices\n{}\n@model",
        model.state_count(),
        model.choice_count()
    );
    let mut initial = vec![false; model.state_count()];
    for &(s, p) in model.initial() {
        if p > 0.0 {
            initial[s as usize] = true;
        }
    }
    let list = |values: &mut dyn Iterator<Item = f64>| -> String {
        values
            // `+ 0.0` turns a negative zero (a rate times 0) into 0: Storm reads either, but
            // "-0" in a reward column reads as a bug.
            .map(|v| format!("{}", v + 0.0))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for s in 0..model.state_count() {
        let exit = match model.kind(s) {
            Kind::Instant => 0.0,
            _ => model.exit_rate(s),
        };
        let _ = write!(
            out,
            "state {s} !{exit} [{}]",
            list(&mut rewards.iter().map(|(_, r)| r.rate[s]))
        );
        if initial[s] {
            out.push_str(" init");
        }
        for (label, set) in labels {
            if set[s] {
                let _ = write!(out, " {label}");
            }
        }
        out.push('\n');
        for c in model.choices(s) {
            let _ = writeln!(
                out,
                "\taction {} [{}]",
                name(net, model.action(c)),
                list(&mut rewards.iter().map(|(_, r)| r.impulse[c]))
            );
            for (t, p) in model.branches(c) {
                let _ = writeln!(out, "\t\t{t} : {p}");
            }
        }
    }
    out
}
