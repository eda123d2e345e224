//! The page's lists, keys and look in a real browser: the trace says "last 200 of N", keeps
//! every digit of its step numbers and times, follows new lines only when the user is at
//! the bottom, and filters; `?` lists the shortcuts and `s` steps; arc weights are drawn in
//! the text colour and inhibitor arcs over the others; `?theme=dark` (as the system's dark
//! preference) darkens the page; a resize fits the net again.
#![cfg(feature = "web")]

use crate::browser::{BROWSER, WAIT, screenshot_path};
use crate::support::browser::Browser;
use crate::support::start_server;

use fantoccini::Locator;
use gspn::net::{Net, NetBuilder, Servers};
use gspn::web::WebState;
use serde_json::{Value, json};

/// `p0 -t0-> p1` (weight 2), `p1 =2=> t1 -> p0`, an inhibitor arc `p2 -o t0`: t0 and t1
/// fire in turn for ever.
fn toggle() -> Net {
    let mut b = NetBuilder::new("toggle");
    let (p0, p1, p2) = (b.place("p0", 1), b.place("p1", 0), b.place("p2", 0));
    let t0 = b.exponential("t0", 2.0, Servers::Single);
    let t1 = b.exponential("t1", 3.0, Servers::Single);
    b.input(p0, t0, 1);
    b.output(t0, p1, 2);
    b.input(p1, t1, 2);
    b.output(t1, p0, 1);
    b.inhibitor(p2, t0, 1);
    b.build().unwrap()
}

async fn firings(b: &Browser) -> u64 {
    let clock = b.text("#clock").await;
    clock
        .split(", ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

async fn wait_firings(b: &Browser, n: u64) {
    let script =
        format!("return document.getElementById('clock').textContent.includes(', {n} firings');");
    b.wait_js(&script, WAIT, &format!("{n} firings")).await;
}

async fn trace_texts(b: &Browser, visible_only: bool) -> Vec<String> {
    let script = format!(
        "return [...document.querySelectorAll('#trace li')]\
           .filter(li => !{visible_only} || !li.classList.contains('hidden'))\
           .map(li => li.textContent);"
    );
    serde_json::from_value(b.js(&script, vec![]).await).unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lists_keys_theme_and_resize() {
    let _one = BROWSER.lock().await;
    let net = toggle();
    let (addr, server) = start_server(WebState::new(net.clone(), None, 5)).await;
    let b = Browser::start(1200, 800).await;
    b.client.goto(&format!("http://{addr}/")).await.unwrap();
    b.wait_js(
        "return window.gspnPerf && window.gspnPerf.drawn;",
        WAIT,
        "the first drawing",
    )
    .await;

    // Arc weights in the text colour, not the inhibitor arcs' red; inhibitor arcs drawn
    // after (over) the others.
    let look = b
        .js(
            "const w = document.querySelector('.arc-weight');\
             const label = document.querySelector('.node text.label');\
             const paths = [...document.querySelectorAll('#arcs path')];\
             return [getComputedStyle(w).fill, getComputedStyle(label).fill,\
                     getComputedStyle(document.querySelector('.arc.inhibitor')).stroke,\
                     paths.map(p => p.classList.contains('inhibitor'))];",
            vec![],
        )
        .await;
    assert_eq!(look[0], look[1], "arc weight colour = label colour: {look}");
    assert_ne!(
        look[0], look[2],
        "arc weight colour != inhibitor colour: {look}"
    );
    assert_eq!(look[3], json!([false, false, false, false, true]));

    // 250 firings: the trace keeps the last 200 and says so; numbers up to 250 in full.
    let n = b.client.find(Locator::Id("n")).await.unwrap();
    n.clear().await.unwrap();
    n.send_keys("250").await.unwrap();
    b.click("#step-n").await;
    wait_firings(&b, 250).await;
    assert_eq!(b.text("#trace-count").await, "last 200 of 250");
    let state: Value = b
        .js(
            "return fetch('/api/sim/state').then(r => r.json());",
            vec![],
        )
        .await;
    let trace = trace_texts(&b, false).await;
    assert_eq!(trace.len(), 200);
    let last = &state["trace"][199];
    assert_eq!(last["step"], 250);
    // Step number, then the time to the microsecond (not `2.6790000000000003`); every
    // digit the server sent in the line's tooltip.
    let time = last["time"].as_f64().unwrap();
    let short: f64 = format!("{time:.6}").parse().unwrap();
    let want = format!("250{short}  {}", last["transition"].as_str().unwrap());
    assert!(
        trace[199].starts_with(&want),
        "{:?} vs {want:?}",
        trace[199]
    );
    assert!(
        format!("{time}").len() > format!("{short}").len(),
        "a time with more digits than shown: {time}"
    );
    let title = b
        .js(
            "return document.querySelector('#trace li:last-child').title;",
            vec![],
        )
        .await;
    assert_eq!(title, json!(format!("time {time}")));
    let seq = b
        .js(
            "const s = document.querySelector('#trace li:last-child .seq');\
             return [s.textContent, s.scrollWidth <= s.clientWidth];",
            vec![],
        )
        .await;
    assert_eq!(seq, json!(["250", true]), "the step number is not cut");

    // Scrolled to the top, a step leaves the list there; at the bottom it follows.
    b.js("document.getElementById('trace').scrollTop = 0;", vec![])
        .await;
    b.click("#step").await;
    wait_firings(&b, 251).await;
    let top = b
        .js("return document.getElementById('trace').scrollTop;", vec![])
        .await;
    assert_eq!(top, json!(0));
    b.js(
        "const o = document.getElementById('trace'); o.scrollTop = o.scrollHeight;",
        vec![],
    )
    .await;
    b.click("#step").await;
    wait_firings(&b, 252).await;
    let bottom = b
        .js(
            "const o = document.getElementById('trace');\
             return o.scrollTop + o.clientHeight >= o.scrollHeight - 4;",
            vec![],
        )
        .await;
    assert_eq!(bottom, json!(true));

    // The filter keeps the lines naming t1: every other firing.
    let f = b.client.find(Locator::Id("trace-filter")).await.unwrap();
    f.send_keys("t1 ").await.unwrap();
    let shown = trace_texts(&b, true).await;
    let want = state["trace"].as_array().unwrap().len();
    assert!(
        !shown.is_empty() && shown.len() < want,
        "{} of {want}",
        shown.len()
    );
    assert!(shown.iter().all(|l| l.contains("t1 ")), "{shown:?}");
    b.screenshot(&screenshot_path("trace-filter.png")).await;
    f.clear().await.unwrap();
    b.js(
        "document.getElementById('trace-filter').dispatchEvent(new Event('input'));",
        vec![],
    )
    .await;
    assert_eq!(trace_texts(&b, true).await.len(), 200);

    // Keys: `?` opens the list of shortcuts, `s` steps.
    b.js("document.activeElement.blur();", vec![]).await;
    let body = b.client.find(Locator::Css("body")).await.unwrap();
    body.send_keys("?").await.unwrap();
    let help = b.text("#help").await;
    assert!(help.contains("step") && help.contains("fit"), "{help}");
    b.screenshot(&screenshot_path("shortcuts.png")).await;
    let before = firings(&b).await;
    body.send_keys("s").await.unwrap();
    wait_firings(&b, before + 1).await;
    body.send_keys("\u{E00C}").await.unwrap(); // Escape
    let hidden = b
        .js(
            "return document.getElementById('help').classList.contains('hidden');",
            vec![],
        )
        .await;
    assert_eq!(hidden, json!(true));

    // A resize fits the net again (the view was the fitted one).
    let k0 = b.js("return view.k;", vec![]).await.as_f64().unwrap();
    b.client.set_window_size(700, 800).await.unwrap();
    b.wait_js(
        &format!("return view.k < {k0} * 0.9;"),
        WAIT,
        "a re-fit after the resize",
    )
    .await;
    b.client.set_window_size(1200, 800).await.unwrap();

    // The dark theme.
    b.client
        .goto(&format!("http://{addr}/?theme=dark"))
        .await
        .unwrap();
    b.wait_js(
        "return window.gspnPerf && window.gspnPerf.drawn;",
        WAIT,
        "the first drawing",
    )
    .await;
    let bg = b
        .js(
            "const c = getComputedStyle(document.body).backgroundColor.match(/\\d+/g).map(Number);\
             return c[0] + c[1] + c[2];",
            vec![],
        )
        .await;
    assert!(bg.as_u64().unwrap() < 150, "a dark background: {bg}");
    b.screenshot(&screenshot_path("dark.png")).await;
    b.close().await;
    server.abort();
}
