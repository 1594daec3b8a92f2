"""Notebook display (``_repr_html_``, ``_repr_png_``) of the analysis results: the order choice and the SHRM.

:class:`~shrmkit.analysis.orders.OrderChoice`: F, P, ε, the rule and its view limit, [RH02]'s ε,
capped / converged, the time, and the per-view-band table at the chosen orders ([RH02] §5.1,
DESIGN §4). :class:`~shrmkit.analysis.shrm.SHRM`: the orders, the map size, the stated error of
the worst view band (predicted and bound, relative RMS), the lights, the window, the timings, the
per-band table, and a picture: the distant-viewer map of [RH02] eq. 12 for a viewer at the zenith,
as a lat-long thumbnail over the reflection direction R (the SHRM part; the lights are shaded per
pixel by the renderers). Cards are built from the pieces of :mod:`~shrmkit.brdf_io.notebook`.

Public objects: :func:`order_choice_html`, :func:`shrm_html`, :func:`shrm_png`, :func:`stated_band`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..brdf_io.display import encode_png, middle_grey_exposure, to_8bit
from ..brdf_io.latlong import row_solid_angles
from ..brdf_io.notebook import THUMBNAIL_ROWS, card, html_table, number, png_img
from .records import PrefilterInfo, ViewBand
from .sh import real_sph_harm

__all__ = ["order_choice_html", "shrm_html", "shrm_png", "stated_band", "THUMBNAIL_VIEW"]

#: The view direction of the SHRM's thumbnail (the zenith, z-up frame).
THUMBNAIL_VIEW = (0.0, 0.0, 1.0)


def _band_name(band: Mapping[str, Any] | ViewBand) -> str:
    edges = band.theta_v_deg if isinstance(band, ViewBand) else band["theta_v_deg"]
    lo, hi = edges if edges is not None else (float("nan"), float("nan"))
    return f"{lo:g}–{hi:g}°"


def order_choice_html(choice: Any) -> str:
    """The card of an :class:`~shrmkit.analysis.orders.OrderChoice`: the orders and their error,
    then ε and √ε per view band at (F, P) under a point light (``OrderChoice.view_bands``)."""
    rule = (f"bands: every view band to {choice.max_view_deg:g}°" if choice.criterion == "bands"
            else "rh02: energy over all views")
    rows = [
        ("F, P", f"{choice.F}, {choice.P}"),
        ("ε (rule's table)", choice.eps),
        ("tolerance", choice.tolerance),
        ("rule", rule),
        ("ε RH02 (all views)", choice.eps_rh02),
        ("capped", choice.capped),
        ("converged", choice.converged),
        ("samples without data", choice.n_without_data),
        ("seconds", choice.seconds),
    ]
    if choice.message:
        rows.append(("note", choice.message))
    bands = choice.view_bands()
    table = html_table(
        ["θ_v", "ε", "rel. RMS (√ε)", "inside the limit", "extrapolated samples"],
        [[_band_name(b), b["eps"], b["rel_rms_point_light"], b["inside"], b["extrapolated_samples"]] for b in bands],
        caption=f"by view band at (F, P) = ({choice.F}, {choice.P}), point light",
    )
    return card("OrderChoice", rows, extra=table)


def stated_band(meta: Mapping[str, Any]) -> dict[str, Any] | None:
    """The view band inside the limit with the largest predicted relative RMS among an SHRM's
    ``meta["view_bands"]`` (the error the SHRM states for itself), as JSON, or None when it states
    none: :meth:`PrefilterInfo.stated_band <shrmkit.analysis.records.PrefilterInfo.stated_band>` of
    ``meta`` (``SHRM.info.stated_band()`` gives the typed band)."""
    band = PrefilterInfo.from_meta(meta).stated_band()
    return None if band is None else band.to_json()


def _or_dash(value: Any) -> Any:
    """A card's value, or "—" for a key the SHRM's meta lacks (a file written before it)."""
    return "—" if value is None else value


def _view_map_thumbnail(shrm: Any, rows: int = THUMBNAIL_ROWS) -> np.ndarray:
    """uint8 thumbnail (≤ rows, ≤ 2·rows, 3) of Σ B̃_pq(R) Y_pq(V) at V = :data:`THUMBNAIL_VIEW`
    (RH02 eq. 12, clamped at 0) on every k-th pixel of the maps (k so that at most ``rows`` rows)."""
    step = max(1, -(-shrm.height // rows))
    coeffs = shrm.coeffs[:, step // 2 :: step, step // 2 :: step]  # pixel centres of a coarser grid
    basis = real_sph_harm(shrm.P, np.asarray(THUMBNAIL_VIEW, dtype=np.float64)).astype(np.float32)
    radiance = np.maximum(np.tensordot(basis, coeffs, axes=(0, 0)), 0.0)
    weights = row_solid_angles(shrm.height, shrm.width)[step // 2 :: step]
    return to_8bit(radiance, exposure=middle_grey_exposure(radiance, weights[:, None]), curve="filmic")


def shrm_png(shrm: Any) -> bytes:
    """The SHRM's thumbnail: the distant-viewer map for a viewer at the zenith, over R, as PNG."""
    return encode_png(_view_map_thumbnail(shrm))


def shrm_html(shrm: Any) -> str:
    """The card of an :class:`~shrmkit.analysis.shrm.SHRM`: orders, map size, the stated error of the
    worst view band, lights, window, timings and the per-band table."""
    info: PrefilterInfo = shrm.info
    worst = info.stated_band()
    limit = float("nan") if info.max_view_deg is None else info.max_view_deg
    stated = "none stated" if worst is None else (
        f"relative RMS {worst.predicted_rel_rms:.3g} (bound {worst.bound_rel_rms:.3g}) in band "
        f"{_band_name(worst)}, worst inside {limit:g}°")
    cube = "" if shrm.cube is None else f"; cube {shrm.cube.shape[2]}² per face"
    rows: list[tuple[str, Any]] = [
        ("BRDF", _or_dash(info.brdf)),
        ("environment", _or_dash(info.environment)),
        ("F, P", f"{shrm.F}, {shrm.P}  ({(shrm.P + 1) ** 2} coefficient maps)"),
        ("map size", f"{shrm.height} × {shrm.width}{cube}, {shrm.coeffs.nbytes / 2**20:.3g} MiB"),
        ("tolerance", shrm.tolerance),
        ("stated error", stated),
        ("lights (shaded exactly)", len(info.lights)),
        ("window", _or_dash(info.window.used)),
    ]
    if info.capped_by:
        rows.append(("capped by", "; ".join(str(c) for c in info.capped_by)))
    timings = info.timings.to_json()
    if timings:
        rows.append(("seconds", ", ".join(f"{k} {v:.3g}" for k, v in timings.items())))
    table = html_table(
        ["θ_v", "predicted rel. RMS", "bound", "inside the limit"],
        [[_band_name(b), b.predicted_rel_rms, b.bound_rel_rms, b.inside] for b in info.view_bands],
        caption="stated error by view band (relative RMS of the reflected radiance)",
    ) if info.view_bands else ""
    image = png_img(shrm_png(shrm), "distant-viewer map, viewer at the zenith", width=4 * THUMBNAIL_ROWS)
    note = ("<div style='font-size:80%'>picture: the SHRM part for a viewer at the zenith, over the "
            f"reflection direction (lat-long); {number(len(info.lights))} light(s) not drawn</div>")
    return card("SHRM", rows, image=image, extra=note + table)
