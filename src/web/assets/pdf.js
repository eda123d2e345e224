// gspn viewer, PDF export: the whole net as a one-page vector PDF, written here from the
// net's data with the primitives of the SVG export (`vectorSvg` in share.js): arcs as
// polylines with their heads, places as circles with their token counts, transitions as
// boxes, names and rates as text in the standard Helvetica (and Symbol for λ, π and ∞), so
// the file embeds no font and the page loads nothing. One drawing unit is one point; a net
// larger than a PDF page may be (14,400 units a side) is drawn smaller and the page says
// so with `/UserUnit`, which keeps it at full size in a viewer.
//
// Test hook: window.gspnExport.pdf() gives the PDF as a binary string (one byte a char).
'use strict';

// Largest page side, in units of 1/72 inch (PDF 1.6's implementation limit).
const PDF_MAX = 14400;

// `#rgb`, `#rrggbb` or `rgb(r, g, b)` as PDF's `r g b` in 0..1.
function pdfRgb(css) {
  const s = css.trim();
  let v = null;
  if (/^#[0-9a-f]{3}$/i.test(s)) v = [1, 2, 3].map((i) => parseInt(s[i] + s[i], 16));
  else if (/^#[0-9a-f]{6}$/i.test(s)) v = [1, 3, 5].map((i) => parseInt(s.slice(i, i + 2), 16));
  else {
    const m = s.match(/rgba?\(\s*(\d+)[ ,]+(\d+)[ ,]+(\d+)/);
    v = m ? [m[1], m[2], m[3]].map(Number) : [0, 0, 0];
  }
  return v.map((c) => pdfNum(c / 255)).join(' ');
}

// A number as PDF writes it: at most two decimals, never an exponent.
function pdfNum(x) {
  const r = Math.round(x * 100) / 100;
  return Object.is(r, -0) ? '0' : String(r);
}

// Characters of Symbol the names and rates use, by their code in that font.
const PDF_SYMBOL = { 'λ': 'l', 'π': 'p', '∞': '\xa5' };

// A text as runs of [font, PDF string]: Symbol for λ, π, ∞; Helvetica (WinAnsi, which is
// Latin-1 from U+00A0 on) for the rest, '?' for what it cannot show.
function pdfRuns(text, font) {
  const runs = [];
  for (const ch of text) {
    const sym = PDF_SYMBOL[ch];
    const f = sym ? '/F3' : font;
    let c = sym || ch;
    const code = c.charCodeAt(0);
    if (!sym && (code > 0xff || (code >= 0x7f && code < 0xa0) || code < 0x20)) c = '?';
    if (c === '(' || c === ')' || c === '\\') c = '\\' + c;
    if (runs.length && runs[runs.length - 1][0] === f) runs[runs.length - 1][1] += c;
    else runs.push([f, c]);
  }
  return runs;
}

// Measures text as the PDF's Helvetica will set it (Arial has Helvetica's widths).
let pdfMeasure = null;
function pdfTextWidth(text, size, bold) {
  if (!pdfMeasure) pdfMeasure = document.createElement('canvas').getContext('2d');
  pdfMeasure.font = (bold ? '600 ' : '') + size + 'px Helvetica, Arial, sans-serif';
  return pdfMeasure.measureText(text).width;
}

// Writes the drawing's operators; y grows downwards as on the page (the page's matrix
// turns it over), so text is set with its own matrix turned back.
class PdfPage {
  constructor() {
    this.ops = [];
  }
  fill(rgb) {
    this.ops.push(rgb + ' rg');
  }
  stroke(rgb, width) {
    this.ops.push(rgb + ' RG ' + pdfNum(width) + ' w');
  }
  polyline(pts) {
    this.ops.push(pts.map((q, k) => pdfNum(q[0]) + ' ' + pdfNum(q[1]) + (k ? ' l' : ' m')).join(' ') + ' S');
  }
  polygon(pts) {
    this.ops.push(pts.map((q, k) => pdfNum(q[0]) + ' ' + pdfNum(q[1]) + (k ? ' l' : ' m')).join(' ') + ' h f');
  }
  // A circle of four Bézier quarters; `op` is `B` (fill and stroke) or `f`.
  circle(cx, cy, r, op) {
    const k = 0.5523 * r;
    const p = (x, y) => pdfNum(cx + x) + ' ' + pdfNum(cy + y);
    this.ops.push(p(r, 0) + ' m ' +
      p(r, k) + ' ' + p(k, r) + ' ' + p(0, r) + ' c ' +
      p(-k, r) + ' ' + p(-r, k) + ' ' + p(-r, 0) + ' c ' +
      p(-r, -k) + ' ' + p(-k, -r) + ' ' + p(0, -r) + ' c ' +
      p(k, -r) + ' ' + p(r, -k) + ' ' + p(r, 0) + ' c ' + op);
  }
  rect(x, y, w, h, op) {
    this.ops.push([x, y, w, h].map(pdfNum).join(' ') + ' re ' + op);
  }
  // `anchor`: 'middle' centres the text on x, 'start' begins it there; y is its baseline.
  text(str, x, y, size, anchor, bold) {
    const x0 = anchor === 'middle' ? x - pdfTextWidth(str, size, bold) / 2 : x;
    const runs = pdfRuns(str, bold ? '/F2' : '/F1');
    this.ops.push('BT 1 0 0 -1 ' + pdfNum(x0) + ' ' + pdfNum(y) + ' Tm ' +
      runs.map(([f, s]) => f + ' ' + size + ' Tf (' + s + ') Tj').join(' ') + ' ET');
  }
}

// The head of an arc ending at `q` coming from `p`: a triangle 9.6 units long (the SVG's
// 8-unit marker scaled by the arc's 1.2 width).
function arrowHead(p, q) {
  const dx = q[0] - p[0];
  const dy = q[1] - p[1];
  const d = Math.hypot(dx, dy) || 1;
  const [ux, uy] = [dx / d, dy / d];
  const [l, h] = [9.6, 4.8];
  return [q, [q[0] - ux * l - uy * h, q[1] - uy * l + ux * h], [q[0] - ux * l + uy * h, q[1] - uy * l - ux * h]];
}

// The drawing of the whole net as content-stream operators, in the net's units.
function pdfDrawing(b) {
  const vars = getComputedStyle(document.documentElement);
  const colour = (name) => pdfRgb(vars.getPropertyValue(name));
  const page = new PdfPage();
  page.fill(colour('--bg'));
  page.rect(b.x0, b.y0, b.w, b.h, 'f');
  // Normal arcs first, inhibitor arcs over them (as on the page).
  const order = net.arcs.map((a, i) => i);
  order.sort((i, j) => (net.arcs[i].kind === 'inhibitor') - (net.arcs[j].kind === 'inhibitor'));
  for (const i of order) {
    const a = net.arcs[i];
    const pts = arcPoints(i);
    const n = pts.length;
    const inhib = a.kind === 'inhibitor';
    page.stroke(colour(inhib ? '--inhib' : '--arc'), 1.2);
    page.polyline(pts);
    if (inhib) {
      page.fill(colour('--bg'));
      page.stroke(colour('--inhib'), 1.5);
      const [p, q] = [pts[n - 2], pts[n - 1]];
      const d = Math.hypot(q[0] - p[0], q[1] - p[1]) || 1;
      page.circle(q[0] - ((q[0] - p[0]) / d) * 4, q[1] - ((q[1] - p[1]) / d) * 4, 4, 'B');
    } else {
      page.fill(colour('--arc'));
      page.polygon(arrowHead(pts[n - 2], pts[n - 1]));
    }
    if (a.weight > 1) {
      const m = Math.floor((n - 1) / 2);
      page.fill(colour('--fg'));
      page.text(String(a.weight), (pts[m][0] + pts[m + 1][0]) / 2 + 4, (pts[m][1] + pts[m + 1][1]) / 2 - 4, 11, 'start', true);
    }
  }
  net.places.forEach((p, i) => {
    page.fill(colour('--node'));
    page.stroke(colour('--stroke'), 1.5);
    page.circle(p.x, p.y, R, 'B');
    page.fill(colour('--fg'));
    if (placeTokens[i] > 0) page.text(String(placeTokens[i]), p.x, p.y + 4.5, 13, 'middle', true);
    page.text(p.name, p.x, p.y + R + 13, 11, 'middle');
  });
  for (const t of net.transitions) {
    const [hw, hh] = transitionHalf(t);
    page.fill(colour(t.kind === 'immediate' ? '--stroke' : '--node'));
    page.stroke(colour('--stroke'), 1.5);
    page.rect(t.x - hw, t.y - hh, 2 * hw, 2 * hh, 'B');
    page.fill(colour('--fg'));
    page.text(t.name, t.x, t.y + hh + 13, 11, 'middle');
    page.fill(colour('--muted'));
    page.text(paramText(t), t.x, t.y - hh - 5, 10, 'middle');
  }
  return page.ops.join('\n');
}

// The whole net as a PDF file: a binary string, one byte per char.
function exportPdf() {
  const b = netBounds();
  const [w, h] = [Math.ceil(b.w), Math.ceil(b.h)];
  // Past PDF_MAX the page is drawn k times smaller and says so with /UserUnit k (k to the
  // two decimals it is written with).
  const k = Math.max(1, Math.ceil((Math.max(w, h) / PDF_MAX) * 100) / 100);
  const s = 1 / k;
  // Net units to the page's: x - x0, and y turned over from the page's top.
  const matrix = [s, 0, 0, -s, -b.x0 * s, (h + b.y0) * s].map((v) => String(Math.round(v * 1e6) / 1e6));
  const content = matrix.join(' ') + ' cm\n1 J 1 j\n' + pdfDrawing(b) + '\n';
  const pageBox = '[0 0 ' + pdfNum(w / k) + ' ' + pdfNum(h / k) + ']';
  const objects = [
    '<< /Type /Catalog /Pages 2 0 R >>',
    '<< /Type /Pages /Kids [3 0 R] /Count 1 >>',
    '<< /Type /Page /Parent 2 0 R /MediaBox ' + pageBox + (k > 1 ? ' /UserUnit ' + pdfNum(k) : '') +
      ' /Resources << /Font << /F1 4 0 R /F2 5 0 R /F3 6 0 R >> >> /Contents 7 0 R >>',
    '<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica /Encoding /WinAnsiEncoding >>',
    '<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica-Bold /Encoding /WinAnsiEncoding >>',
    '<< /Type /Font /Subtype /Type1 /BaseFont /Symbol >>',
    '<< /Length ' + content.length + ' >>\nstream\n' + content + 'endstream',
    '<< /Producer (gspn viewer) /Title (' + pdfRuns(net.name || 'net', '').map((r) => r[1]).join('') + ') >>',
  ];
  // Binary marker line: tells tools the file holds bytes past ASCII.
  let out = '%PDF-1.6\n%\xe2\xe3\xcf\xd3\n';
  const offsets = [];
  objects.forEach((o, i) => {
    offsets.push(out.length);
    out += (i + 1) + ' 0 obj\n' + o + '\nendobj\n';
  });
  const xref = out.length;
  out += 'xref\n0 ' + (objects.length + 1) + '\n0000000000 65535 f \n' +
    offsets.map((o) => String(o).padStart(10, '0') + ' 00000 n \n').join('');
  out += 'trailer\n<< /Size ' + (objects.length + 1) + ' /Root 1 0 R /Info ' + objects.length + ' 0 R >>\nstartxref\n' + xref + '\n%%EOF\n';
  return out;
}

function downloadPdf() {
  const text = exportPdf();
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  const url = URL.createObjectURL(new Blob([bytes], { type: 'application/pdf' }));
  download(url, (net ? net.name : 'net') + '.pdf');
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}
