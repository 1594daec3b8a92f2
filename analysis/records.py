"""Typed records of what :func:`~shrmkit.analysis.shrm.prefilter` did and states.

:class:`PrefilterInfo` gathers the orders, the lights, the window (:class:`WindowInfo`), the
stage timings (:class:`Timings`), the budgets that capped the rule and the per-band statement
(:class:`ViewBand`). ``to_meta()`` writes exactly the keys and values of ``SHRM.meta``
(``data_specs/shrm_file.md``), the serialized form every verb, report and file prints or stores;
``from_meta()`` reads them back, tolerating files written before a key existed (the key reads as
None). :attr:`SHRM.info <shrmkit.analysis.shrm.SHRM.info>` is ``PrefilterInfo.from_meta(meta)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

__all__ = ["PrefilterInfo", "WindowInfo", "LightsInfo", "Timings", "ViewBand"]


@dataclass(frozen=True)
class Timings:
    """Seconds per stage of ``prefilter`` (``meta["timings"]``); a stage that did not run is None
    (``pixels``: the pixel rule; ``cube``: the cube map) and is left out of the JSON."""

    orders: float | None = None
    lights: float | None = None
    lighting: float | None = None
    window: float | None = None
    pixels: float | None = None
    map_size: float | None = None
    synthesis: float | None = None
    cube: float | None = None
    errors: float | None = None
    total: float | None = None

    def to_json(self) -> dict[str, float]:
        """``{stage: seconds}`` in stage order; the key of ``map_size`` is ``"map size"``."""
        return {_TIMING_KEYS.get(f.name, f.name): getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}

    @classmethod
    def from_json(cls, data: Mapping[str, Any] | None) -> Timings:
        data = data or {}
        return cls(**{f.name: data.get(_TIMING_KEYS.get(f.name, f.name)) for f in fields(cls)})


_TIMING_KEYS = {"map_size": "map size"}


@dataclass(frozen=True)
class ViewBand:
    """One band of the view angle θ_v in the SHRM's per-band statement (``meta["view_bands"]``,
    ``data_specs/view_bands.md``): relative RMS errors, in the units of a measured one.

    ``theta_v_deg`` is [lo, hi] in degrees. The ``lights_*`` and ``*_residual`` fields exist only
    when the SHRM has explicit lights, the lookup fields (``bound_informative``, ``map_bound_cost``,
    ``bound_rel_rms_exact_lookup``) in files written since the map budget (issue 29); None fields
    of that optional tail are left out of the JSON. Keys this record does not know are kept in
    ``extra`` and written after the others.
    """

    theta_v_deg: tuple[float, float] | None = None
    predicted_rel_rms: float | None = None
    bound_rel_rms: float | None = None
    truncation_rel_rms: float | None = None
    map_rel_rms: float | None = None
    inside: bool | None = None
    extrapolated_samples: int | None = None
    bound_holds: bool | None = None
    lights_rel_rms: float | None = None
    lights_rel_rms_residual: float | None = None
    predicted_rel_rms_residual: float | None = None
    bound_rel_rms_residual: float | None = None
    bound_informative: bool | None = None
    map_bound_cost: float | None = None
    bound_rel_rms_exact_lookup: float | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "extra" or (value is None and f.name in _OPTIONAL_BAND_KEYS):
                continue
            out[f.name] = list(value) if f.name == "theta_v_deg" and value is not None else value
        out.update(self.extra)
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ViewBand:
        names = {f.name for f in fields(cls)} - {"extra"}
        known = {k: v for k, v in data.items() if k in names}
        if known.get("theta_v_deg") is not None:
            known["theta_v_deg"] = tuple(known["theta_v_deg"])
        return cls(**known, extra={k: v for k, v in data.items() if k not in names})


_OPTIONAL_BAND_KEYS = frozenset((
    "lights_rel_rms", "lights_rel_rms_residual", "predicted_rel_rms_residual", "bound_rel_rms_residual",
    "bound_informative", "map_bound_cost", "bound_rel_rms_exact_lookup",
))


@dataclass(frozen=True)
class WindowInfo:
    """The window against Gibbs ringing and the undershoot before and after it (the ``window*`` and
    ``negative*`` keys of ``meta``, ``data_specs/shrm_file.md``; DESIGN §7).

    ``used``: ``"none"`` or ``"lanczos"``; ``requested``: as asked (``"auto"`` too); ``strength``: t;
    ``cost``: the energy of its change relative to B's; ``eps_reflected_unwindowed``: ε_B without it;
    ``negative_*``: undershoot as a fraction of the peak on the sample (``before`` None when not
    measured), the fraction of sampled pairs with a negative channel, the sample's largest θ_v
    (degrees) and its pair count; ``capped``: the budget kept the undershoot above ``threshold``.
    """

    used: str | None = None
    requested: str | None = None
    strength: float | None = None
    reason: str | None = None
    threshold: float | None = None
    cost: float | None = None
    eps_reflected_unwindowed: float | None = None
    negative_before: float | None = None
    negative_after: float | None = None
    negative_fraction_after: float | None = None
    negative_max_view_deg: float | None = None
    negative_sample_pairs: int | None = None
    capped: bool | None = None

    def to_meta(self) -> dict[str, Any]:
        return {_WINDOW_KEYS.get(f.name, f.name): getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any]) -> WindowInfo:
        return cls(**{f.name: meta.get(_WINDOW_KEYS.get(f.name, f.name)) for f in fields(cls)})

    def describe(self) -> str:
        """``lanczos x0.42`` or ``none``: the window used and its strength, as the CLI prints it."""
        return str(self.used) if self.used == "none" else f"{self.used} x{self.strength:.3g}"


_WINDOW_KEYS = {"used": "window", "requested": "window_requested", "strength": "window_strength",
                "reason": "window_reason", "threshold": "window_threshold", "cost": "window_cost",
                "capped": "window_capped"}


@dataclass(frozen=True)
class LightsInfo:
    """The explicit lights taken out of the map (the ``lights*`` keys of ``meta``,
    ``data_specs/lights.md``): ``requested`` (``"auto"``, ``"none"`` or N), one JSON object per light
    (``Light.to_dict()``), their share of the map's flux, the extraction's threshold (None when
    none applied), the bright regions left in the map, the BRDF that shades them (a spec or a file;
    None without lights) and what the statements are relative to (``statement_signal``)."""

    requested: str | int | None = None
    lights: tuple[dict[str, Any], ...] = ()
    flux_share: float | None = None
    threshold: float | None = None
    left_in_map: int | None = None
    brdf: str | None = None
    statement_signal: str | None = None

    def to_meta(self) -> dict[str, Any]:
        return {"lights_requested": self.requested, "lights": list(self.lights), "lights_flux_share": self.flux_share,
                "lights_threshold": self.threshold, "lights_left_in_map": self.left_in_map,
                "lights_brdf": self.brdf, "statement_signal": self.statement_signal}

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any]) -> LightsInfo:
        return cls(requested=meta.get("lights_requested"), lights=tuple(meta.get("lights") or ()),
                   flux_share=meta.get("lights_flux_share"), threshold=meta.get("lights_threshold"),
                   left_in_map=meta.get("lights_left_in_map"), brdf=meta.get("lights_brdf"),
                   statement_signal=meta.get("statement_signal"))

    def __len__(self) -> int:
        return len(self.lights)


@dataclass(frozen=True)
class PrefilterInfo:
    """What ``prefilter`` made and states, beside the SHRM's orders, maps and ``eps``
    (``SHRM.meta`` typed; keys and meanings: ``data_specs/shrm_file.md``).

    Attributes
    ----------
    brdf, environment, environment_source
        Names (and the environment's file, '' for a builtin).
    lights
        :class:`LightsInfo`.
    F_rho, P_rho, F_L, lighting_capped
        The BRDF's orders, the lighting's order and whether ε_L stays above ε up to its lmax.
    orders_message, orders_asked
        Notes on the orders ('' when none) and the orders given to ``prefilter(F=, P=)`` (None, or
        ``{"F": ..., "P": ...}``).
    timings
        :class:`Timings` (seconds).
    version, frame, azimuth_free
        ``shrmkit_version``, the pixel convention, the azimuth-free SHRM [KM00].
    window
        :class:`WindowInfo`.
    criterion, max_view_deg
        The order rule and its view limit (degrees).
    scene_capped, capped, capped_by
        No F_B up to the map's rows meets ε; whether any budget kept the rule from ε, and which.
    pixel_rule, pixel_errors
        The per-direction rule's check (None when it did not run) and statement, as JSON
        (``analysis/pixels.py``).
    view_bands
        Tuple of :class:`ViewBand`, the per-band statement.
    map_budget
        What the map's size costs the statement, as JSON (``analysis/map_budget.py``).
    extrapolated_samples
        Samples of a measured table without data.
    """

    brdf: str | None = None
    environment: str | None = None
    environment_source: str | None = None
    lights: LightsInfo = field(default_factory=LightsInfo)
    F_rho: int | None = None
    P_rho: int | None = None
    F_L: int | None = None
    lighting_capped: bool | None = None
    orders_message: str | None = None
    orders_asked: Mapping[str, int | None] | None = None
    timings: Timings = field(default_factory=Timings)
    version: str | None = None
    frame: str | None = None
    azimuth_free: bool | None = None
    window: WindowInfo = field(default_factory=WindowInfo)
    criterion: str | None = None
    max_view_deg: float | None = None
    scene_capped: bool | None = None
    capped: bool | None = None
    capped_by: tuple[str, ...] = ()
    pixel_rule: Mapping[str, Any] | None = None
    pixel_errors: Mapping[str, Any] | None = None
    view_bands: tuple[ViewBand, ...] = ()
    map_budget: Mapping[str, Any] | None = None
    extrapolated_samples: int | None = None

    def to_meta(self) -> dict[str, Any]:
        """``SHRM.meta``: the keys, order and values ``data_specs/shrm_file.md`` defines."""
        return {
            "brdf": self.brdf, "environment": self.environment, "environment_source": self.environment_source,
            **self.lights.to_meta(),
            "F_rho": self.F_rho, "P_rho": self.P_rho, "F_L": self.F_L, "lighting_capped": self.lighting_capped,
            "orders_message": self.orders_message, "orders_asked": self.orders_asked,
            "timings": self.timings.to_json(), "shrmkit_version": self.version, "frame": self.frame,
            "azimuth_free": self.azimuth_free,
            **self.window.to_meta(),
            "criterion": self.criterion, "max_view_deg": self.max_view_deg, "scene_capped": self.scene_capped,
            "capped": self.capped, "capped_by": list(self.capped_by), "pixel_rule": self.pixel_rule,
            "pixel_errors": self.pixel_errors, "view_bands": [band.to_json() for band in self.view_bands],
            "map_budget": self.map_budget, "extrapolated_samples": self.extrapolated_samples,
        }

    @classmethod
    def of(cls, source: Any) -> PrefilterInfo:
        """The record of ``source``: a :class:`PrefilterInfo` itself, an SHRM (its ``info``), an
        object holding only the serialized ``meta`` dict (an SHRM-like stand-in), or that dict.
        Anything else gives the empty record (it states nothing)."""
        if isinstance(source, cls):
            return source
        info = getattr(source, "info", None)
        if isinstance(info, cls):
            return info
        meta = source if isinstance(source, Mapping) else getattr(source, "meta", None)
        return cls.from_meta(meta if isinstance(meta, Mapping) else None)

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any] | None) -> PrefilterInfo:
        """The record of a ``meta`` dict (a prefiltered SHRM's, or a file's: keys a file lacks
        read as None, or empty for the lists); never raises on missing keys."""
        meta = meta or {}
        return cls(
            brdf=meta.get("brdf"), environment=meta.get("environment"),
            environment_source=meta.get("environment_source"), lights=LightsInfo.from_meta(meta),
            F_rho=meta.get("F_rho"), P_rho=meta.get("P_rho"), F_L=meta.get("F_L"),
            lighting_capped=meta.get("lighting_capped"), orders_message=meta.get("orders_message"),
            orders_asked=meta.get("orders_asked"), timings=Timings.from_json(meta.get("timings")),
            version=meta.get("shrmkit_version"), frame=meta.get("frame"), azimuth_free=meta.get("azimuth_free"),
            window=WindowInfo.from_meta(meta), criterion=meta.get("criterion"),
            max_view_deg=meta.get("max_view_deg"), scene_capped=meta.get("scene_capped"),
            capped=meta.get("capped"), capped_by=tuple(meta.get("capped_by") or ()),
            pixel_rule=meta.get("pixel_rule"), pixel_errors=meta.get("pixel_errors"),
            view_bands=tuple(ViewBand.from_json(band) for band in meta.get("view_bands") or ()),
            map_budget=meta.get("map_budget"), extrapolated_samples=meta.get("extrapolated_samples"),
        )

    def bands_inside(self) -> tuple[ViewBand, ...]:
        """The bands inside the rule's view limit (a band without ``inside`` counts as inside)."""
        return tuple(band for band in self.view_bands if band.inside is not False)

    def stated_band(self) -> ViewBand | None:
        """The error the SHRM states for itself: among the bands marked ``inside`` the rule's view
        limit, the one with the largest ``predicted_rel_rms`` (the first of equals); None when no
        band is marked inside (a file without the per-band statement)."""
        inside = [band for band in self.view_bands if band.inside]
        return max(inside, key=lambda band: band.predicted_rel_rms or 0.0) if inside else None
