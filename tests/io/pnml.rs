//! PNML: the 17 MCC P/T models, the timed Kanban GSPNs, and the thesis's PNML dialects.

use crate::support::fixtures as shared_fixtures;

use gspn::io::{Format, ReadOptions, read_net};
use gspn::net::{Net, Servers, Timing};
use shared_fixtures::{files_under, fixture};

fn load(rel: &str) -> Net {
    let path = fixture(rel);
    read_net(&path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{rel} does not load: {e}"))
        .net
}

/// `STATE_SPACE <key> <n>` from a model's oracle file.
fn oracle(model: &str, key: &str) -> u64 {
    let text = std::fs::read_to_string(fixture(&format!("mcc/{model}/StateSpace-oracle-2021.out")))
        .expect("oracle file");
    text.lines()
        .find_map(|l| {
            let mut w = l.split_whitespace();
            (w.next() == Some("STATE_SPACE") && w.next() == Some(key))
                .then(|| w.next().unwrap().parse().unwrap())
        })
        .unwrap_or_else(|| panic!("no {key} in the oracle of {model}"))
}

#[test]
fn all_17_mcc_models_load_as_rate_1_single_server_pt_nets() {
    let files = files_under("mcc", &["model.pnml"]);
    assert_eq!(files.len(), 17);
    for f in &files {
        let l =
            read_net(f, &ReadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(l.format, Format::Pnml);
        assert!(l.net.place_count() > 0 && l.net.transition_count() > 0);
        for t in l.net.transitions() {
            assert_eq!(
                t.timing,
                Timing::Exponential {
                    rate: 1.0,
                    servers: Servers::Single
                },
                "{}: {}",
                f.display(),
                t.name
            );
        }
    }
}

#[test]
fn mcc_models_have_their_place_transition_arc_and_token_counts() {
    // Counted independently in the model files (places, transitions, arcs, tokens).
    let cases = [
        ("SwimmingPool-PT-01", 9, 7, 20, 45),
        ("Philosophers-PT-000005", 25, 25, 80, 10),
        ("Kanban-PT-00005", 16, 16, 40, 20),
        ("FMS-PT-00005", 22, 20, 50, 21),
        ("Dekker-PT-010", 50, 120, 820, 20),
        ("TokenRing-PT-005", 36, 156, 624, 6),
        ("Peterson-PT-2", 102, 126, 384, 8),
        ("GPPP-PT-C0001N0000000001", 33, 22, 83, 22),
    ];
    for (model, p, t, a, tokens) in cases {
        let net = load(&format!("mcc/{model}/model.pnml"));
        assert_eq!(
            (
                net.place_count(),
                net.transition_count(),
                net.arcs().len(),
                net.initial_tokens()
            ),
            (p, t, a, tokens),
            "{model}"
        );
    }
}

#[test]
fn conservative_mcc_models_start_with_the_oracles_max_tokens_per_marking() {
    // Philosophers and TokenRing conserve tokens: the initial count is the oracle's maximum.
    for model in ["Philosophers-PT-000005", "TokenRing-PT-005"] {
        let net = load(&format!("mcc/{model}/model.pnml"));
        assert_eq!(
            net.initial_tokens(),
            oracle(model, "MAX_TOKEN_PER_MARKING"),
            "{model}"
        );
    }
}

#[test]
fn gppp_arc_inscriptions_are_weights() {
    let net = load("mcc/GPPP-PT-C0001N0000000001/model.pnml");
    let generate = net.transition_by_name("generate").unwrap();
    let adp = net.place_by_name("ADP").unwrap();
    let gluc = net.place_by_name("Gluc").unwrap();
    let out = net.outputs(generate);
    assert!(out.contains(&(adp, 7)), "{out:?}");
    assert!(out.contains(&(gluc, 4)), "{out:?}");
    assert_eq!(net.place(net.place_by_name("c1").unwrap()).initial, 7);
}

#[test]
fn kanban_n1_has_16_places_16_timed_transitions_and_their_rates() {
    let net = load("kanban/kanban_gspn_N1.pnml");
    assert_eq!(
        (net.place_count(), net.transition_count(), net.arcs().len()),
        (16, 16, 40)
    );
    assert_eq!(net.initial_tokens(), 4);
    for p in ["P1", "P2", "P3", "P4"] {
        assert_eq!(net.place(net.place_by_name(p).unwrap()).initial, 1, "{p}");
    }
    let rates = [
        ("tback3", 0.3),
        ("tredo3", 0.42),
        ("tredo2", 0.39),
        ("tok3", 0.98),
        ("tredo4", 0.36),
        ("tin4", 1.0),
        ("tok4", 0.84),
        ("tback4", 0.3),
        ("tsynch1_23", 0.5),
        ("tout1", 0.9),
        ("tok1", 0.77),
        ("tsynch4_23", 0.4),
        ("tredo1", 0.33),
        ("tback1", 0.3),
        ("tback2", 0.3),
        ("tok2", 0.91),
    ];
    for (t, rate) in rates {
        let id = net.transition_by_name(t).unwrap();
        assert_eq!(
            net.transition(id).timing,
            Timing::Exponential {
                rate,
                servers: Servers::Single
            },
            "{t}"
        );
    }
}

#[test]
fn kanban_n_tokens_scale_with_n() {
    for n in 1..=4u64 {
        let net = load(&format!("kanban/kanban_gspn_N{n}.pnml"));
        assert_eq!(net.initial_tokens(), 4 * n);
    }
}

#[test]
fn viptool_dialect_of_azevedo_2018_is_read_with_ids_for_blank_names() {
    let l = read_net(
        &fixture("thesis/azevedo_2018/test.pnml"),
        &ReadOptions::default(),
    )
    .unwrap();
    let net = &l.net;
    assert_eq!(l.format, Format::Pnml);
    assert_eq!(
        (net.place_count(), net.transition_count(), net.arcs().len()),
        (2, 2, 4)
    );
    // Names are blank (a no-break space): the ids name the nodes.
    let p17 = net.place_by_name("17").expect("place 17");
    assert_eq!(net.place(p17).initial, 2);
    assert_eq!(net.place(net.place_by_name("18").unwrap()).initial, 0);
    assert!(net.transition_by_name("15").is_some());
    assert!(
        l.warnings.iter().any(|w| w.contains("VipTool")),
        "{:?}",
        l.warnings
    );
    assert!(
        l.warnings.iter().any(|w| w.contains("named by their id")),
        "{:?}",
        l.warnings
    );
}

#[test]
fn iso_pnml_without_namespace_of_azevedo_2018_is_read() {
    // example.pnml: ISO structure, ids differ from names, all arcs share one id.
    let l = read_net(
        &fixture("thesis/azevedo_2018/example.pnml"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(l.format, Format::Pnml);
    assert_eq!(
        (
            l.net.place_count(),
            l.net.transition_count(),
            l.net.arcs().len()
        ),
        (7, 7, 17)
    );
    assert!(
        l.net.transition_by_name("a").is_some(),
        "named by <name>, not by id"
    );
    assert!(
        l.warnings.iter().any(|w| w.contains("arc id")),
        "{:?}",
        l.warnings
    );
    // examp2.pnml is PIPE's dialect under a .pnml name.
    let l = read_net(
        &fixture("thesis/azevedo_2018/examp2.pnml"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(l.format, Format::Pipe);
    assert_eq!((l.net.place_count(), l.net.transition_count()), (5, 4));
}
