use super::*;
use crate::net::Servers;

fn cyc3() -> Net {
    crate::net::cyc3(Servers::Single)
}

fn edit(v: serde_json::Value) -> Edit {
    serde_json::from_value(v).unwrap()
}

#[test]
fn operations_read_from_the_pages_json() {
    assert_eq!(
        edit(serde_json::json!({"op": "set_place", "place": "P1", "capacity": null})),
        Edit::SetPlace(change::SetPlace {
            place: "P1".into(),
            name: None,
            tokens: None,
            capacity: Some(None),
        })
    );
    let e = serde_json::from_value::<Edit>(
        serde_json::json!({"op": "set_place", "place": "P1", "tokns": 3}),
    );
    assert!(e.unwrap_err().to_string().contains("unknown field `tokns`"));
}

#[test]
fn deleting_a_place_renumbers_the_arcs_of_the_later_ones() {
    let net = cyc3();
    let (after, label) = apply(
        &net,
        &edit(serde_json::json!({"op": "delete", "node": {"place": "P1"}})),
    )
    .unwrap();
    assert_eq!(label, "delete place P1 and its 2 arcs");
    assert_eq!(after.place_count(), 2);
    assert_eq!(after.arcs().len(), net.arcs().len() - 2);
    for a in after.arcs() {
        let before = net
            .arcs()
            .iter()
            .find(|b| {
                net.place(b.place).name == after.place(a.place).name
                    && net.transition(b.transition).name == after.transition(a.transition).name
            })
            .unwrap();
        assert_eq!(before.kind, a.kind);
    }
}
