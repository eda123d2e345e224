//! The viewer readable on a laptop (1280×800), measured on the page in screen pixels: MCC's
//! Peterson (every node at one point in its file) draws with no two nodes overlapping; the
//! README's home-cleaning plan (GSPNR grid positions) opens in the automatic layout with at
//! most 40 arc crossings, no arc segment through a node and no label over a label, and the
//! `layout` control brings the file's positions back (remembered on reload); the thesis
//! patrol shows its names at 10 px or more and its rates; a replay's conformance table has
//! every column reachable.
#![cfg(feature = "web")]

use crate::browser::{BROWSER, PATROL, WAIT, analyse_on_page, open, screenshot_path};
use crate::support as common;
use crate::support::browser::Browser;
use crate::support::start_server;

use std::path::PathBuf;

use gspn::io::{ReadOptions, read_net};
use gspn::net::Net;
use gspn::web::WebState;
use serde_json::{Value, json};

/// The drawing in screen pixels: node bodies, visible names and rates, every arc's polyline
/// with its place and transition. Returns `{nodes, labels, overlaps, crossings, through,
/// labelOverlaps, minNamePx, params}`.
pub(crate) const SCREEN_GEOMETRY: &str = r#"
const nodes = [];
const labels = [];
const shown = (e) => getComputedStyle(e).display !== 'none';
for (const g of document.querySelectorAll('#nodes .node')) {
  const name = g.getAttribute('data-place') || g.getAttribute('data-transition');
  const place = g.hasAttribute('data-place');
  const body = g.querySelector('circle.body') || g.querySelector('rect');
  const r = body.getBoundingClientRect();
  nodes.push({ name, place, x0: r.left, y0: r.top, x1: r.right, y1: r.bottom,
               cx: (r.left + r.right) / 2, cy: (r.top + r.bottom) / 2, r: r.width / 2 });
  for (const t of g.querySelectorAll('text.label, text.param')) {
    if (!shown(t) || !t.textContent) continue;
    const b = t.getBoundingClientRect();
    const px = parseFloat(getComputedStyle(t).fontSize) * t.getScreenCTM().a;
    labels.push({ name: name + ': ' + t.textContent, param: t.classList.contains('param'),
                  x0: b.left, y0: b.top, x1: b.right, y1: b.bottom, px });
  }
}
const byName = (place, name) => nodes.find((n) => n.place === place && n.name === name);
const overlap = (a, b, m) => Math.min(a.x1, b.x1) - Math.max(a.x0, b.x0) > m && Math.min(a.y1, b.y1) - Math.max(a.y0, b.y0) > m;
let overlaps = 0;
for (let i = 0; i < nodes.length; i++) for (let j = i + 1; j < nodes.length; j++) if (overlap(nodes[i], nodes[j], 0)) overlaps++;
// Arcs: their paths in screen pixels (net.arcs and arcEls are the page's own).
const segs = [];
net.arcs.forEach((a, i) => {
  const path = arcEls[i].path;
  const m = path.getScreenCTM();
  const nums = path.getAttribute('d').replace(/[ML]/g, ' ').trim().split(/\s+/).map(Number);
  const pts = [];
  for (let k = 0; k < nums.length; k += 2) {
    const p = new DOMPoint(nums[k], nums[k + 1]).matrixTransform(m);
    pts.push([p.x, p.y]);
  }
  const ends = [net.places[a.place].name, net.transitions[a.transition].name];
  for (let k = 1; k < pts.length; k++) segs.push({ p: pts[k - 1], q: pts[k], arc: i, ends });
});
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
  return Math.hypot(p[0] + s * dx - c.cx, p[1] + s * dy - c.cy) < c.r - 1;
}
const through = [];
for (const s of segs) {
  for (const n of nodes) {
    if (s.ends.includes(n.name)) continue;
    const shrunk = { x0: n.x0 + 1, y0: n.y0 + 1, x1: n.x1 - 1, y1: n.y1 - 1 };
    if (n.place ? hitsCircle(s.p, s.q, n) : hitsBox(s.p, s.q, shrunk)) through.push(s.arc + ' through ' + n.name);
  }
}
const orient = (a, b, c) => (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
const sides = (x, y) => (x > 1e-6 && y < -1e-6) || (x < -1e-6 && y > 1e-6);
let crossings = 0;
for (let i = 0; i < segs.length; i++) {
  for (let j = i + 1; j < segs.length; j++) {
    const a = segs[i], b = segs[j];
    if (a.arc === b.arc) continue;
    if (sides(orient(a.p, a.q, b.p), orient(a.p, a.q, b.q)) && sides(orient(b.p, b.q, a.p), orient(b.p, b.q, a.q))) crossings++;
  }
}
const labelOverlaps = [];
for (let i = 0; i < labels.length; i++) for (let j = i + 1; j < labels.length; j++) {
  if (overlap(labels[i], labels[j], 0.5)) labelOverlaps.push(labels[i].name + ' / ' + labels[j].name);
}
const names = labels.filter((l) => !l.param);
return { nodes: nodes.length, labels: labels.length, overlaps, crossings, through, labelOverlaps,
         minNamePx: Math.min(...names.map((l) => l.px)),
         params: labels.filter((l) => l.param).map((l) => l.name) };
"#;

/// The home-cleaning plan's locations kept together: each node's location by its name (the
/// first `L<k>` part after the first, or the name itself: `Go_L1_L2` and `L1` are `L1`'s),
/// the bounding box of each location's node bodies on the screen, and how many nodes of
/// other locations have their centre inside one (counted per box). Returns `{groups,
/// foreign, boxes}`.
const LOCATION_MIXING: &str = r#"
const groupOf = (name) => {
  const parts = name.split(/[^A-Za-z0-9]+/);
  return parts.length === 1 ? parts[0] : parts.slice(1).find((p) => /^L[0-9]+$/.test(p));
};
const nodes = [...document.querySelectorAll('#nodes .node')].map((g) => {
  const r = (g.querySelector('circle.body') || g.querySelector('rect')).getBoundingClientRect();
  const name = g.getAttribute('data-place') || g.getAttribute('data-transition');
  return { group: groupOf(name), r, cx: (r.left + r.right) / 2, cy: (r.top + r.bottom) / 2 };
});
const boxes = {};
for (const n of nodes) {
  if (!n.group) continue;
  const b = boxes[n.group] || (boxes[n.group] = { x0: Infinity, y0: Infinity, x1: -Infinity, y1: -Infinity });
  b.x0 = Math.min(b.x0, n.r.left); b.y0 = Math.min(b.y0, n.r.top);
  b.x1 = Math.max(b.x1, n.r.right); b.y1 = Math.max(b.y1, n.r.bottom);
}
let foreign = 0;
for (const [g, b] of Object.entries(boxes)) {
  for (const n of nodes) if (n.group !== g && n.cx >= b.x0 && n.cx <= b.x1 && n.cy >= b.y0 && n.cy <= b.y1) foreign++;
}
return { groups: Object.keys(boxes).length, foreign, boxes };
"#;

fn read(path: &std::path::Path) -> Net {
    read_net(path, &ReadOptions::default()).unwrap().net
}

async fn geometry(b: &Browser) -> Value {
    b.js(SCREEN_GEOMETRY, vec![]).await
}

fn count(v: &Value) -> u64 {
    v.as_u64().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn at_1280x800_nets_open_readable() {
    let _one = BROWSER.lock().await;
    let b = Browser::start(1280, 800).await;

    // Peterson: 228 nodes at (100, 100) in the file: the automatic layout, no overlap.
    let net = read(&common::fixture("mcc/Peterson-PT-2/model.pnml"));
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0)).await;
    open(&b, addr).await;
    let g = geometry(&b).await;
    assert_eq!(count(&g["nodes"]), 228);
    assert_eq!(g["overlaps"], json!(0), "Peterson: overlapping nodes");
    let title = b.text("#title").await;
    assert!(title.ends_with("(automatic layout)"), "{title}");
    b.screenshot(&screenshot_path("peterson-1280.png")).await;
    server.abort();

    // The home-cleaning plan's net, with its GreatSPN look.
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/home-cleaning/net.PNPRO");
    let net = read(&path);
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0).with_source(&path)).await;
    open(&b, addr).await;
    let after = geometry(&b).await;
    let grouped = b.js(LOCATION_MIXING, vec![]).await;
    b.screenshot(&screenshot_path("home-cleaning-1280.png"))
        .await;
    assert_eq!(
        count(&after["nodes"]),
        (net.place_count() + net.transition_count()) as u64
    );
    // The file's positions, by the `layout` control: what the page drew before.
    b.js(
        "const s = document.getElementById('layout-choice'); s.value = 'file';\
         s.dispatchEvent(new Event('change'));",
        vec![],
    )
    .await;
    b.wait_js("return net.layout === 'file';", WAIT, "the file's layout")
        .await;
    let before = geometry(&b).await;
    let file_grouped = b.js(LOCATION_MIXING, vec![]).await;
    b.screenshot(&screenshot_path("home-cleaning-1280-file-layout.png"))
        .await;
    eprintln!(
        "home-cleaning at 1280x800: file positions {} crossings, {} segments through nodes, {} label overlaps, \
         {} nodes in another location's box; automatic {} crossings, {} through nodes, {} label overlaps, \
         {} nodes in another location's box",
        before["crossings"],
        before["through"].as_array().unwrap().len(),
        before["labelOverlaps"].as_array().unwrap().len(),
        file_grouped["foreign"],
        after["crossings"],
        after["through"].as_array().unwrap().len(),
        after["labelOverlaps"].as_array().unwrap().len(),
        grouped["foreign"],
    );
    // The three locations, each in a box of its own that no other node enters (58 nodes
    // are in another location's box at the file's positions).
    assert_eq!(grouped["groups"], json!(3));
    assert_eq!(grouped["foreign"], json!(0), "{grouped}");
    assert!(count(&after["crossings"]) <= 40, "{}", after["crossings"]);
    assert_eq!(after["through"], json!([]), "arcs through nodes");
    assert_eq!(after["labelOverlaps"], json!([]), "labels over labels");
    assert!(
        count(&before["crossings"]) > count(&after["crossings"]),
        "{} vs {}",
        before["crossings"],
        after["crossings"]
    );
    assert!(!before["through"].as_array().unwrap().is_empty());
    // Remembered for this net: a reload keeps the file's positions, then back.
    open(&b, addr).await;
    let kept = b
        .js(
            "return [document.getElementById('layout-choice').value, net.layout];",
            vec![],
        )
        .await;
    assert_eq!(kept, json!(["file", "file"]));
    b.js(
        "const s = document.getElementById('layout-choice'); s.value = 'layered';\
         s.dispatchEvent(new Event('change'));",
        vec![],
    )
    .await;
    b.wait_js(
        "return net.layout === 'layered';",
        WAIT,
        "the automatic layout",
    )
    .await;
    assert_eq!(geometry(&b).await["crossings"], after["crossings"]);
    server.abort();

    // The thesis patrol (no positions): names at 10 px at least, every rate and weight shown.
    let net = read(&common::fixture(PATROL));
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0)).await;
    open(&b, addr).await;
    let g = geometry(&b).await;
    b.screenshot(&screenshot_path("patrol-1280.png")).await;
    let px = g["minNamePx"].as_f64().unwrap();
    assert!(px >= 9.99, "names {px} px high");
    let params = g["params"].as_array().unwrap();
    for t in net.transitions() {
        let prefix = if t.is_immediate() { "w=" } else { "λ=" };
        assert!(
            params.iter().any(|p| p
                .as_str()
                .unwrap()
                .starts_with(&format!("{}: {prefix}", t.name))),
            "no rate or weight shown for {}: {params:?}",
            t.name
        );
    }
    // Plots: p1 clicked, then p5 shift-clicked: two curves over the same times, as CSV with
    // the tokens the page shows now on its last line; the pointer reads both curves.
    b.click("#step-n").await;
    b.wait_js(
        "return document.getElementById('clock').textContent.includes(', 10 firings');",
        WAIT,
        "10 firings",
    )
    .await;
    let click = "const g = document.querySelector('#nodes [data-place=\"' + arguments[0] + '\"] circle');\
                 const r = g.getBoundingClientRect();\
                 const o = {clientX: r.x + r.width / 2, clientY: r.y + r.height / 2, bubbles: true, shiftKey: arguments[1]};\
                 g.dispatchEvent(new MouseEvent('mousedown', o));\
                 window.dispatchEvent(new MouseEvent('mouseup', o));";
    let (p1, p5) = ("p1:Check_Temperature_L1", "p5:Check_Temperature_L2");
    b.js(click, vec![json!(p1), json!(false)]).await;
    b.js(click, vec![json!(p5), json!(true)]).await;
    let plot = b
        .wait_js(
            "const ls = [...document.querySelectorAll('#plot polyline')];\
             return ls.length === 2 && [ls.map(l => l.dataset.series), window.gspnPlot.csv(),\
               [...document.querySelectorAll('#nodes [data-place]')].map(g => [g.dataset.place, g.dataset.tokens])];",
            WAIT,
            "two curves",
        )
        .await;
    assert_eq!(plot[0], json!([p1, p5]));
    let csv = plot[1].as_str().unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], format!("time,{p1},{p5}"));
    let tokens: std::collections::HashMap<String, String> =
        serde_json::from_value::<Vec<(String, String)>>(plot[2].clone())
            .unwrap()
            .into_iter()
            .collect();
    let last: Vec<&str> = lines.last().unwrap().split(',').collect();
    assert_eq!(
        last[1..],
        [tokens[p1].as_str(), tokens[p5].as_str()],
        "{csv}"
    );
    assert!(lines.len() >= 3, "{csv}");
    let readout = b
        .js(
            "const svg = document.getElementById('plot'); const r = svg.getBoundingClientRect();\
             svg.dispatchEvent(new MouseEvent('mousemove', {clientX: r.x + r.width / 2, clientY: r.y + r.height / 2, bubbles: true}));\
             return document.getElementById('plot-readout').textContent;",
            vec![],
        )
        .await;
    let readout = readout.as_str().unwrap();
    assert!(
        readout.starts_with("t = ") && readout.contains(p1) && readout.contains(p5),
        "{readout}"
    );
    b.screenshot(&screenshot_path("plot-two-places.png")).await;

    // A question's answers as curves: the expected tokens of the plotted places at each
    // asked time, as in the table, and as CSV.
    analyse_on_page(&b).await;
    b.js(
        "document.getElementById('query-times').value = '0.5, 2, 10';\
         document.getElementById('query').click();",
        vec![],
    )
    .await;
    let answers = b
        .wait_js(
            "const ls = [...document.querySelectorAll('#answer-plot polyline')];\
             return ls.length > 0 && [ls.map(l => [l.dataset.series, l.dataset.points]), window.gspnAnswers.csv(),\
               [...document.querySelectorAll('#query-result td[data-tokens]')].map(td => [td.dataset.tokens, td.dataset.t + ',' + td.dataset.value])];",
            WAIT,
            "the answers' curves",
        )
        .await;
    let curves: Vec<(String, String)> = serde_json::from_value(answers[0].clone()).unwrap();
    assert_eq!(
        curves.iter().map(|c| c.0.as_str()).collect::<Vec<_>>(),
        [format!("E[{p1}]"), format!("E[{p5}]")]
    );
    // Compared as text: every digit the page holds (serde_json's float reading may round).
    let cells: Vec<(String, String)> = serde_json::from_value(answers[2].clone()).unwrap();
    for (series, points) in &curves {
        let place = &series[2..series.len() - 1];
        let want: Vec<&str> = cells
            .iter()
            .filter(|c| c.0 == place)
            .map(|c| c.1.as_str())
            .collect();
        let drawn: Vec<&str> = points.split(' ').collect();
        assert_eq!(drawn, want, "{series}");
        assert_eq!(drawn.len(), 3);
    }
    let csv = answers[1].as_str().unwrap();
    assert_eq!(csv.lines().count(), 4, "{csv}");
    assert!(
        csv.starts_with(&format!("time,E[{p1}],E[{p5}]\n0.5,")),
        "{csv}"
    );

    // The minimap: small, hidden by its button (remembered on reload) and while editing.
    let mini = b
        .js(
            "const m = document.getElementById('minimap-box');\
             const w = m.getBoundingClientRect().width;\
             document.querySelector('[data-collapse=\"minimap-box\"]').click();\
             return [w, getComputedStyle(m).display];",
            vec![],
        )
        .await;
    assert!(mini[0].as_f64().unwrap() <= 160.0, "{mini}");
    assert_eq!(mini[1], "none");
    open(&b, addr).await;
    let hidden = b
        .js(
            "return getComputedStyle(document.getElementById('minimap-box')).display;",
            vec![],
        )
        .await;
    assert_eq!(hidden, "none", "the hidden minimap stays hidden on reload");

    // `fit` (key f) still shows the whole net, smaller.
    b.click("#fit").await;
    // (Names too small to read are not drawn at all: no size.)
    let whole = geometry(&b).await["minNamePx"].as_f64().unwrap_or(0.0);
    assert!(whole < px, "{whole} vs {px}");
    b.screenshot(&screenshot_path("patrol-1280-whole.png"))
        .await;
    b.close().await;
    server.abort();
}
