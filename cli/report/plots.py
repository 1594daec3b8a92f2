"""Report plots as PNG bytes, drawn from a ``report.json`` document alone (matplotlib, Agg).

The figures use matplotlib's object API (``Figure`` + the Agg canvas, never ``pyplot``),
so they need no display and change no pyplot state. matplotlib's text layout (mathtext,
font caches) is still shared by the whole process, so :func:`make_plots` draws under
``shared_state.MATPLOTLIB_LOCK``: safe from the threads of a Dask worker.

- ``energy``: captured energy 1 − ε(F, P) against F for each P, with the environments'
  1 − ε_L(F) (RH02 Fig. 6 style) and the chosen (F, P) at each tolerance;
- ``accuracy_by_p``: 1 − ε(F, P) against P at the largest tabulated F and at the chosen F
  (RH02 Fig. 8 style: how much P buys);
- ``speed_error``: measured SHRM error against prefilter time per tolerance (and √ε_B);
- ``fit_slices``: measured vs fitted ρ in the plane of incidence at a few view angles;
- ``fit_bands``: fit error by view-elevation band (Green et al. 2007 Fig. 4 style).

Reference: R. Ramamoorthi, P. Hanrahan, "Frequency Space Environment Map Rendering",
SIGGRAPH 2002 (RH02), doi:10.1145/566654.566611.
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .shared_state import MATPLOTLIB_LOCK

__all__ = ["PLOT_TITLES", "make_plots", "energy_plot", "accuracy_by_p_plot", "speed_error_plot",
           "fit_slices_plot", "fit_bands_plot"]

PLOT_TITLES = {
    "energy": "Captured energy against F (RH02 Fig. 6 style)",
    "accuracy_by_p": "Accuracy by P (RH02 Fig. 8 style)",
    "speed_error": "Speed against error",
    "fit_slices": "Measured vs fitted slices (plane of incidence)",
    "fit_bands": "Fit error by view-elevation band",
}
_LUMA = np.array([0.2126, 0.7152, 0.0722])
_DPI = 80


def _figure(width: float = 6.0, height: float = 3.6):
    fig = Figure(figsize=(width, height), dpi=_DPI)
    FigureCanvasAgg(fig)
    return fig


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=_DPI, metadata={"Software": None})
    return buf.getvalue()


def energy_plot(doc: dict[str, Any]) -> bytes:
    """1 − ε(F, P) against F for P = 0 … min(P0, 8), lighting curves dashed."""
    table = np.array(doc["eps_table"]["eps"], dtype=float)
    fig = _figure()
    ax = fig.add_subplot(1, 1, 1)
    F = np.arange(table.shape[0])

    cmap = colormaps["viridis"]
    n_p = min(table.shape[1], 9)
    for p in range(n_p):
        colour = cmap(p / max(n_p - 1, 1))
        ax.plot(F, 1.0 - table[:, p], color=colour, lw=1.2, label=f"P={p}")
    for env in doc.get("environments", []):
        curve = np.array([np.nan if v is None else v for v in env["eps_L_curve"]], dtype=float)
        ax.plot(np.arange(curve.size), 1.0 - curve, "k--", lw=1.0, label=f"lighting {env['name']}")
    for row in doc["orders"]:
        ax.plot([row["F"]], [1.0 - row["eps"]], "o", color="crimson", ms=5)
        ax.annotate(f"ε={row['tolerance']:g}", (row["F"], 1.0 - row["eps"]), textcoords="offset points",
                    xytext=(4, -10), fontsize=7, color="crimson")
    ax.set_xlabel("order F")
    ax.set_ylabel("captured energy 1 − ε")
    ax.set_ylim(max(0.0, float(np.nanmin(1.0 - table[:, 0])) - 0.05), 1.005)
    ax.set_xlim(0, F[-1])
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="lower right")
    return _png(fig)


def accuracy_by_p_plot(doc: dict[str, Any]) -> bytes:
    """1 − ε against P at the largest tabulated F and at each tolerance's chosen F."""
    table = np.array(doc["eps_table"]["eps"], dtype=float)
    fig = _figure(5.0, 3.2)
    ax = fig.add_subplot(1, 1, 1)
    P = np.arange(table.shape[1])
    ax.plot(P, 1.0 - table[-1], "s-", color="k", label=f"F={table.shape[0] - 1} (all)")
    for row in doc["orders"]:
        f = min(row["F"], table.shape[0] - 1)
        ax.plot(P, 1.0 - table[f], "o-", ms=3, lw=1, label=f"F={f} (ε={row['tolerance']:g})")
        ax.axhline(1.0 - row["tolerance"], color="grey", lw=0.6, ls=":")
    ax.set_xlabel("order P (view direction)")
    ax.set_ylabel("accuracy 1 − ε(F, P)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
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
    ax.set_yscale("log")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _png(fig)


def _luma(rgb: Any) -> np.ndarray:
    return np.asarray(rgb, dtype=float) @ _LUMA


def fit_slices_plot(doc: dict[str, Any]) -> bytes:
    """Luminance of ρ in the plane of incidence (log scale): measured vs each fitted model."""
    slices = doc["fit_slices"]
    views = slices["views"]
    fig = _figure(2.4 * max(len(views), 1), 2.8)
    theta = np.asarray(slices["theta_deg"], dtype=float)
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
        ax.set_yscale("log")
        ax.set_title(f"θ_o = {view['view_deg']:g}°", fontsize=8)
        ax.set_xlabel("signed θ_i (°)", fontsize=7)
        ax.tick_params(labelsize=6)
        if k == 0:
            ax.set_ylabel("ρ luminance (1/sr)", fontsize=7)
            ax.legend(fontsize=6)
    return _png(fig)


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


def make_plots(doc: dict[str, Any]) -> dict[str, bytes]:
    """Every plot the document has data for: ``{key: png_bytes}`` (keys of :data:`PLOT_TITLES`)."""
    if doc.get("status") != "ok":
        return {}
    with MATPLOTLIB_LOCK:  # matplotlib's text layout is process-global state (shared_state module)
        plots = {"energy": energy_plot(doc), "accuracy_by_p": accuracy_by_p_plot(doc)}
        if doc.get("speed_vs_error"):
            plots["speed_error"] = speed_error_plot(doc)
        if doc.get("fit_slices", {}).get("views"):
            plots["fit_slices"] = fit_slices_plot(doc)
        if any(f.get("bands") for f in doc.get("fits", [])):
            plots["fit_bands"] = fit_bands_plot(doc)
    return plots
