//! The drawing in a real browser: on the thesis's temperature patrol (a file with no
//! positions: the automatic layout) and on GreatSPN's FMS (the file's positions, rotations
//! and label offsets) no arc passes through a node and at most 4 arc–label crossings remain,
//! counted from the SVG geometry the page drew (paths, circles, rectangles, text boxes).
#![cfg(feature = "web")]

use crate::browser::{BROWSER, PATROL, WAIT, screenshot_path};
use crate::support as common;
use crate::support::browser::Browser;
use crate::support::start_server;

use gspn::io::{ReadOptions, read_net};
use gspn::web::WebState;
use serde_json::Value;

/// Every arc's polyline against every node's body and every name and parameter text, in
/// the net's coordinates. Returns `{arcs, nodes, labels, hitsNode: [...], hitsLabel: [...]}`.
const GEOMETRY: &str = r#"
const nodes = [];
const labels = [];
for (const g of document.querySelectorAll('#nodes .node')) {
  const m = g.transform.baseVal.consolidate().matrix;
  const name = g.getAttribute('data-place') || g.getAttribute('data-transition');
  const circle = g.querySelector('circle.body');
  if (circle) {
    nodes.push({ name, cx: m.e, cy: m.f, r: circle.r.baseVal.value });
  } else {
    const b = g.querySelector('rect').getBBox();
    nodes.push({ name, x0: m.e + b.x, y0: m.f + b.y, x1: m.e + b.x + b.width, y1: m.f + b.y + b.height });
  }
  for (const t of g.querySelectorAll('text.label, text.param')) {
    const b = t.getBBox();
    labels.push({ name: name + ': ' + t.textContent, x0: m.e + b.x, y0: m.f + b.y, x1: m.e + b.x + b.width, y1: m.f + b.y + b.height });
  }
}
// Does the segment p–q meet the box (Liang–Barsky)?
function hitsBox(p, q, b) {
  let t0 = 0, t1 = 1;
  const d = [q[0] - p[0], q[1] - p[1]];
  const edges = [[-d[0], p[0] - b.x0], [d[0], b.x1 - p[0]], [-d[1], p[1] - b.y0], [d[1], b.y1 - p[1]]];
  for (const [pp, qq] of edges) {
    if (pp === 0) { if (qq < 0) return false; continue; }
    const r = qq / pp;
    if (pp < 0) { if (r > t1) return false; if (r > t0) t0 = r; }
    else { if (r < t0) return false; if (r < t1) t1 = r; }
  }
  return true;
}
function hitsCircle(p, q, c) {
  const dx = q[0] - p[0], dy = q[1] - p[1];
  const l2 = dx * dx + dy * dy;
  const s = l2 ? Math.max(0, Math.min(1, ((c.cx - p[0]) * dx + (c.cy - p[1]) * dy) / l2)) : 0;
  return Math.hypot(p[0] + s * dx - c.cx, p[1] + s * dy - c.cy) < c.r;
}
const hitsNode = [];
const hitsLabel = [];
const paths = [...document.querySelectorAll('#arcs path.arc')];
paths.forEach((path, i) => {
  const nums = path.getAttribute('d').replace(/[ML]/g, ' ').trim().split(/\s+/).map(Number);
  const pts = [];
  for (let k = 0; k < nums.length; k += 2) pts.push([nums[k], nums[k + 1]]);
  const seg = (f) => pts.slice(1).some((q, k) => f(pts[k], q));
  for (const n of nodes) {
    if (seg((p, q) => (n.r ? hitsCircle(p, q, n) : hitsBox(p, q, n)))) hitsNode.push(i + ' ' + n.name);
  }
  for (const l of labels) {
    if (seg((p, q) => hitsBox(p, q, l))) hitsLabel.push(i + ' ' + l.name);
  }
});
return { arcs: paths.length, nodes: nodes.length, labels: labels.length, hitsNode, hitsLabel };
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_patrol_and_fms_have_no_arc_through_a_node_and_at_most_four_through_a_label() {
    let _one = BROWSER.lock().await;
    let net = read_net(&common::fixture(PATROL), &ReadOptions::default())
        .unwrap()
        .net;
    assert!(net.places().iter().all(|p| p.position.is_none()));
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0)).await;
    let b = Browser::start(1400, 900).await;
    b.client.goto(&format!("http://{addr}/")).await.unwrap();
    b.wait_js(
        "return window.gspnPerf && window.gspnPerf.drawn;",
        WAIT,
        "the first drawing",
    )
    .await;
    let g: Value = b.js(GEOMETRY, vec![]).await;
    b.screenshot(&screenshot_path("patrol-layout.png")).await;
    assert_eq!(g["arcs"], net.arcs().len());
    assert_eq!(g["nodes"], net.place_count() + net.transition_count());
    // A name under each node, a rate above each transition (the patrol has no capacities
    // but PIPE's 0, drawn as `cap 0`).
    assert!(g["labels"].as_u64().unwrap() >= 64, "{}", g["labels"]);
    assert_eq!(g["hitsNode"], serde_json::json!([]), "arcs through nodes");
    let crossings = g["hitsLabel"].as_array().unwrap();
    assert!(
        crossings.len() <= 4,
        "{} arc–label crossings: {crossings:?}",
        crossings.len()
    );
    server.abort();

    // FMS, a GreatSPN project: its rotations and label offsets are honoured (the file's
    // layout, the file's look).
    let path = common::fixture("greatspn/greatspn_examples/fms.PNPRO");
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0).with_source(&path)).await;
    b.client.goto(&format!("http://{addr}/")).await.unwrap();
    b.wait_js(
        "return window.gspnPerf && window.gspnPerf.drawn;",
        WAIT,
        "the first drawing",
    )
    .await;
    let g: Value = b.js(GEOMETRY, vec![]).await;
    b.screenshot(&screenshot_path("fms.png")).await;
    // `repM2` is turned a quarter round: its bar lies down.
    let rep = b
        .js(
            "const r = document.querySelector('[data-transition=\"repM2\"] rect').getBBox();\
             return [r.width, r.height];",
            vec![],
        )
        .await;
    assert_eq!(rep, serde_json::json!([30, 6]));
    let crossings = g["hitsLabel"].as_array().unwrap();
    // 22 arc–label crossings when rotations and offsets were ignored.
    assert!(
        crossings.len() <= 4,
        "FMS: {} arc–label crossings: {crossings:?}",
        crossings.len()
    );
    assert_eq!(
        g["hitsNode"],
        serde_json::json!([]),
        "FMS: arcs through nodes"
    );
    b.close().await;
    server.abort();
}
