"""What the map's size costs the stated errors: uninformative bounds said so (issue 29).

The per-band statement of an SHRM (:func:`~shrmkit.analysis.view_bands.shrm_view_bands`) counts
the bilinear lookup in the stored S × 2S maps: a map term per degree,
κ_l ≈ (l(l+1))² h⁴/160 with h = π/S (and, in the bound, at degree l + P, [RH02] eq. 8). When a cap
holds S below what F needs — the 256 MiB memory budget (``analysis.map_size.default_size``) or a
``size=`` — that Taylor term grows past 1 (κ_l ∝ (lh)⁴) and the bound says nothing: measured on
Grace at 512 rows, F_B 295–403 on 185 rows gave bounds 1.05–9.07 where brute force measured
0.013–0.05.

:func:`assess_map` compares the statement on S rows with the same statement without lookup
error (exact evaluation of Σ B̃_pq Y_pq) and says, per band, whether the bound is informative
(``bound_rel_rms`` <= 1 and <= :data:`UNINFORMATIVE_FACTOR` × ``predicted_rel_rms``), what the map
costs (``map_rel_rms``: the map term of the prediction; ``map_bound_cost``: the bound minus the
bound without lookup), and the rows and bytes a map would need for its lookup to take at most
the share of ε that ``analysis.map_size.map_rows`` allows (the memory budget that meets ε).

Reference: [RH02] §5.2 (S ≈ 10 F).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass

__all__ = ["MapAssessment", "assess_map", "map_bytes", "UNINFORMATIVE_FACTOR"]

#: A bound more than this many times the prediction (or above 1) is flagged as uninformative.
UNINFORMATIVE_FACTOR = 10.0


def map_bytes(rows: int, P: int) -> int:
    """Bytes of the float32 global SHRM: (P + 1)² RGB maps of rows × 2·rows texels."""
    return int((P + 1) ** 2 * rows * 2 * rows * 3 * 4)


def informative(band: dict) -> bool:
    """False when a band's bound says nothing: above 1, or above :data:`UNINFORMATIVE_FACTOR` ×
    its prediction."""
    bound, pred = float(band["bound_rel_rms"]), float(band["predicted_rel_rms"])
    return bound <= 1.0 and bound <= UNINFORMATIVE_FACTOR * max(pred, 0.0)


@dataclass(frozen=True)
class MapAssessment:
    """The map's size against what its stated errors need (``SHRM.meta["map_budget"]``).

    Attributes
    ----------
    rows, bytes
        The map's rows S and its bytes (:func:`map_bytes`).
    budget_bytes
        The memory budget of the default size (``size=`` overrides it; then ``capped`` is False).
    capped
        True when the budget held S below RH02's 10 F (what ``capped_by`` says).
    uninformative_bands
        [lo, hi] degrees of the bands inside the view limit whose bound is uninformative.
    map_rel_rms, map_bound_cost
        Worst over the bands inside the limit: the map term of the prediction, and the bound
        minus the bound without lookup error (what the size costs, relative RMS).
    bound_without_lookup
        Worst bound inside the limit without lookup error (exact evaluation).
    rows_needed, bytes_needed
        The rows (``analysis.map_size.map_rows`` with no memory budget) and bytes of a map whose
        lookup meets its share of ε; None when every bound is informative and nothing capped S.
    note
        One sentence for the user ('' when there is nothing to say).
    """

    rows: int
    bytes: int
    budget_bytes: int
    capped: bool
    uninformative_bands: list
    map_rel_rms: float
    map_bound_cost: float
    bound_without_lookup: float
    rows_needed: int | None
    bytes_needed: int | None
    note: str

    def to_dict(self) -> dict:
        return asdict(self)


def assess_map(
    bands: Sequence[dict], raw_bands: Sequence[dict], exact_bands: Sequence[dict], *, rows: int, P: int,
    inside: Sequence[int],
    budget_bytes: int, capped: bool, rows_needed: Callable[[], int],
) -> MapAssessment:
    """Compare the statement on ``rows`` with the one without lookup error, band by band.

    Adds to each of ``bands`` (in place): ``bound_informative`` (bool), ``bound_rel_rms_exact_lookup``
    (the bound without lookup error, plus whatever the caller added to both, e.g. the lights'
    merge term, which cancels in the difference) and ``map_bound_cost``.

    Parameters
    ----------
    bands
        The statement's bands on ``rows`` (``predicted_rel_rms``, ``bound_rel_rms``,
        ``map_rel_rms``), possibly with terms the caller added after the statement (annotated).
    raw_bands, exact_bands
        The statement on ``rows`` before the caller's terms, and the same with ``map_rows=None``
        (no lookup error): the difference of their bounds is the map's cost.
    rows, P
        The map's rows and view order.
    inside
        Indices of the bands inside the view limit.
    budget_bytes, capped
        The memory budget and whether it held the rows down.
    rows_needed
        Called only when a bound is uninformative or ``capped``: the rows the lookup needs.
    """
    worst_map = worst_cost = worst_exact = 0.0
    flagged = []
    for index, (band, raw, exact) in enumerate(zip(bands, raw_bands, exact_bands, strict=True)):
        cost = max(float(raw["bound_rel_rms"]) - float(exact["bound_rel_rms"]), 0.0)
        band["bound_informative"] = informative(band)
        band["map_bound_cost"] = cost
        band["bound_rel_rms_exact_lookup"] = float(band["bound_rel_rms"]) - cost
        if index in inside:
            worst_map = max(worst_map, float(band.get("map_rel_rms", 0.0)))
            worst_cost = max(worst_cost, cost)
            worst_exact = max(worst_exact, band["bound_rel_rms_exact_lookup"])
            if not band["bound_informative"]:
                flagged.append([float(x) for x in band["theta_v_deg"]])
    need = bytes_need = None
    note = ""
    if flagged or capped:
        need = int(rows_needed())
        bytes_need = map_bytes(need, P)
        if flagged and need > rows:
            note = (f"bounds uninformative in {len(flagged)} view band(s) inside the limit: the {rows}-row map's "
                    f"lookup adds up to {worst_cost:.3g} to the bound (prediction's map term {worst_map:.3g}); without "
                    f"lookup error the worst bound is {worst_exact:.3g}; {need} rows ({bytes_need / 2**20:.0f} MiB, "
                    f"budget {budget_bytes / 2**20:.3g} MiB) would meet eps (size= or a larger budget)")
        elif flagged:
            note = (f"bounds uninformative in {len(flagged)} view band(s) inside the limit, not because of the "
                    f"map's size ({rows} rows; without lookup error the worst bound is {worst_exact:.3g})")
    return MapAssessment(rows=int(rows), bytes=map_bytes(rows, P), budget_bytes=int(budget_bytes), capped=bool(capped),
                         uninformative_bands=flagged, map_rel_rms=worst_map, map_bound_cost=worst_cost,
                         bound_without_lookup=worst_exact, rows_needed=need, bytes_needed=bytes_need, note=note)
