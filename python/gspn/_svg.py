"""A net drawn as SVG (Jupyter shows a :class:`gspn.Net` with it): the viewer's layout —
the file's positions when every node has one, else the layered layout — places as circles
with their tokens, transitions as bars (immediate: thin and black), arcs with arrowheads
(inhibitors: a small circle)."""

from __future__ import annotations

from html import escape
from typing import Any

R = 14.0  # place radius
TW, TH = 8.0, 28.0  # transition bar


def net_svg(net: Any, layout: dict[str, Any]) -> str:
    places = [tuple(p) for p in layout["places"]]
    transitions = [tuple(t) for t in layout["transitions"]]
    xs = [x for x, _ in places + transitions] or [0.0]
    ys = [y for _, y in places + transitions] or [0.0]
    x0, y0 = min(xs) - 60, min(ys) - 50
    w, h = max(xs) - x0 + 60, max(ys) - y0 + 50
    index_p = {p.name: i for i, p in enumerate(net.places)}
    index_t = {t.name: i for i, t in enumerate(net.transitions)}
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0:.1f} {y0:.1f} {w:.1f} {h:.1f}" '
        f'width="{min(w, 960):.0f}" font-family="sans-serif" font-size="11">',
        '<defs><marker id="a" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,0L10,5L0,10z"/></marker></defs>',
    ]
    for arc, bends in zip(net.arcs, layout["arcs"]):
        p = places[index_p[arc.place]]
        t = transitions[index_t[arc.transition]]
        src, dst = (t, p) if arc.kind == "output" else (p, t)
        pts = [src] + [tuple(b) for b in bends] + [dst]
        head = ' marker-end="url(#a)"' if arc.kind != "inhibitor" else ""
        path = " ".join(f"{x:.1f},{y:.1f}" for x, y in pts)
        out.append(f'<polyline points="{path}" fill="none" stroke="#555"{head}/>')
        if arc.kind == "inhibitor":
            out.append(f'<circle cx="{t[0] - TW:.1f}" cy="{t[1]:.1f}" r="4" fill="white" stroke="#555"/>')
        if arc.weight > 1:
            mx, my = pts[len(pts) // 2 - 1]
            nx, ny = pts[len(pts) // 2]
            out.append(f'<text x="{(mx + nx) / 2:.1f}" y="{(my + ny) / 2 - 3:.1f}">{arc.weight}</text>')
    for place, (x, y) in zip(net.places, places):
        out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{R}" fill="white" stroke="black"/>')
        if place.initial:
            out.append(f'<text x="{x:.1f}" y="{y + 4:.1f}" text-anchor="middle">{place.initial}</text>')
        out.append(f'<text x="{x:.1f}" y="{y + R + 12:.1f}" text-anchor="middle">{escape(place.name)}</text>')
    for t, (x, y) in zip(net.transitions, transitions):
        fill = "black" if t.kind == "immediate" else "white"
        bw = TW / 2 if t.kind == "immediate" else TW
        out.append(
            f'<rect x="{x - bw / 2:.1f}" y="{y - TH / 2:.1f}" width="{bw:.1f}" height="{TH}" '
            f'fill="{fill}" stroke="black"/>'
        )
        out.append(f'<text x="{x:.1f}" y="{y - TH / 2 - 4:.1f}" text-anchor="middle">{escape(t.name)}</text>')
    out.append("</svg>")
    return "".join(out)
