//! The whole net as a PDF (the header's `PDF`, `window.gspnExport.pdf()`): a file another
//! PDF reader (`lopdf`) parses, one page the size of the whole-net SVG export, every node
//! drawn once and every name in its text — on the thesis patrol (SVG-drawn) and on a
//! 10,000-place ring (canvas-drawn, a page past PDF's 14,400-unit side: `/UserUnit`).
#![cfg(feature = "web")]

use crate::browser::{BROWSER, PATROL, open, screenshot_path};
use crate::support as common;
use crate::support::browser::Browser;
use crate::support::start_server;

use std::collections::{BTreeMap, BTreeSet};

use gspn::io::{ReadOptions, read_net};
use gspn::net::{Net, Servers};
use gspn::web::WebState;
use lopdf::content::Content;
use lopdf::{Document, Object};

/// What the test reads from one exported PDF.
struct Pdf {
    bytes: Vec<u8>,
    doc: Document,
    /// The page's drawing, decoded by lopdf.
    content: Content,
    /// The page's `MediaBox` times its `UserUnit`: its size in the net's units.
    size: (f64, f64),
    user_unit: f64,
}

impl Pdf {
    /// The page's PDF, read back through lopdf.
    async fn of(b: &Browser) -> Pdf {
        let text = b.js("return window.gspnExport.pdf();", vec![]).await;
        let bytes: Vec<u8> = text
            .as_str()
            .expect("a binary string")
            .chars()
            .map(|c| u8::try_from(u32::from(c)).expect("one byte a char"))
            .collect();
        let doc = Document::load_mem(&bytes).expect("lopdf parses the PDF");
        let pages = doc.get_pages();
        assert_eq!(pages.len(), 1, "one page");
        let page_id = pages[&1];
        let page = doc.get_dictionary(page_id).unwrap();
        let number = |o: &Object| o.as_float().map(f64::from).unwrap();
        let user_unit = page.get(b"UserUnit").map_or(1.0, number);
        let media: Vec<f64> = page
            .get(b"MediaBox")
            .unwrap()
            .as_array()
            .unwrap()
            .iter()
            .map(number)
            .collect();
        assert_eq!(media[..2], [0.0, 0.0]);
        let content = Content::decode(&doc.get_page_content(page_id)).unwrap();
        Pdf {
            bytes,
            doc,
            content,
            size: (media[2] * user_unit, media[3] * user_unit),
            user_unit,
        }
    }

    /// How many times each operator is used.
    fn operators(&self) -> BTreeMap<&str, usize> {
        let mut n = BTreeMap::new();
        for op in &self.content.operations {
            *n.entry(op.operator.as_str()).or_insert(0) += 1;
        }
        n
    }

    /// Every string the page shows (`Tj`), in order.
    fn shown(&self) -> Vec<String> {
        self.content
            .operations
            .iter()
            .filter(|op| op.operator == "Tj")
            .map(|op| match &op.operands[0] {
                Object::String(s, _) => String::from_utf8_lossy(s).into_owned(),
                other => panic!("Tj of {other:?}"),
            })
            .collect()
    }
}

/// The whole-net SVG export's `width` and `height`.
async fn whole_svg_size(b: &Browser) -> (f64, f64) {
    let size = b
        .js(
            "const s = window.gspnExport.svg(true);\
             const d = new DOMParser().parseFromString(s, 'image/svg+xml').documentElement;\
             return [Number(d.getAttribute('width')), Number(d.getAttribute('height'))];",
            vec![],
        )
        .await;
    (size[0].as_f64().unwrap(), size[1].as_f64().unwrap())
}

/// Keeps a PDF beside the screenshots, to look at.
fn keep(name: &str, bytes: &[u8]) {
    let path = screenshot_path(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, bytes).unwrap();
}

fn names(net: &Net) -> BTreeSet<String> {
    net.places()
        .iter()
        .map(|p| p.name.clone())
        .chain(net.transitions().iter().map(|t| t.name.clone()))
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_whole_net_exports_as_a_vector_pdf_that_another_reader_parses() {
    let _one = BROWSER.lock().await;
    let net = read_net(&common::fixture(PATROL), &ReadOptions::default())
        .unwrap()
        .net;
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0)).await;
    let b = Browser::start(1280, 800).await;
    open(&b, addr).await;
    let pdf = Pdf::of(&b).await;
    assert!(pdf.bytes.starts_with(b"%PDF-1.6\n"));
    assert!(pdf.bytes.ends_with(b"%%EOF\n"));
    assert_eq!(pdf.user_unit, 1.0);
    assert_eq!(
        pdf.size,
        whole_svg_size(&b).await,
        "the page is the whole net"
    );
    let ops = pdf.operators();
    let inhibitors = net
        .arcs()
        .iter()
        .filter(|a| a.kind == gspn::net::ArcKind::Inhibitor)
        .count();
    // One stroke per arc; a box per transition and the background; four Bézier quarters per
    // place and per inhibitor head.
    assert_eq!(ops["S"], net.arcs().len());
    assert_eq!(ops["re"], net.transition_count() + 1);
    assert_eq!(ops["c"], 4 * (net.place_count() + inhibitors));
    let shown: BTreeSet<String> = pdf.shown().into_iter().collect();
    let missing: Vec<_> = names(&net).difference(&shown).cloned().collect();
    assert!(missing.is_empty(), "names not in the PDF: {missing:?}");
    // A rate in Symbol's λ (`l`) and Helvetica's digits.
    assert!(pdf.bytes.windows(13).any(|w| w == b"/F3 10 Tf (l)"));
    // lopdf's own text extraction (fonts and encodings) finds the names too.
    let text = pdf.doc.extract_text(&[1]).unwrap();
    for p in net.places() {
        assert!(
            text.contains(&p.name),
            "{} not in the extracted text",
            p.name
        );
    }
    keep("export-patrol.pdf", &pdf.bytes);
    b.close().await;
    server.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_ten_thousand_place_ring_exports_as_one_pdf_page_with_every_node() {
    let _one = BROWSER.lock().await;
    let net = common::ring(10_000, |i| u32::from(i % 10 == 0), |_| 1.0, Servers::Single).0;
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0)).await;
    let b = Browser::start(1280, 800).await;
    open(&b, addr).await;
    let on_canvas = b
        .js(
            "return getComputedStyle(document.getElementById('net-canvas')).display;",
            vec![],
        )
        .await;
    assert_eq!(on_canvas, "block");
    let pdf = Pdf::of(&b).await;
    let (w, h) = whole_svg_size(&b).await;
    // The page's size in the net's units is the whole net's (to the two decimals written).
    assert!(
        (pdf.size.0 - w).abs() < 0.01 * pdf.user_unit,
        "{:?} vs {w}",
        pdf.size
    );
    assert!(
        (pdf.size.1 - h).abs() < 0.01 * pdf.user_unit,
        "{:?} vs {h}",
        pdf.size
    );
    assert_eq!(
        pdf.user_unit > 1.0,
        w.max(h) > 14_400.0,
        "UserUnit {} for a net of {w} × {h}",
        pdf.user_unit
    );
    let ops = pdf.operators();
    assert_eq!(ops["S"], 20_000, "one stroke per arc");
    assert_eq!(ops["re"], 10_001, "a box per transition and the background");
    assert_eq!(ops["c"], 40_000, "four quarters per place");
    let shown = pdf.shown();
    // The names, and a `1` in each of the 1,000 marked places.
    assert_eq!(shown.iter().filter(|s| *s == "1").count(), 1_000);
    let shown: BTreeSet<String> = shown.into_iter().collect();
    let missing: Vec<_> = names(&net).difference(&shown).take(5).cloned().collect();
    assert!(missing.is_empty(), "names not in the PDF: {missing:?}…");
    keep("export-ring-10000.pdf", &pdf.bytes);
    b.close().await;
    server.abort();
}
