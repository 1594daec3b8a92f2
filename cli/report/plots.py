"""Report plots as PNG bytes, drawn from a ``report.json`` document alone (matplotlib, Agg).

The figures use matplotlib's object API (``Figure`` + the Agg canvas, never ``pyplot``),
so they need no display and change no pyplot state. matplotlib's text layout (mathtext,
font caches) is still shared by the whole process, so :func:`make_plots` draws under
``shared_state.MATPLOTLIB_LOCK``: safe from the threads of a Dask worker.

- ``energy``: captured energy 1 − ε(F, P) against F for each P, with the environments'
  1 − ε_L(F) ([RH02] Fig. 6 style) and the chosen (F, P) at each tolerance;
- ``accuracy_by_p``: ε(F, P) against P (log scale) at the largest tabulated F and at the chosen F
  ([RH02] Fig. 8 style: how much P buys);
- ``speed_error``: measured SHRM error against prefilter time per tolerance (and √ε_B);
- ``fit_slices``: measured vs fitted ρ in the plane of incidence at a few view angles;
- ``fit_bands``: fit error by view-elevation band ([Green07] Fig. 4 style);
- BRDF Explorer's views (``explorer.py``, [Burley12]): ``explorer_slice`` (θ_h × θ_d image
  slice at one φ_d, log colour scale, missing cells marked) or ``explorer_samples``
  (scattered measurements near the plane of incidence), ``explorer_polar`` (polar plots of
  the plane of incidence, measured vs each fit) and ``explorer_albedo`` (directional albedo
  against θ_v with the energy-conservation line at 1); :func:`image_row_plot` lays out the
  lit spheres ``explorer.py`` renders.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatter, MaxNLocator, NullLocator

from ...brdf_io.colour import REC709_LUMA
from .images import image_row_plot  # re-exported
from .plot_names import EXPLORER_PLOTS, PLOT_TITLES, plots_wanted  # re-exported
from .shared_state import MATPLOTLIB_LOCK

__all__ = ["PLOT_TITLES", "EXPLORER_PLOTS", "plots_wanted", "make_plots", "energy_plot", "accuracy_by_p_plot",
           "speed_error_plot", "fit_slices_plot", "fit_bands_plot", "explorer_slice_plot", "explorer_samples_plot",
           "explorer_polar_plot", "explorer_albedo_plot", "image_row_plot", "MISSING_COLOUR", "BELOW_COLOUR"]

#: Slice cells without a measurement, and cells with L or V below the surface.
MISSING_COLOUR = (1.0, 0.0, 1.0, 1.0)
BELOW_COLOUR = (0.62, 0.62, 0.62, 1.0)
#: Decades of ρ shown by the explorer's log scales (slice, polar plots), below the largest value.
_DECADES = 4
_POLAR_DECADES = 3
_DPI = 100


def _figure(width: float = 6.0, height: float = 3.6):
    fig = Figure(figsize=(width, height), dpi=_DPI)
    FigureCanvasAgg(fig)
    return fig


def _row_layout(fig, left: float, right: float, bottom: float, top: float, gap: float) -> None:
    """Fixed margins in inches for a row of panels (``gap`` between neighbours): what
    tight_layout would find for these labels, without drawing the figure once more to measure
    its text (a row of polar axes: 40 % of a report's plotting time)."""
    width, height = fig.get_size_inches()
    n = max(len(fig.axes), 1)
    panel = max((width - left - right - (n - 1) * gap) / n, 1e-3)
    fig.subplots_adjust(left=left / width, right=1.0 - right / width, bottom=bottom / height,
                        top=1.0 - top / height, wspace=gap / panel)


class _PlainLogFormatter(LogFormatter):
    """LogFormatter's choice of labelled ticks, each written as %g (0.01, 0.04, 100)."""

    def _num_to_string(self, x: float, vmin: float, vmax: float) -> str:
        return f"{x:g}"


def _log_y(ax) -> None:
    """A log y axis labelled in plain text (0.01, 0.1, 1; minor ticks labelled when the range is
    under about a decade): the default 10^k labels go through mathtext, whose parser cost each plot
    0.1–0.2 s."""
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(_PlainLogFormatter())
    ax.yaxis.set_minor_formatter(_PlainLogFormatter(labelOnlyBase=False, minor_thresholds=(1, 0.4)))


def _png(fig, row: tuple[float, float, float, float, float] | None = None) -> bytes:
    """The figure as PNG bytes; ``row``: (left, right, bottom, top, gap) margins in inches of a row
    of panels (:func:`_row_layout`), else one plain axes gets fixed margins and anything else
    tight_layout."""
    buf = io.BytesIO()
    if row is not None:
        _row_layout(fig, *row)
    elif len(fig.axes) == 1 and fig.axes[0].name == "rectilinear":
        # one plain axes: fixed margins in inches (tick labels, axis labels, a title line) instead of
        # tight_layout, which draws the whole figure once more only to measure its text
        width, height = fig.get_size_inches()
        fig.subplots_adjust(left=0.72 / width, right=1.0 - 0.15 / width, bottom=0.5 / height,
                            top=1.0 - (0.35 if fig.axes[0].get_title() else 0.15) / height)
    else:
        fig.tight_layout()
    # zlib level 1: 6 % larger files than the default 6, ~0.03 s less CPU a figure
    fig.savefig(buf, format="png", dpi=_DPI, metadata={"Software": None}, pil_kwargs={"compress_level": 1})
    return buf.getvalue()


def _rule_label(doc: dict[str, Any]) -> str:
    """What ε means in this report: the worst view band's error (bands rule) or RH02's energy."""
    bands = any(o.get("criterion") == "bands" for o in doc.get("orders", []))
    return "worst view band" if bands else "RH02, all views"


def _plotted_p(doc: dict[str, Any], n_p: int, most: int = 8) -> list[int]:
    """View orders to draw: every chosen P, P = 0, the largest tabulated, and evenly spaced others
    up to ``most`` curves (the chosen orders' dots then lie on drawn curves)."""
    chosen = {min(int(o["P"]), n_p - 1) for o in doc.get("orders", [])}
    picks = chosen | {0, n_p - 1}
    for p in np.linspace(0, n_p - 1, most).round().astype(int):
        if len(picks) >= max(most, len(chosen) + 2):
            break
        picks.add(int(p))
    return sorted(picks)


def energy_plot(doc: dict[str, Any]) -> bytes:
    """1 − ε(F, P) against F for the chosen P of every tolerance and a few others (at most ~8
    curves), lighting curves dashed, each chosen (F, P) a dot on its own curve."""
    table = np.array(doc["eps_table"]["eps"], dtype=float)
    fig = _figure()
    ax = fig.add_subplot(1, 1, 1)
    F = np.arange(table.shape[0])
    chosen = {min(int(o["P"]), table.shape[1] - 1) for o in doc["orders"]}
    cmap = colormaps["viridis"]
    top = max(table.shape[1] - 1, 1)
    for p in _plotted_p(doc, table.shape[1]):
        ax.plot(F, 1.0 - table[:, p], color=cmap(0.9 * p / top), lw=2.0 if p in chosen else 1.0,
                label=f"P={p}" + (" (chosen)" if p in chosen else ""))
    for env in doc.get("environments", []):
        curve = np.array([np.nan if v is None else v for v in env["eps_L_curve"]], dtype=float)
        ax.plot(np.arange(curve.size), 1.0 - curve, "k--", lw=1.0, label=f"lighting {env['name']}")
    for row in doc["orders"]:
        f, p = min(int(row["F"]), table.shape[0] - 1), min(int(row["P"]), table.shape[1] - 1)
        value = 1.0 - table[f, p]  # on the drawn curve (the tightest tolerance's grid)
        ax.plot([f], [value], "o", color="crimson", ms=5)
        ax.annotate(f"ε={row['tolerance']:g}: F={row['F']}, P={row['P']}", (f, value), textcoords="offset points",
                    xytext=(-4, -12), ha="right", fontsize=8, color="crimson")
    ax.set_xlabel("order F")
    ax.set_ylabel(f"captured energy 1 − ε ({_rule_label(doc)})", fontsize=9)
    ax.set_ylim(max(0.0, float(np.nanmin(1.0 - table[:, 0])) - 0.05), 1.005)
    ax.set_xlim(0, F[-1])
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2, loc="lower right")
    return _png(fig)


def accuracy_by_p_plot(doc: dict[str, Any]) -> bytes:
    """ε(F, P) against P (log scale: no negative "accuracy" where a low P's error passes 1) at the
    largest tabulated F and at each tolerance's chosen F, with the tolerances as lines; P on
    integer ticks."""
    table = np.array(doc["eps_table"]["eps"], dtype=float)
    fig = _figure(5.0, 3.2)
    ax = fig.add_subplot(1, 1, 1)
    P = np.arange(table.shape[1])
    floor = 1e-6  # ε = 0 (a P that fits every view exactly) drawn at the floor of the log axis

    def shown(values: np.ndarray) -> np.ndarray:
        return np.maximum(values, floor)

    ax.plot(P, shown(table[-1]), "s-", color="k", ms=4, label=f"F={table.shape[0] - 1} (all)")
    for k, row in enumerate(doc["orders"]):
        f = min(row["F"], table.shape[0] - 1)
        colour = colormaps["tab10"](k)
        ax.plot(P, shown(table[f]), "o-", ms=3, lw=1, color=colour, label=f"F={f} (ε={row['tolerance']:g})")
        ax.axhline(row["tolerance"], color=colour, lw=0.8, ls=":")
        ax.plot([min(int(row["P"]), P[-1])], [max(table[f, min(int(row["P"]), P[-1])], floor)], "o", ms=7,
                mfc="none", color="crimson")
    ax.set_xlabel("order P (view direction)")
    ax.set_ylabel(f"error ε(F, P) ({_rule_label(doc)})", fontsize=9)
    _log_y(ax)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlim(-0.3, P[-1] + 0.3)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, title="dotted: tolerances; circles: chosen P", title_fontsize=7)
    return _png(fig)


def speed_error_plot(doc: dict[str, Any]) -> bytes:
    """Measured relative RMS (and √ε_B) against prefilter time, one series per environment."""
    fig = _figure(5.0, 3.2)
    ax = fig.add_subplot(1, 1, 1)
    rows = doc.get("speed_vs_error", [])
    for env in sorted({r["env"] for r in rows}):
        sel = [r for r in rows if r["env"] == env]
        t = [r["prefilter_seconds"] * 1e3 for r in sel]
        ax.plot(t, [r["measured_rel_rms"] for r in sel], "o-", label=f"{env}: measured")
        ax.plot(t, [r["sqrt_eps_B"] for r in sel], "x--", label=f"{env}: √ε_B")
        for r, ti in zip(sel, t, strict=True):
            ax.annotate(f"ε={r['tolerance']:g}\n(F,P)=({r['F_B']},{r['P_B']})", (ti, r["measured_rel_rms"]),
                        textcoords="offset points", xytext=(4, 2), fontsize=6)
    ax.set_xlabel("prefilter time (ms, orders + lighting + synthesis)")
    ax.set_ylabel("relative RMS error")
    _log_y(ax)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _png(fig)


def _luma(rgb: Any) -> np.ndarray:
    """Luminance of (..., 3) RGB; an empty list (no samples in a slice) gives an empty array."""
    values = np.asarray(rgb, dtype=float)
    return values.reshape(-1, 3) @ REC709_LUMA if values.size == 0 else values @ REC709_LUMA


def fit_slices_plot(doc: dict[str, Any]) -> bytes:
    """Luminance of ρ in the plane of incidence (log scale): measured vs each fitted model."""
    slices = doc["fit_slices"]
    views = slices["views"]
    fig = _figure(2.4 * max(len(views), 1), 2.8)
    theta = np.asarray(slices["theta_deg"], dtype=float)
    # one log range for all panels, _DECADES below the largest value (as the explorer's plots),
    # decades only: a log axis over many decades with minor ticks costs most of a report's plotting
    lo, hi = _log_range([_luma(view["measured_rgb"]) for view in views]
                        + [_luma(rgb) for view in views for rgb in view["fitted_rgb"].values() if rgb is not None])
    for k, view in enumerate(views):
        ax = fig.add_subplot(1, max(len(views), 1), k + 1)
        measured = _luma(view["measured_rgb"])
        mtheta = np.asarray(view["measured_theta_deg"], dtype=float)
        style = "k-" if mtheta.size == theta.size and np.allclose(mtheta, theta) else "k."
        ax.plot(mtheta, np.maximum(measured, 1e-6), style, lw=1.5, ms=3, label="measured")
        for model, rgb in view["fitted_rgb"].items():
            if rgb is not None:
                ax.plot(theta, np.maximum(_luma(rgb), 1e-6), lw=1, label=model)
        ax.axvline(-view["view_deg"], color="grey", lw=0.5, ls=":")
        _log_y(ax)
        ax.set_ylim(10.0**lo, 10.0**hi)
        ax.yaxis.set_minor_locator(NullLocator())
        ax.set_title(f"θ_o = {view['view_deg']:g}°", fontsize=8)
        ax.set_xlabel("signed θ_i (°)", fontsize=7)
        ax.tick_params(labelsize=6)
        if k == 0:
            ax.set_ylabel("ρ luminance (1/sr)", fontsize=7)
            ax.legend(fontsize=6)
    return _png(fig, row=(0.62, 0.1, 0.42, 0.25, 0.4))  # left, right, bottom, top, gap (inches)


def fit_bands_plot(doc: dict[str, Any]) -> bytes:
    """Relative RMS of each fit per view-elevation band, grouped bars."""
    fits = [f for f in doc["fits"] if f.get("bands")]
    fig = _figure(5.0, 3.0)
    ax = fig.add_subplot(1, 1, 1)
    labels = sorted({(b["lo_deg"], b["hi_deg"]) for f in fits for b in f["bands"]})
    x = np.arange(len(labels))
    width = 0.8 / max(len(fits), 1)
    for k, f in enumerate(fits):
        values = {(b["lo_deg"], b["hi_deg"]): b["rel_rms"] for b in f["bands"]}
        ax.bar(x + k * width, [values.get(lab, np.nan) or np.nan for lab in labels], width, label=f["model"])
    ax.set_xticks(x + 0.4 - width / 2, [f"{lo:g}–{hi:g}°" for lo, hi in labels], fontsize=7)
    ax.set_ylabel("relative RMS")
    ax.set_xlabel("view elevation θ_o band")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7)
    return _png(fig)


def _grid(rows: list) -> np.ndarray:
    return np.array([[np.nan if v is None else v for v in row] for row in rows], dtype=float)


def _log_range(values: list[np.ndarray], decades: int = _DECADES) -> tuple[float, float]:
    """(lo, hi) decades of a log scale: the decade above the largest positive value and at most
    ``decades`` below it."""
    finite = np.concatenate([np.ravel(v)[np.isfinite(np.ravel(v)) & (np.ravel(v) > 0)] for v in values] or
                            [np.zeros(0)])
    if finite.size == 0:
        return -float(decades), 0.0
    hi = float(np.ceil(np.log10(finite.max()) + 1e-9))
    lo = max(hi - decades, float(np.floor(np.log10(finite.min()))))
    return lo, max(hi, lo + 1.0)


def explorer_slice_plot(doc: dict[str, Any]) -> bytes:
    """log10 of ρ's luminance on the θ_h × θ_d slice: the BRDF and each fit on one colour scale;
    missing cells magenta, cells below the surface grey."""
    s = doc["explorer"]["slice"]
    panels = [("brdf", _grid(s["lum"]))] + [(m, _grid(g)) for m, g in s["fitted_lum"].items() if g is not None]
    lo, hi = _log_range([a for _, a in panels])
    norm, cmap = Normalize(lo, hi), colormaps["inferno"]
    missing = np.zeros(panels[0][1].shape, bool)
    below = np.zeros_like(missing)
    for i, j in s["missing"]:
        missing[i, j] = True
    for i, j in s["below_surface"]:
        below[i, j] = True
    fig = _figure(2.3 * len(panels) + 0.9, 2.7)
    axes = []
    for k, (label, a) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        rgba = cmap(norm(np.log10(np.maximum(np.nan_to_num(a, nan=0.0), 10.0**lo))))
        rgba[below] = BELOW_COLOUR
        if k == 0:
            rgba[missing] = MISSING_COLOUR
        ax.imshow(rgba, origin="lower", extent=(0, 90, 0, 90), interpolation="nearest")
        ax.set_title(label + (f" ({int(missing.sum())} cells missing)" if k == 0 and missing.any() else ""),
                     fontsize=8)
        ax.set_xlabel("θ_d (°)", fontsize=7)
        if k == 0:
            ax.set_ylabel("θ_h (°)", fontsize=7)
        ax.set_xticks([0, 30, 60, 90])
        ax.set_yticks([0, 30, 60, 90])
        ax.tick_params(labelsize=6)
        axes.append(ax)
    bar = fig.colorbar(ScalarMappable(norm, cmap), ax=axes, fraction=0.03, pad=0.02)
    bar.set_label(f"log10 ρ luminance (1/sr), φ_d = {s['phi_d_deg']:g}°", fontsize=7)
    bar.ax.tick_params(labelsize=6)
    buf = io.BytesIO()
    # zlib level 1: 6 % larger files than the default 6, ~0.03 s less CPU a figure
    fig.savefig(buf, format="png", dpi=_DPI, metadata={"Software": None}, pil_kwargs={"compress_level": 1})
    return buf.getvalue()


def explorer_samples_plot(doc: dict[str, Any]) -> bytes:
    """Scattered measurements within a few degrees of the plane of incidence: θ_i against
    signed θ_o (> 0 on the mirror side), coloured by log10 of ρ's luminance."""
    s = doc["explorer"]["samples"]
    lum = _luma(s["rgb"]) if s["rgb"] else np.zeros(0)
    lo, hi = _log_range([lum])
    fig = _figure(4.6, 3.4)
    ax = fig.add_subplot(1, 1, 1)
    points = ax.scatter(s["theta_i_deg"], s["theta_o_deg"], c=np.log10(np.maximum(lum, 10.0**lo)), s=9,
                        cmap="inferno", vmin=lo, vmax=hi, edgecolors="none")
    ax.plot([0, 90], [0, 90], color="grey", lw=0.6, ls=":", label="mirror direction")
    ax.set_xlabel("θ_i (°)")
    ax.set_ylabel("signed θ_o (°)")
    ax.set_xlim(0, 90)
    ax.set_ylim(-90, 90)
    ax.set_title(f"{s['n_shown']} of {s['n_in_plane']} samples within {s['max_off_plane_deg']:g}° of the plane",
                 fontsize=8)
    ax.legend(fontsize=7, loc="lower right")
    bar = fig.colorbar(points, ax=ax)
    bar.set_label("log10 ρ luminance (1/sr)", fontsize=7)
    return _png(fig)


def explorer_polar_plot(doc: dict[str, Any]) -> bytes:
    """ρ's luminance in the plane of incidence as polar plots (angle: signed θ_o from the
    normal, mirror side right; radius: log10 ρ over _POLAR_DECADES decades), one per θ_i."""
    p = doc["explorer"]["polar"]
    curves = p["curves"]
    theta = np.radians(np.asarray(p["theta_o_deg"], dtype=float))

    def lum(rgb: list) -> np.ndarray:
        return np.array([np.nan if v is None else float(np.dot(v, REC709_LUMA)) for v in rgb], dtype=float)

    series = [lum(c["measured_rgb"]) for c in curves] + [lum(v) for c in curves for v in c["fitted_rgb"].values()
                                                          if v is not None]
    lo, hi = _log_range(series, decades=_POLAR_DECADES)
    n = max(len(curves), 1)
    fig = _figure(2.35 * n, 2.6)
    cmap = colormaps["tab10"]
    for k, c in enumerate(curves):
        ax = fig.add_subplot(1, n, k + 1, projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        ax.set_thetamin(-90)
        ax.set_thetamax(90)

        def radius(values: np.ndarray) -> np.ndarray:
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.clip(np.log10(values) - lo, 0.0, None)

        mtheta = np.radians(np.asarray(c["measured_theta_o_deg"], dtype=float))
        measured = lum(c["measured_rgb"])
        dense = mtheta.size == theta.size and np.allclose(mtheta, theta)
        ax.plot(mtheta, radius(measured), "k-" if dense else "k.", lw=1.5, ms=3, label="measured")
        for j, (model, rgb) in enumerate(c["fitted_rgb"].items()):
            if rgb is not None:
                ax.plot(theta, radius(lum(rgb)), lw=1, color=cmap(j), label=model)
        ti = np.radians(c["theta_i_deg"])
        ax.plot([-ti, -ti], [0, hi - lo], color="goldenrod", lw=1, ls="--", label="light")
        ax.set_rlim(0, hi - lo)
        ax.set_rticks(np.arange(1.0, hi - lo + 0.5, 1.0))
        ax.set_yticklabels([])
        ax.set_thetagrids([-90, -60, -30, 0, 30, 60, 90], fontsize=6)
        ax.set_title(f"θ_i = {c['theta_i_deg']:g}°", fontsize=8)
        ax.set_xlabel(f"rings: decades of ρ, 1e{lo:.0f} (centre) to 1e{hi:.0f}", fontsize=6, labelpad=-20)
        if k == 0:
            ax.legend(fontsize=6, loc="lower left", bbox_to_anchor=(-0.15, -0.25))
    return _png(fig, row=(0.3, 0.3, 0.7, 0.3, 0.4))  # left, right, bottom, top, gap (inches)


def explorer_albedo_plot(doc: dict[str, Any]) -> bytes:
    """Directional albedo against θ_v: luminance (solid) and the largest channel (dotted) of the
    BRDF and of each fit, with energy conservation (albedo 1) as a line."""
    a = doc["explorer"]["albedo"]
    views = np.asarray(a["views_deg"], dtype=float)
    fig = _figure(5.0, 3.2)
    ax = fig.add_subplot(1, 1, 1)
    series = ([("brdf", a["measured_rgb"], "k")] if a["measured_rgb"] is not None else []) + [
        (m, v, colormaps["tab10"](j)) for j, (m, v) in enumerate(a["fitted_rgb"].items()) if v is not None]
    top = 1.0
    for label, rgb, colour in series:
        values = np.asarray(rgb, dtype=float)
        ax.plot(views, values @ REC709_LUMA, "-", color=colour, lw=1.3, label=label)
        ax.plot(views, values.max(axis=1), ":", color=colour, lw=1)
        top = max(top, float(np.nanmax(values)))
    ax.axhline(1.0, color="crimson", lw=1, ls="--", label="energy conservation")
    ax.set_xlim(0, 90)
    ax.set_ylim(0, 1.08 * top)
    ax.set_xlabel("view angle θ_v (°)")
    ax.set_ylabel("directional albedo")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best", title="solid: luminance, dotted: largest channel", title_fontsize=6)
    return _png(fig)


def make_plots(doc: dict[str, Any], keys: Sequence[str] | None = None) -> dict[str, bytes]:
    """Every plot the document has data for, of ``keys`` (default: all of :data:`PLOT_TITLES`;
    a report folder draws :func:`plots_wanted`): ``{key: png_bytes}``."""
    if doc.get("status") != "ok":
        return {}
    wanted = set(PLOT_TITLES if keys is None else keys)
    explorer = doc.get("explorer") or {}
    have = {
        "energy": True,
        "accuracy_by_p": True,
        "speed_error": bool(doc.get("speed_vs_error")),
        "fit_slices": bool(doc.get("fit_slices", {}).get("views")),
        "fit_bands": any(f.get("bands") for f in doc.get("fits", [])),
        "explorer_slice": bool(explorer.get("slice")),
        "explorer_samples": bool(explorer.get("samples")),
        "explorer_polar": bool(explorer.get("polar", {}).get("curves")),
        "explorer_albedo": bool(explorer.get("albedo")),
    }
    draw = {"energy": energy_plot, "accuracy_by_p": accuracy_by_p_plot, "speed_error": speed_error_plot,
            "fit_slices": fit_slices_plot, "fit_bands": fit_bands_plot, "explorer_slice": explorer_slice_plot,
            "explorer_samples": explorer_samples_plot, "explorer_polar": explorer_polar_plot,
            "explorer_albedo": explorer_albedo_plot}
    with MATPLOTLIB_LOCK:  # matplotlib's text layout is process-global state (shared_state module)
        return {key: draw[key](doc) for key in PLOT_TITLES if key in wanted and have[key]}
