"""The report's plots by name (keys, titles) and which a report draws: what the pages and the folder
writer need without importing matplotlib (``plots.py`` draws them)."""

from __future__ import annotations

from typing import Any

__all__ = ["PLOT_TITLES", "EXPLORER_PLOTS", "plots_wanted"]

PLOT_TITLES = {
    "energy": "Captured energy against F (RH02 Fig. 6 style)",
    "accuracy_by_p": "Error against P (RH02 Fig. 8 style, as ε on a log scale)",
    "speed_error": "Speed against error",
    "fit_slices": "Measured vs fitted slices (plane of incidence)",
    "fit_bands": "Fit error by view-elevation band",
    "explorer_slice": "Image slice θ_h × θ_d (BRDF Explorer)",
    "explorer_samples": "Measured samples near the plane of incidence",
    "explorer_polar": "Polar plots of the plane of incidence (BRDF Explorer)",
    "explorer_albedo": "Directional albedo against θ_v (BRDF Explorer)",
}
#: The BRDF views' plots: drawn unless the report's options say ``explorer_plots: false`` (the quick
#: profile); the others (RH02's energy and ε-by-P plots, speed against error, fit errors by band) are
#: drawn whenever ``plots`` is.
EXPLORER_PLOTS = ("fit_slices", "explorer_slice", "explorer_samples", "explorer_polar", "explorer_albedo")


def plots_wanted(doc: dict[str, Any]) -> tuple[str, ...]:
    """The keys of :data:`PLOT_TITLES` the report's options ask for (``plots``, ``explorer_plots``)."""
    options = doc.get("options", {})
    if not options.get("plots", True):
        return ()
    explorer = options.get("explorer_plots", True)
    return tuple(k for k in PLOT_TITLES if explorer or k not in EXPLORER_PLOTS)
