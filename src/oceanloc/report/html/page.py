"""One self-contained HTML page from a :class:`Report`: plotly figures, tables, provenance, nothing fetched.

plotly's JavaScript bundle is written once into the page's ``<head>``; each figure is a ``<div>`` with a
``Plotly.newPlot`` call (``include_plotlyjs=False``); every style is inline. A Content-Security-Policy
``default-src 'none'`` forbids the page any request: it works on a boat with no network, and a browser
reports any attempt as an error (which the browser tests look for).

The map is east-north in metres at equal scale with a scale bar; where the frame is georeferenced the
hover gives latitude and longitude. Each estimate has its 95 % ellipse drawn to scale; when the largest
ellipse is under 1 % of the map's extent, an inset draws every ellipse magnified about its estimate.
The drawn track is thinned to at most :data:`MAX_TRACK_POINTS` points (the data is not).
"""

from __future__ import annotations

import html
import json
import math

import numpy as np
import plotly.graph_objects as go
from plotly.offline import get_plotlyjs

from oceanloc.geo.enu import enu_to_geodetic
from oceanloc.report.html.model import MapLayers, Report, Series

MAX_TRACK_POINTS = 5000
"""Track points drawn at most (evenly strided, first and last kept)."""
MAX_RANGE_SEGMENTS = 600
"""Range segments drawn at most."""
MAX_SERIES_MARKERS = 2000
"""A markers line of more points is drawn as its extent per time bin (see :func:`series_figure`)."""
SERIES_BINS = 1000
"""Bins of such a line (about one per pixel column of a report's panel)."""
INSET_FRACTION = 0.01
"""Draw the magnified inset when the largest ellipse's semi-major axis is below this share of the map."""

COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")
_PLOT_CONFIG = {"displaylogo": False, "responsive": True, "scrollZoom": True}

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:1.2em auto;max-width:1180px;
color:#222;padding:0 1em}
h1{font-size:1.4em}h2{font-size:1.15em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
td,th{border:1px solid #ccc;padding:.25em .5em;text-align:left;vertical-align:top}
th{background:#f2f2f2}td.num{text-align:right;font-variant-numeric:tabular-nums}
tr.pass td.verdict{color:#106010;font-weight:bold}tr.fail td.verdict{color:#b00000;font-weight:bold}
.summary li{margin:.15em 0}.note{color:#555;font-size:.9em}code{font-size:.9em}
dl{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}dt{font-weight:bold}dd{margin:0}
"""

CSP = (
    "default-src 'none'; script-src 'unsafe-inline' 'unsafe-eval'; style-src 'unsafe-inline'; "
    "img-src data: blob:; font-src data:"
)


def _thin(n: int, limit: int) -> np.ndarray:
    """Indices of at most ``limit`` of ``n`` points, evenly strided, first and last kept."""
    if n <= limit:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, limit).round().astype(np.int64))


def _nice_length(span_m: float) -> float:
    """A 1-2-5 length near a fifth of ``span_m``."""
    target = max(span_m / 5.0, 1e-3)
    base = 10.0 ** math.floor(math.log10(target))
    return max(m * base for m in (1.0, 2.0, 5.0) if m * base <= target)


def _format_length(m: float) -> str:
    if m >= 1000.0:
        return f"{m / 1000:g} km"
    if m >= 1.0:
        return f"{m:g} m"
    return f"{m * 100:g} cm"


def _hover_geo(layers: MapLayers, en: np.ndarray) -> tuple[np.ndarray | None, str]:
    """customdata (lat, lon) and the hover template part, where the frame is georeferenced."""
    if layers.origin is None or en.size == 0:
        return None, ""
    enu = np.concatenate([en, np.zeros((en.shape[0], 1))], axis=1)
    geo = enu_to_geodetic(enu, layers.origin).reshape(-1, 3)
    return geo[:, :2], "<br>lat %{customdata[0]:.7f}°, lon %{customdata[1]:.7f}°"


def map_figure(layers: MapLayers) -> go.Figure:
    """The map: track, ranges, sites, legs, circles, obstacles, estimates and their 95 % ellipses."""
    fig = go.Figure()
    hover_en = "E %{x:.3f} m, N %{y:.3f} m"
    pts = [layers.track_en_m, layers.sites_en_m]
    pts += [np.array([[e.east_m, e.north_m]]) for e in layers.estimates]
    pts += [leg for _, leg in layers.legs] + [poly for _, poly in layers.polygons]
    allpts = np.concatenate([p.reshape(-1, 2) for p in pts if p.size]) if any(p.size for p in pts) else None
    if allpts is not None:
        allpts = allpts[np.isfinite(allpts).all(axis=1)]
        allpts = allpts if allpts.size else None
    if layers.current is not None and layers.current.size:
        q = layers.current
        span = float(np.ptp(q[:, 0])) if allpts is None else float(np.ptp(allpts[:, 0]))
        speed = np.hypot(q[:, 2], q[:, 3])
        scale = 0.04 * span / max(float(speed.max()), 1e-9)
        xs, ys = [], []
        for e, n, u, v in q:
            xs += [e, e + scale * u, None]
            ys += [n, n + scale * v, None]
        fig.add_trace(
            go.Scatter(
                x=xs,
                y=ys,
                mode="lines",
                name="current",
                line={"color": "#9ecae1", "width": 1},
                hoverinfo="skip",
            )
        )
    for j, (label, poly) in enumerate(layers.polygons):
        ring = np.vstack([poly, poly[:1]])
        fig.add_trace(
            go.Scatter(
                x=ring[:, 0],
                y=ring[:, 1],
                mode="lines",
                fill="toself",
                name=label,
                legendgroup="obstacles",
                showlegend=j == 0,
                line={"color": "#555"},
                fillcolor="rgba(80,80,80,0.35)",
                hoverinfo="name",
            )
        )
    for c in layers.circles:
        t = np.linspace(0, 2 * np.pi, 73)
        fig.add_trace(
            go.Scatter(
                x=c.east_m + c.radius_m * np.cos(t),
                y=c.north_m + c.radius_m * np.sin(t),
                mode="lines",
                name=c.label,
                line={"color": "#7f7f7f", "dash": "dot"},
                hovertemplate=f"{html.escape(c.label)}: radius {c.radius_m:.1f} m<extra></extra>",
            )
        )
    if layers.range_segments_en_m.size:
        seg = layers.range_segments_en_m[_thin(layers.range_segments_en_m.shape[0], MAX_RANGE_SEGMENTS)]
        xs = np.column_stack([seg[:, 0, 0], seg[:, 1, 0], np.full(seg.shape[0], np.nan)]).ravel()
        ys = np.column_stack([seg[:, 0, 1], seg[:, 1, 1], np.full(seg.shape[0], np.nan)]).ravel()
        fig.add_trace(
            go.Scatter(
                x=xs,
                y=ys,
                mode="lines",
                name=f"ranges as taken ({seg.shape[0]} drawn)",
                line={"color": "rgba(255,127,14,0.25)", "width": 1},
                hoverinfo="skip",
            )
        )
    if layers.track_en_m.size:
        idx = _thin(layers.track_en_m.shape[0], MAX_TRACK_POINTS)
        tr = layers.track_en_m[idx]
        geo, geo_tpl = _hover_geo(layers, tr)
        name = layers.track_label
        thinned = idx.size < layers.track_en_m.shape[0]
        if thinned:  # drawn as a light line, no marker per point, so the estimates stay visible
            name += f" ({idx.size} of {layers.track_en_m.shape[0]} points drawn)"
        fig.add_trace(
            go.Scatter(
                x=tr[:, 0],
                y=tr[:, 1],
                mode="lines" if thinned else "lines+markers",
                name=name,
                customdata=geo,
                marker={"size": 3, "color": "#1f77b4"},
                line={"color": "rgba(31,119,180,0.4)" if thinned else "#1f77b4", "width": 1},
                hovertemplate=f"track<br>{hover_en}{geo_tpl}<extra></extra>",
            )
        )
    for label, leg in layers.legs:
        color = "#d62728" if "flight" in label else "#2ca02c"
        fig.add_trace(
            go.Scatter(
                x=leg[:, 0],
                y=leg[:, 1],
                mode="lines",
                name=label,
                line={"color": color, "width": 3},
                hovertemplate=f"{html.escape(label)}<br>{hover_en}<extra></extra>",
            )
        )
    if layers.sites_en_m.size:
        s = layers.sites_en_m
        geo, geo_tpl = _hover_geo(layers, s)
        order = np.arange(1, s.shape[0] + 1)
        cd = order[:, None] if geo is None else np.column_stack([geo, order])
        k = 0 if geo is None else 2
        fig.add_trace(
            go.Scatter(
                x=s[:, 0],
                y=s[:, 1],
                mode="lines+markers+text" if layers.sites_connect else "markers+text",
                name=layers.sites_label,
                text=[str(i) if s.shape[0] <= 60 else "" for i in order],
                textposition="top center",
                textfont={"size": 9, "color": "#555"},
                customdata=cd,
                marker={"size": 7, "color": "#ff7f0e", "symbol": "circle-open"},
                line={"color": "#ff7f0e", "width": 1, "dash": "dot"},
                hovertemplate=f"site %{{customdata[{k}]}}<br>{hover_en}{geo_tpl}<extra></extra>",
            )
        )
    _estimates(fig, layers, allpts)
    fig.update_layout(
        height=640,
        margin={"l": 60, "r": 20, "t": 30, "b": 50},
        hovermode="closest",
        xaxis={"title": {"text": "east (m)"}, "zeroline": False},
        yaxis={"title": {"text": "north (m)"}, "scaleanchor": "x", "scaleratio": 1, "zeroline": False},
        legend={"orientation": "h", "y": -0.12},
        plot_bgcolor="#f7fbff",
    )
    if allpts is not None:
        _scale_bar(fig, allpts)
    return fig


def _estimates(fig: go.Figure, layers: MapLayers, allpts: np.ndarray | None) -> None:
    if not layers.estimates:
        return
    span = float(np.ptp(allpts, axis=0).max()) if allpts is not None and allpts.shape[0] > 1 else 0.0
    biggest = max(e.semi_major_m for e in layers.estimates)
    inset = span > 0 and biggest < INSET_FRACTION * span
    for i, e in enumerate(layers.estimates):
        color = COLORS[i % len(COLORS)]
        ring = e.ring_en_m()
        geo, geo_tpl = _hover_geo(layers, np.array([[e.east_m, e.north_m]]))
        detail = f"<br>{html.escape(e.detail)}" if e.detail else ""
        axes = f"95 % ellipse {e.semi_major_m:.3g} x {e.semi_minor_m:.3g} m"
        fig.add_trace(
            go.Scatter(
                x=ring[:, 0],
                y=ring[:, 1],
                mode="lines",
                name=f"95% ellipse {e.label}",
                legendgroup=e.label,
                showlegend=False,
                line={"color": color, "width": 2},
                fill="toself",
                fillcolor="rgba(0,0,0,0.05)",
                hovertemplate=f"{html.escape(e.label)}: {axes}<extra></extra>",
            )
        )
        fig.add_trace(
            go.Scatter(
                x=[e.east_m],
                y=[e.north_m],
                mode="markers",
                name=f"estimate {e.label}",
                legendgroup=e.label,
                customdata=geo,
                marker={"size": 9, "color": color, "symbol": "x"},
                hovertemplate=f"estimate {html.escape(e.label)}<br>E %{{x:.3f}} m, N %{{y:.3f}} m"
                f"{geo_tpl}<br>{axes}{detail}<extra></extra>",
            )
        )
        if e.truth_en_m is not None:
            fig.add_trace(
                go.Scatter(
                    x=[e.truth_en_m[0]],
                    y=[e.truth_en_m[1]],
                    mode="markers",
                    name=f"truth {e.label}",
                    legendgroup=e.label,
                    showlegend=False,
                    marker={"size": 8, "color": color, "symbol": "circle-open"},
                    hovertemplate=f"truth {html.escape(e.label)}<br>{'E %{x:.3f} m, N %{y:.3f} m'}"
                    "<extra></extra>",
                )
            )
        if inset:
            off = (ring - [e.east_m, e.north_m]) * 100.0
            fig.add_trace(
                go.Scatter(
                    x=off[:, 0],
                    y=off[:, 1],
                    mode="lines",
                    name=f"inset ellipse {e.label}",
                    legendgroup=e.label,
                    showlegend=False,
                    xaxis="x2",
                    yaxis="y2",
                    line={"color": color, "width": 2},
                    hovertemplate=f"{html.escape(e.label)}: dE %{{x:.1f}} cm, dN %{{y:.1f}} cm"
                    "<extra></extra>",
                )
            )
    if inset:
        fig.update_layout(
            xaxis={"domain": [0.0, 0.7]},
            xaxis2={
                "domain": [0.77, 1.0],
                "anchor": "y2",
                "title": {"text": "dE (cm)"},
                "mirror": True,
                "showline": True,
            },
            yaxis2={
                "domain": [0.45, 1.0],
                "anchor": "x2",
                "scaleanchor": "x2",
                "scaleratio": 1,
                "title": {"text": "dN (cm)", "standoff": 2},
                "mirror": True,
                "showline": True,
            },
        )
        fig.add_annotation(
            text="inset, magnified: 95 % ellipses<br>about each estimate, in cm;<br>"
            f"largest semi-major axis {biggest * 100:.1f} cm",
            xref="paper",
            yref="paper",
            x=0.77,
            y=0.33,
            xanchor="left",
            yanchor="top",
            showarrow=False,
            align="left",
            font={"size": 11},
        )


def _scale_bar(fig: go.Figure, pts: np.ndarray) -> None:
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-3))
    length = _nice_length(span)
    x0 = float(lo[0])
    fig.add_shape(
        type="line",
        xref="x",
        yref="paper",
        x0=x0,
        x1=x0 + length,
        y0=0.03,
        y1=0.03,
        line={"color": "black", "width": 4},
        name="scale bar",
    )
    fig.add_annotation(
        text=f"scale {_format_length(length)}",
        xref="x",
        yref="paper",
        x=x0 + length / 2,
        y=0.035,
        yanchor="bottom",
        showarrow=False,
        font={"size": 11},
    )


def extent_per_bin(x: np.ndarray, y: np.ndarray, bins: int, pad: float) -> tuple[np.ndarray, np.ndarray]:
    """A dense scatter as one vertical stroke per x bin, from its lowest to its highest y (NaN-separated).

    Every point lies on a stroke, so no extreme value is hidden; ``pad`` lengthens each stroke at both
    ends so a bin of one point still shows. Returns the stroke coordinates (``3 * used bins``).
    """
    keep = np.isfinite(x) & np.isfinite(y)
    order = np.argsort(x[keep], kind="stable")
    x, y = x[keep][order], y[keep][order]
    edges = np.linspace(x[0], x[-1], bins + 1)
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
    starts = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
    lo, hi = np.minimum.reduceat(y, starts) - pad, np.maximum.reduceat(y, starts) + pad
    mid = 0.5 * (edges[idx[starts]] + edges[idx[starts] + 1])
    gap = np.full(mid.size, np.nan)
    return np.column_stack([mid, mid, gap]).ravel(), np.column_stack([lo, hi, gap]).ravel()


def _unit(label: str) -> str:
    """The unit in an axis label's last parentheses (``time (s)`` -> ``s``), else empty."""
    return label.rsplit("(", 1)[-1].rstrip(")") if label.endswith(")") else ""


def series_figure(s: Series) -> go.Figure:
    """One time-series panel.

    A markers line of more than :data:`MAX_SERIES_MARKERS` numeric points and no per-point text (on a
    linear axis) is drawn as its extent per :data:`SERIES_BINS` time bins (:func:`extent_per_bin`, strokes
    at least 0.6 % of the axis span tall, about 2 px): one SVG path instead of a node per point, every
    extreme still visible. Other lines of over 20,000 points use WebGL.
    """
    fig = go.Figure()
    spans = [np.asarray(y, dtype=float) for _, _, y, _, _ in s.lines if np.asarray(y).size]
    finite = np.concatenate(spans)[np.isfinite(np.concatenate(spans))] if spans else np.zeros(0)
    pad = 0.003 * float(np.ptp(finite)) if finite.size else 0.0
    for i, (name, x, y, mode, hover) in enumerate(s.lines):
        x, y = np.asarray(x), np.asarray(y)
        n = x.size
        dense = mode == "markers" and hover is None and n > MAX_SERIES_MARKERS and not s.log_y
        if dense and x.dtype.kind in "fiu":
            width = float(np.ptp(x[np.isfinite(x)])) / SERIES_BINS
            x, y = extent_per_bin(x.astype(float), y.astype(float), SERIES_BINS, pad)
            name = f"{name} ({n} points, drawn as their extent per {width:.3g} {_unit(s.x_label)})".replace(
                "  ", " "
            )
            mode = "lines"
        cls = go.Scattergl if n > 20000 and mode != "lines" else go.Scatter
        fig.add_trace(
            cls(
                x=x,
                y=y,
                mode=mode,
                name=name,
                text=hover,
                marker=(
                    {"size": 7, "symbol": "x", "color": COLORS[i % len(COLORS)]}
                    if name.startswith("excluded")  # excluded pings stand out from the used ones
                    else {"size": 4, "color": COLORS[i % len(COLORS)]}
                ),
                line={"color": COLORS[i % len(COLORS)]},
                hovertemplate=(
                    f"{html.escape(name)}<br>%{{x}}: %{{y:.4g}}"
                    + ("<br>%{text}" if hover else "")
                    + "<extra></extra>"
                ),
            )
        )
    for label, lo, hi in s.bands:
        fig.add_hrect(
            y0=lo,
            y1=hi,
            fillcolor="rgba(44,160,44,0.12)",
            line_width=0,
            layer="below",
            annotation_text=label,
            annotation_position="top left",
        )
    fig.update_layout(
        title={"text": s.title},
        height=360,
        margin={"l": 60, "r": 20, "t": 40, "b": 45},
        xaxis={"title": {"text": s.x_label}},
        yaxis={"title": {"text": s.y_label}, "type": "log" if s.log_y else "linear"},
        legend={"orientation": "h", "y": -0.25},
        hovermode="closest",
    )
    return fig


_PLOTLY_TAGS = ("br", "b", "i", "em", "sup", "sub")
"""The markup plotly renders that a label may keep: line breaks and emphasis, no links, no styles."""


def plotly_text(text: str) -> str:
    """``text`` made safe for a plotly label: escaped, then only the bare tags of :data:`_PLOTLY_TAGS`
    restored. Plotly renders a subset of HTML in names, titles and annotations (links included), so a
    transponder id or file name holding ``<a href=...>`` would become a link in the legend."""
    out = html.escape(text, quote=False)
    for tag in _PLOTLY_TAGS:
        out = out.replace(f"&lt;{tag}&gt;", f"<{tag}>").replace(f"&lt;/{tag}&gt;", f"</{tag}>")
    return out


def _safe(value: object) -> object:
    if isinstance(value, str):
        return plotly_text(value)
    if isinstance(value, list | tuple | np.ndarray) and len(value) and isinstance(value[0], str):
        return [plotly_text(v) if isinstance(v, str) else v for v in value]
    return value


def sanitize_figure(fig: go.Figure) -> go.Figure:
    """Every text of ``fig`` that plotly renders as markup (trace names and texts, titles, axis titles,
    annotations) passed through :func:`plotly_text`; the one exit from figures to pages applies it."""
    for trace in fig.data:
        for key in ("name", "text", "hovertext"):
            if key in trace and trace[key] is not None:
                trace[key] = _safe(trace[key])
        title = getattr(trace, "legendgrouptitle", None)
        if title is not None and title.text:
            title.text = plotly_text(title.text)
    layout = fig.layout
    if layout.title and layout.title.text:
        layout.title.text = plotly_text(layout.title.text)
    for name in dir(layout):
        if name.startswith(("xaxis", "yaxis")):
            axis = getattr(layout, name, None)
            if axis is not None and getattr(axis, "title", None) is not None and axis.title.text:
                axis.title.text = plotly_text(axis.title.text)
    for note in layout.annotations or ():
        if note.text:
            note.text = plotly_text(note.text)
    return fig


def figure_div(fig: go.Figure, div_id: str) -> str:
    """A figure as a ``<div>`` and its ``Plotly.newPlot`` call (the bundle is in the head), its labels
    made safe (:func:`sanitize_figure`)."""
    return sanitize_figure(fig).to_html(
        full_html=False, include_plotlyjs=False, div_id=div_id, config=_PLOT_CONFIG
    )


def _table(header: tuple[str, ...], rows: tuple[tuple[str, ...], ...], table_id: str) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = []
    for r in rows:
        cells = "".join(
            f'<td class="num">{html.escape(c)}</td>' if _numeric(c) else f"<td>{html.escape(c)}</td>"
            for c in r
        )
        body.append(f"<tr>{cells}</tr>")
    return f'<table id="{table_id}"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'


def _numeric(text: str) -> bool:
    try:
        float(text.replace(",", "").split(" ")[0])
    except ValueError:
        return False
    return True


def _checks(report: Report) -> str:
    rows = []
    for c in report.checks:
        cls = "pass" if c.passed else "fail"
        rows.append(
            f'<tr class="check {cls}"><td>{html.escape(c.name)}</td>'
            f'<td class="num">{html.escape(c.value)}</td>'
            f'<td>{html.escape(c.bound)}</td><td class="verdict">{"pass" if c.passed else "FAIL"}</td>'
            f"<td>{html.escape(c.detail)}</td></tr>"
        )
    n_pass = sum(c.passed for c in report.checks)
    page = (
        f"<p>{n_pass} of {len(report.checks)} checks pass.</p>"
        '<table id="checks"><thead><tr><th>check</th><th>value</th><th>bound</th><th>verdict</th>'
        f"<th>detail</th></tr></thead><tbody>{''.join(rows)}</tbody></table>"
    )
    if not any(c.value or c.bound for c in report.checks):  # e.g. a reproduction: the detail says it all
        page = page.replace("<th>value</th><th>bound</th>", "").replace('<td class="num"></td><td></td>', "")
    return page


def _provenance(prov: dict) -> str:
    items = []
    for key in (
        "oceanloc_version",
        "command",
        "created_utc",
        "seed",
        "scenario",
        "scenario_sha256",
        "inputs",
    ):
        if key not in prov:
            continue
        value = prov[key]
        if key == "command" and isinstance(value, list):
            text = " ".join(str(v) for v in value)
        elif key == "inputs" and isinstance(value, list):
            text = (
                "; ".join(
                    f"{i.get('path', i)} sha256 {i.get('sha256', '?')}" if isinstance(i, dict) else str(i)
                    for i in value
                )
                or "none"
            )
        else:
            text = "none" if value is None else str(value)
        items.append(
            f"<dt>{html.escape(key.replace('_', ' '))}</dt><dd><code>{html.escape(text)}</code></dd>"
        )
    rest = {
        k: v
        for k, v in prov.items()
        if k
        not in {"oceanloc_version", "command", "created_utc", "seed", "scenario", "scenario_sha256", "inputs"}
    }
    for key, value in rest.items():
        text = json.dumps(value, sort_keys=True) if isinstance(value, dict | list) else str(value)
        items.append(f"<dt>{html.escape(key)}</dt><dd><code>{html.escape(text)}</code></dd>")
    return f'<dl id="provenance">{"".join(items)}</dl>'


def page_head(title: str, kind: str, *, csp: str = CSP, head_extra: str = "") -> str:
    """The page up to the ``<h1>``: CSP, style, plotly's bundle inline (shared by the live page)."""
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{csp}">'
        f'<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>{html.escape(title)}</title><style>{_CSS}</style>{head_extra}"
        f'<script type="text/javascript">{get_plotlyjs()}</script></head>'
        f'<body data-report-kind="{html.escape(kind)}"><h1>{html.escape(title)}</h1>'
    )


def render_html(report: Report) -> str:
    """The whole page as one string (about 4.7 MB of it is plotly's bundle)."""
    parts = [page_head(report.title, report.kind)]
    if report.summary:
        parts.append(
            '<ul class="summary">' + "".join(f"<li>{html.escape(s)}</li>" for s in report.summary) + "</ul>"
        )
    if report.map is not None:
        parts.append(
            '<h2>Map</h2><p class="note">East-north in metres about the frame\'s origin, equal '
            "scale; drag to pan, scroll to zoom, hover for values.</p>"
        )
        parts.append(figure_div(map_figure(report.map), "map"))
    checks = "<h2>Checks</h2>" + _checks(report) if report.checks else ""
    if report.map is None:  # a record of statistics: its checks are what a reader looks for first
        parts.append(checks)
    if report.series:
        parts.append("<h2>Time series</h2>")
        parts += [figure_div(series_figure(s), f"series-{i}") for i, s in enumerate(report.series)]
    if report.map is not None:
        parts.append(checks)
    for i, t in enumerate(report.tables):
        parts.append(f"<h2>{html.escape(t.title)}</h2>" + _table(t.header, t.rows, f"table-{i}"))
    if report.notes:
        parts.append("".join(f'<p class="note">{html.escape(n)}</p>' for n in report.notes))
    parts.append("<h2>Provenance</h2>" + _provenance(report.provenance))
    parts.append("</body></html>\n")
    return "".join(parts)
