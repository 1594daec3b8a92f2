"""A census of a BRDF library: accuracy at given orders, orders needed, the fit, and why each miss.

[RH02] Fig. 8 asks of a whole library (the 61 CURET surfaces, [CURET99]) how much of each BRDF's
energy a fixed number of coefficients captures: the accuracy 1 − ε(F, P) at F = 30 and P = 0…5
([RH02] §5.1, §6.2: 56 of 61 BRDFs above 90 % at F = 30, P = 5; the surfaces their fits could not
represent are anisotropic). :func:`run_census` answers that, and more, for any library ``report``
accepts: one :class:`CensusRow` per material (representation, accuracy at (F, P) by both order
criteria, orders needed, grazing share, :data:`REASONS` for a miss); a file that cannot be read or
analysed is one failed row (its message kept), never an aborted census.
"""

from __future__ import annotations

import multiprocessing
import pickle
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import ducc0
import numpy as np
from threadpoolctl import threadpool_limits

from ..brdf_io.brdf import BRDF
from ..brdf_io.curet import read_curet_all
from ..brdf_io.errors import BadInputError, ShrmError
from ..brdf_io.specs import BRDF_FILE_TYPES, brdf_sources, load_brdf
from .defaults import CENSUS_F as DEFAULT_F  # numpy-free home, for the CLI's parsers
from .defaults import CENSUS_MAX_F_LIMIT as MAX_F_LIMIT
from .defaults import CENSUS_MAX_P_LIMIT as MAX_P_LIMIT
from .defaults import CENSUS_MAX_WORKERS as MAX_WORKERS
from .defaults import CENSUS_P as DEFAULT_P
from .defaults import CENSUS_THRESHOLD as DEFAULT_THRESHOLD
from .fit.crossval import DEFAULT_FOLDS
from .fit.representation import CANDIDATES, RepresentationChoice, choose_representation
from .fit.summary import FIT_FAIL_BAND_REL_RMS
from .order_rule import OrderRule, RuleFields, resolve_rule
from .orders import DEFAULT_MAX_F, DEFAULT_MAX_P, OrderChoice, choose_orders, orders_on_grid_for
from .threads import single_threaded_blas

__all__ = [
    "CSV_COLUMNS",
    "Census",
    "CensusRow",
    "DEFAULT_F",
    "DEFAULT_P",
    "DEFAULT_THRESHOLD",
    "GRAZING_SHARE",
    "MAX_F_LIMIT",
    "MAX_P_LIMIT",
    "MAX_WORKERS",
    "MISSING_SHARE",
    "REASONS",
    "census_sources",
    "grazing_share",
    "run_census",
]

#: A miss is put down to grazing energy when more than this share of the energy missed at (F, P)
#: lies in the view bands beyond the view limit.
GRAZING_SHARE = 0.5
#: A miss is put down to missing data when more than this share of the reparameterized table
#: samples had no measurement to interpolate (MERL's holes, an RGL file's uncovered directions).
MISSING_SHARE = 0.01

#: The reasons a row gives for a miss or a failure, and what each means.
REASONS = {
    "error": "the file could not be read or analysed (the row's error says why)",
    "fit": f"the representation's held-out worst view band is above {FIT_FAIL_BAND_REL_RMS:g} (relative RMS): "
           "the accuracy describes the fit, not the material",
    "missing": f"more than {MISSING_SHARE:.0%} of the table's reparameterized samples had no measurement",
    "anisotropy": "the material is anisotropic (measured held-out energy of the φ-dependent part): "
                  "an isotropic representation misses it",
    "grazing": f"more than {GRAZING_SHARE:.0%} of the energy missed at (F, P) lies at views beyond the view limit",
    "orders": "energy above the orders (F, P) at views inside the view limit: the material needs higher orders",
}

#: Columns of ``census.csv`` (``data_specs/census_json.md``); ``acc_rh02_P{p}`` and
#: ``acc_bands_P{p}`` follow for p = 0…P.
CSV_COLUMNS = (
    "source", "name", "status", "representation", "model", "fit_ok", "fit_worst_band_rel_rms", "fit_worst_band_deg",
    "accuracy_rh02", "accuracy_bands", "above_rh02", "above_bands", "F_needed", "P_needed", "eps_needed",
    "capped", "anisotropy", "anisotropic", "grazing_share", "missing_share", "reasons", "reason_text", "error",
    "seconds",
)


@dataclass(frozen=True)
class CensusRow:
    """One material of a census. What it holds:

    - **representation**: scattered measurements (CURET, Cornell, gonioreflectometer CSV) go
      through the representation with the smallest held-out worst-view-band error
      (:func:`~shrmkit.analysis.fit.representation.choose_representation`); tables and models are
      analysed as they are;
    - **accuracy at (F, P)**: on one quadrature grid sized for (F, P)
      (:func:`~shrmkit.analysis.orders.orders_on_grid_for`), 1 − ε(F, p) for p = 0…P by [RH02]'s
      criterion (energy over all views, [RH02] §5.1: what Fig. 8 plots) and by the bands criterion
      (the worst θ_v band inside the view limit under a point light, ``analysis/view_bands.py``);
    - **orders needed** at a tolerance (:func:`~shrmkit.analysis.orders.choose_orders`);
    - **grazing share**: the share of the energy missed at (F, P) (bands criterion, per band
      ε_b × the band's energy of ρ̂) that lies in the view bands beyond the view limit;
    - **reasons** for every row that misses the threshold or fails (:data:`REASONS`).

    Attributes
    ----------
    source
        The argument that names it (``abrdf.dat#7``, a file path, a spec).
    name
        The BRDF's name ("" when it could not be read).
    status
        ``"ok"`` or ``"failed"`` (could not be read or analysed: ``error`` says why).
    kind
        The BRDF's kind (``"scattered"``, ``"table"``, ``"model"``, ...), "" when unread.
    representation
        What was analysed: the chosen representation's label (scattered data), else ``"as given"``.
    model
        The chosen representation's model (``"zernike"``, ``"lafortune"``, ``"cook-torrance"``),
        "" when the BRDF was analysed as given.
    fit_ok
        The chosen representation's held-out worst band is at most 0.5 (None: not fitted).
    fit_worst
        Its held-out worst view band ``{"lo_deg", "hi_deg", "n", "rel_rms", "log_rms"}``, None
        when not fitted (or no band of enough samples).
    accuracy_rh02, accuracy_bands
        (P+1,) 1 − ε(F, p) for p = 0…P: RH02's energy over all views, and the worst θ_v band
        inside the view limit (point light); empty when the row failed.
    F_needed, P_needed, eps_needed, capped
        The orders the rule needs at the census' tolerance, the ε they reach, and whether the
        caps stopped the search (None when failed).
    anisotropy, anisotropic
        From the representation choice (``isotropy.py``): the held-out energy fraction only the
        true azimuths predict and the verdict; None where not measured.
    grazing_share
        Share of the energy missed at (F, P) that lies beyond the view limit (module docs).
    missing_share
        Share of the reparameterized table samples (``n_theta_i · n_theta_o · n_phi`` of the grid
        sized for (F, P)) that had no measurement to interpolate; None for scattered data (the
        representation fills between the measurements: its held-out error says how well).
    reasons
        Codes of :data:`REASONS` for a miss (below the threshold at (F, P) by either criterion)
        or a failure; empty for a material above it with a passing fit.
    reason_text
        The reasons for people, with their numbers.
    error
        Why the row failed (one line), else None.
    seconds
        Wall time of this row.
    representation_record
        The representation choice's ``as_dict()`` (``data_specs/representation_json.md``) or None.
    """

    source: str
    name: str
    status: str
    kind: str = ""
    representation: str = ""
    model: str = ""
    fit_ok: bool | None = None
    fit_worst: dict[str, float] | None = None
    accuracy_rh02: tuple[float, ...] = ()
    accuracy_bands: tuple[float, ...] = ()
    F_needed: int | None = None
    P_needed: int | None = None
    eps_needed: float | None = None
    capped: bool | None = None
    anisotropy: float | None = None
    anisotropic: bool | None = None
    grazing_share: float | None = None
    missing_share: float | None = None
    reasons: tuple[str, ...] = ()
    reason_text: str = ""
    error: str | None = None
    seconds: float = 0.0
    representation_record: dict[str, Any] | None = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def accuracy(self, criterion: str = "rh02") -> float:
        """1 − ε(F, P) at the census' P by ``"rh02"`` or ``"bands"`` (NaN when failed)."""
        acc = self.accuracy_rh02 if criterion == "rh02" else self.accuracy_bands
        return float(acc[-1]) if acc else float("nan")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (``data_specs/census_json.md``)."""
        return {
            "source": self.source, "name": self.name, "status": self.status, "kind": self.kind,
            "representation": self.representation, "model": self.model, "fit_ok": self.fit_ok,
            "fit_worst_band": self.fit_worst,
            "accuracy_rh02": list(self.accuracy_rh02), "accuracy_bands": list(self.accuracy_bands),
            "F_needed": self.F_needed, "P_needed": self.P_needed, "eps_needed": self.eps_needed,
            "capped": self.capped, "anisotropy": self.anisotropy, "anisotropic": self.anisotropic,
            "grazing_share": self.grazing_share, "missing_share": self.missing_share,
            "reasons": list(self.reasons), "reason_text": self.reason_text, "error": self.error,
            "seconds": self.seconds, "representation_record": self.representation_record,
        }


@dataclass(frozen=True)
class Census(RuleFields):
    """The outcome of :func:`run_census`: one row per material and the settings.

    Attributes
    ----------
    rows
        One :class:`CensusRow` per source, in the order given.
    F, P, threshold
        The orders asked and the accuracy mark (RH02 Fig. 8: 30, 5, 0.9).
    rule
        The order rule of ``F_needed``/``P_needed`` (:class:`~shrmkit.analysis.order_rule.OrderRule`,
        ``choose_orders``); its fields read back as ``eps``, ``criterion``, ``max_view_deg``,
        ``max_F``, ``max_P``.
    fit
        The representation settings: ``candidates``, ``folds``, ``seed``, ``max_theta_deg``.
    seconds
        Wall time of the whole census.
    """

    rows: tuple[CensusRow, ...]
    F: int
    P: int
    threshold: float
    rule: OrderRule
    fit: dict[str, Any]
    seconds: float

    @property
    def n_failed(self) -> int:
        """Rows that could not be read or analysed."""
        return sum(not r.ok for r in self.rows)

    def count_above(self, criterion: str = "rh02", p: int | None = None) -> int:
        """Rows whose 1 − ε(F, p) (default p = P) is above the threshold by ``criterion``."""
        p = self.P if p is None else int(p)
        key = "accuracy_rh02" if criterion == "rh02" else "accuracy_bands"
        return sum(1 for r in self.rows if r.ok and getattr(r, key)[p] > self.threshold)

    def fit_settings(self) -> str:
        """The representation settings for people, e.g. ``"scattered data through the representation
        with the smallest held-out worst view band (lafortune, cook-torrance, zernike; 5-fold
        cross-validation, seed 0, samples to 80°)"``."""
        f = self.fit
        if f.get("represent"):
            return f"scattered data through {f['represent']}"
        return (f"scattered data through the representation with the smallest held-out worst view band "
                f"({', '.join(f['candidates'])}; {f['folds']}-fold cross-validation, seed {f['seed']}, "
                f"samples to {f['max_theta_deg']:g}°)")

    def count_line(self) -> str:
        """``"N of M above 90 % accuracy at F = 30, P = 5 (RH02's energy over all views); K of M in every
        view band to 80°; <fit settings>"``."""
        n = len(self.rows)
        return (f"{self.count_above('rh02')} of {n} above {self.threshold:.0%} accuracy at F = {self.F}, "
                f"P = {self.P} (RH02's energy over all views); {self.count_above('bands')} of {n} in every view "
                f"band to {self.max_view_deg:g}°; {self.fit_settings()}"
                + (f"; {self.n_failed} could not be analysed" if self.n_failed else ""))

    def csv_rows(self) -> list[dict[str, Any]]:
        """One dict per row with the keys :data:`CSV_COLUMNS` then ``acc_rh02_P{p}``, ``acc_bands_P{p}``."""
        out = []
        for r in self.rows:
            w = r.fit_worst
            row: dict[str, Any] = {
                "source": r.source, "name": r.name, "status": r.status, "representation": r.representation,
                "model": r.model, "fit_ok": "" if r.fit_ok is None else r.fit_ok,
                "fit_worst_band_rel_rms": "" if w is None else w["rel_rms"],
                "fit_worst_band_deg": "" if w is None else f"{w['lo_deg']:g}-{w['hi_deg']:g}",
                "accuracy_rh02": _blank(r.accuracy("rh02")), "accuracy_bands": _blank(r.accuracy("bands")),
                "above_rh02": "" if not r.ok else r.accuracy("rh02") > self.threshold,
                "above_bands": "" if not r.ok else r.accuracy("bands") > self.threshold,
                "F_needed": _blank(r.F_needed), "P_needed": _blank(r.P_needed), "eps_needed": _blank(r.eps_needed),
                "capped": _blank(r.capped), "anisotropy": _blank(r.anisotropy), "anisotropic": _blank(r.anisotropic),
                "grazing_share": _blank(r.grazing_share), "missing_share": _blank(r.missing_share),
                "reasons": ";".join(r.reasons), "reason_text": r.reason_text, "error": r.error or "",
                "seconds": round(r.seconds, 3),
            }
            for key, acc in (("acc_rh02", r.accuracy_rh02), ("acc_bands", r.accuracy_bands)):
                for p in range(self.P + 1):
                    row[f"{key}_P{p}"] = acc[p] if acc else ""
            out.append(row)
        return out

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (``data_specs/census_json.md``)."""
        n = len(self.rows)
        return {
            "F": self.F, "P": self.P, "threshold": self.threshold, "eps": self.eps, "criterion": self.criterion,
            "max_view_deg": self.max_view_deg, "max_F": self.max_F, "max_P": self.max_P, "fit": dict(self.fit),
            "n": n, "n_failed": self.n_failed,
            "count_above": {c: [self.count_above(c, p) for p in range(self.P + 1)] for c in ("rh02", "bands")},
            "count_line": self.count_line(), "reasons": dict(REASONS), "seconds": self.seconds,
            "rows": [r.as_dict() for r in self.rows],
        }


def _blank(value: Any) -> Any:
    """``""`` for None or NaN (an empty CSV cell), else the value."""
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return ""
    return value


def census_sources(paths: Iterable[str | Path]) -> list[str]:
    """The BRDFs a list of arguments names: a folder gives its BRDF files (by the suffixes of
    ``BRDF_FILE_TYPES``, sorted, not recursive), a multi-BRDF file its members (the 61 CURET
    samples, a CSV's wavelengths: ``brdf_sources``), anything else itself.

    Raises
    ------
    BadInputError
        A folder that cannot be listed; as ``brdf_sources`` when a file's members cannot be listed
        (a multi-BRDF file that cannot be read is then one source, and one failed row).
    """
    out: list[str] = []
    for item in paths:
        path = Path(item)
        if path.is_dir():
            try:
                files = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in BRDF_FILE_TYPES)
            except OSError as err:
                raise BadInputError(path, f"cannot list the folder ({err.strerror or err})") from None
            out += [m for f in files for m in _members(str(f))]
        else:
            out += _members(str(item))
    return out


def _members(source: str) -> list[str]:
    try:
        return brdf_sources(source)
    except ShrmError:
        return [source]  # read again by its row, which fails with the reader's message


def _curet_members_once(load: Callable[[str], BRDF]) -> Callable[[str], BRDF]:
    """``load``, except that the members of a CURET ``abrdf.dat`` named by number (``abrdf.dat#7``)
    come from one parse of the file (``read_curet_all``): reading one sample parses the whole
    61-sample file (0.24 s), which a census of the 61 would do 61 times. Anything else, and a file
    ``read_curet_all`` refuses, goes to ``load`` (which then names the problem)."""
    parsed: dict[str, dict[str, BRDF] | None] = {}

    def load_member(source: str) -> BRDF:
        base, sep, selector = source.rpartition("#")
        if sep and Path(base).suffix.lower() == ".dat" and selector.strip().isdigit():
            if base not in parsed:
                try:
                    members_read: dict[str, BRDF] = {}
                    for b in read_curet_all(base):
                        assert b.source is not None  # read_curet_all names each member FILE#N
                        members_read[str(int(b.source.rpartition("#")[2]))] = b
                    parsed[base] = members_read
                except ShrmError:
                    parsed[base] = None
            members = parsed[base]
            key = str(int(selector))
            if members is not None and key in members:
                return members[key]
        return load(source)

    return load_member


def grazing_share(choice: OrderChoice, F: int, P: int) -> float:
    """Share of the energy missed at (F, P) that lies in the view bands beyond the view limit.

    Per θ_v band b: ε_b(F, P) (``OrderChoice.view_bands``: energy fraction of the band missed,
    worst channel) times the band's energy of ρ̂, ∫_b density · 2 sin 2θ_v dθ_v over the profile's
    nodes (sin θ_o' dθ_o' = 2 sin 2θ_v dθ_v, ``ViewProfile.energy``), channels summed. 0 when
    nothing is missed.
    """
    profile = choice.profile
    density = profile.full().sum(axis=0) + profile.beyond  # (K, 3)
    band_energy = profile.band_sum((2.0 * np.sin(2.0 * profile.theta_v))[:, None] * density).sum(axis=1)
    bands = choice.view_bands(F, P)
    missed = np.array([b["eps"] for b in bands]) * band_energy
    outside = np.array([not b["inside"] for b in bands])
    total = float(missed.sum())
    return float(missed[outside].sum() / total) if total > 0 else 0.0


def _table_missing_share(choice: OrderChoice) -> float:
    """Share of the 3-D reparameterized grid's samples (``n_theta_i · n_theta_o · n_phi``) that had
    no measurement to interpolate (``ReparamBRDF.n_without_data``)."""
    g = choice.grid
    assert choice.source is not None  # choose_orders keeps its grid data
    reparam = choice.source.reparam  # read by the RH02 table already
    return reparam.n_without_data / max(int(g.n_theta_i * g.n_theta_o * g.n_phi), 1)


def _reasons(row: dict[str, Any], choice: RepresentationChoice | None, threshold: float,
             max_view_deg: float) -> tuple[tuple[str, ...], str]:
    """(codes, text) of :data:`REASONS` for a row that misses ``threshold`` or whose fit fails."""
    acc_r, acc_b = row["accuracy_rh02"][-1], row["accuracy_bands"][-1]
    missed = acc_r <= threshold or acc_b <= threshold
    fit_failed = choice is not None and not choice.success
    if not (missed or fit_failed):
        return (), ""
    codes, text = [], []
    if fit_failed:
        assert choice is not None  # fit_failed
        codes.append("fit")
        text.append(f"fit error: {choice.label()} has held-out worst view band {choice.chosen.band_text()}, above "
                    f"{FIT_FAIL_BAND_REL_RMS:g}")
    if row["missing_share"] is not None and row["missing_share"] > MISSING_SHARE:
        codes.append("missing")
        text.append(f"missing data: {row['missing_share']:.1%} of the samples had no measurement")
    if row["anisotropic"]:
        assert choice is not None and choice.isotropy is not None  # row["anisotropic"] comes from the choice's isotropy
        codes.append("anisotropy")
        text.append(f"anisotropy: {choice.isotropy.line()}")
    if missed:
        share = row["grazing_share"]
        if share > GRAZING_SHARE:
            codes.append("grazing")
            text.append(f"grazing energy: {share:.0%} of the energy missed at (F, P) lies beyond {max_view_deg:g}°")
        if not codes:
            codes.append("orders")
            text.append(f"orders: needs (F, P) = ({row['F_needed']}, {row['P_needed']})"
                        + (" (capped)" if row["capped"] else "") + f"; {1 - share:.0%} of the missed energy lies "
                        f"inside {max_view_deg:g}°")
    return tuple(codes), "; ".join(text)


def _census_row(
    source: str, *, F: int, P: int, threshold: float, rule: OrderRule, fit: dict[str, Any],
    load: Callable[[str], BRDF], represent: tuple[str, Callable[[BRDF], BRDF]] | None,
) -> CensusRow:
    t0 = time.perf_counter()
    try:
        brdf = load(source)
    except _ROW_ERRORS as err:
        return _failed(source, "", "", err, t0)
    name, kind = str(getattr(brdf, "name", source)), str(getattr(brdf, "kind", ""))
    try:
        choice = None
        analysed = brdf
        if kind == "scattered" and represent is not None:
            analysed = represent[1](brdf)
        elif kind == "scattered":
            choice = choose_representation(brdf, candidates=tuple(fit["candidates"]), folds=fit["folds"],
                                           seed=fit["seed"], max_theta_deg=fit["max_theta_deg"])
            analysed = choice.brdf
        # the accuracy table on the grid of (F, P): the bands rule at its default tolerance and caps
        grid = orders_on_grid_for(analysed, F, P, rule=OrderRule(criterion="bands", max_view_deg=rule.max_view_deg))
        needed = choose_orders(analysed, rule=rule)
        acc_r = tuple(float(v) for v in 1.0 - grid.rh02_table[F, : P + 1])
        acc_b = tuple(float(v) for v in 1.0 - grid.table[F, : P + 1])
        # scattered data: the representation fills between the measurements, and its held-out error
        # says how well; a table: the reparameterized samples that had no measurement to interpolate
        missing = None if choice is not None else _table_missing_share(grid)
        iso = None if choice is None else choice.isotropy
        row: dict[str, Any] = {
            "accuracy_rh02": acc_r, "accuracy_bands": acc_b, "F_needed": int(needed.F), "P_needed": int(needed.P),
            "eps_needed": float(needed.eps), "capped": bool(needed.capped), "grazing_share": grazing_share(grid, F, P),
            "missing_share": missing, "anisotropy": None if iso is None else float(iso.anisotropy),
            "anisotropic": None if iso is None else bool(iso.anisotropic and iso.judged),
        }
    except _ROW_ERRORS as err:
        return _failed(source, name, kind, err, t0)
    codes, text = _reasons(row, choice, threshold, rule.max_view_deg)
    worst = None if choice is None or choice.chosen.held_out_worst is None else choice.chosen.held_out_worst.as_dict()
    if choice is not None:
        representation = choice.label()
    elif kind != "scattered":
        representation = "as given"
    else:
        assert represent is not None  # scattered data without a choice went through represent
        representation = represent[0]
    return CensusRow(
        source=source, name=name, status="ok", kind=kind,
        representation=representation,
        model="" if choice is None else choice.model,
        fit_ok=None if choice is None else bool(choice.success), fit_worst=worst, reasons=codes, reason_text=text,
        seconds=time.perf_counter() - t0, representation_record=None if choice is None else choice.as_dict(), **row,
    )


#: What makes one row fail instead of the census: the library's own errors, a file system refusal,
#: and the numerical errors a hostile file can still raise deep in the analysis.
_ROW_ERRORS = (ShrmError, OSError, ValueError, FloatingPointError, np.linalg.LinAlgError)


def _failed(source: str, name: str, kind: str, err: Exception, t0: float) -> CensusRow:
    message = " ".join(str(err).split()) if isinstance(err, ShrmError) else f"{source}: {type(err).__name__}: {err}"
    message = " ".join(message.split())
    codes = ("error", "anisotropy") if "anisotrop" in message.lower() else ("error",)
    return CensusRow(source=source, name=name, status="failed", kind=kind, reasons=codes,
                     reason_text=f"could not be analysed: {message}", error=message,
                     seconds=time.perf_counter() - t0)


def run_census(
    sources: Sequence[str | Path],
    *,
    F: int = DEFAULT_F,
    P: int = DEFAULT_P,
    threshold: float = DEFAULT_THRESHOLD,
    rule: OrderRule | None = None,
    candidates: tuple[str, ...] = CANDIDATES,
    folds: int = DEFAULT_FOLDS,
    seed: int = 0,
    max_theta_deg: float = 80.0,
    load: Callable[[str], BRDF] = load_brdf,
    progress: Callable[[int, int, CensusRow], None] | None = None,
    represent: tuple[str, Callable[[BRDF], BRDF]] | None = None,
    workers: int = 1,
) -> Census:
    """Tabulate a BRDF library: one :class:`CensusRow` per source.

    ``workers`` > 1 computes the rows in that many spawned processes (one BLAS and one ducc0
    thread each); the rows are the same numbers as a serial census (each row depends only on its
    source and the settings), in the order given; a source whose process dies (killed for memory, a
    crash) is retried alone in a fresh process, and is one failed row if that one dies too.

    Parameters
    ----------
    sources
        BRDF sources for ``load`` (file members such as ``abrdf.dat#7``, paths, specs);
        :func:`census_sources` expands folders and multi-BRDF files.
    F, P
        Orders of the accuracy table: 1 − ε(F, p) for p = 0…P (RH02 Fig. 8: 30, 5).
    threshold
        Accuracy mark in (0, 1) (RH02 Fig. 8: 0.9).
    rule
        The order rule of the orders needed (:class:`~shrmkit.analysis.order_rule.OrderRule`,
        ``choose_orders``; default ``OrderRule()``).
    candidates, folds, seed, max_theta_deg
        The representation choice of scattered data (``choose_representation``).
    load
        Reads one source (default ``load_brdf``; the CLI passes its RGL-aware loader).
    progress
        Called as ``progress(done, total, row)`` after each row (with ``workers`` > 1, in the
        order the rows finish; ``done`` counts them).
    represent
        ``(label, function)``: analyse scattered data through ``function(brdf)`` (a BRDF
        evaluable everywhere) instead of the representation choice, e.g. CURET's published
        55-term least-squares Zernike fits (``benchmarks/fig8_curet.py``); those rows then
        have no fit error or anisotropy, and ``fit`` says ``label``.
    workers
        Processes computing the rows (1..:data:`MAX_WORKERS`; default 1: in this process).
        With more, ``load`` and ``represent`` must be picklable (module-level functions or
        ``functools.partial`` of them); the rows are the serial census' numbers, in the order of
        ``sources`` (above).

    Returns
    -------
    Census

    Raises
    ------
    BadInputError
        Bad settings (orders, threshold, a ``rule`` that is not an ``OrderRule``, candidates, folds,
        workers): checked before any row. A source that cannot be read or analysed is a failed row.
    """
    t0 = time.perf_counter()
    if not (isinstance(F, int | np.integer) and 0 <= F <= DEFAULT_MAX_F):
        raise BadInputError(None, f"F must be an integer in 0..{DEFAULT_MAX_F}, got {F!r}")
    if not (isinstance(P, int | np.integer) and 0 <= P <= DEFAULT_MAX_P):
        raise BadInputError(None, f"P must be an integer in 0..{DEFAULT_MAX_P}, got {P!r}")
    if not (isinstance(threshold, float | int) and 0.0 < threshold < 1.0):
        raise BadInputError(None, f"threshold must be a number in (0, 1), got {threshold!r}")
    rule = resolve_rule(rule)
    unknown = [c for c in candidates if c not in CANDIDATES]
    if unknown or not candidates:
        raise BadInputError(None, f"unknown representation(s) {unknown}; choose from {', '.join(CANDIDATES)}")
    if not (isinstance(folds, int | np.integer) and folds >= 2):
        raise BadInputError(None, f"folds must be an integer >= 2, got {folds!r}")
    if not (np.isfinite(max_theta_deg) and 0.0 < max_theta_deg <= 90.0):
        raise BadInputError(None, f"max_theta_deg must be in (0, 90], got {max_theta_deg!r}")
    fit = {"candidates": list(candidates), "folds": int(folds), "seed": int(seed),
           "max_theta_deg": float(max_theta_deg), "represent": None if represent is None else str(represent[0])}
    if not (isinstance(workers, int | np.integer) and 1 <= workers <= MAX_WORKERS):
        raise BadInputError(None, f"workers must be an integer in [1, {MAX_WORKERS}], got {workers!r}")
    settings: dict[str, Any] = {
        "F": int(F), "P": int(P), "threshold": float(threshold), "rule": rule, "fit": fit, "represent": represent}
    names = [str(source) for source in sources]
    if workers > 1 and len(names) > 1:
        try:
            pickle.dumps((load, represent))
        except (pickle.PicklingError, AttributeError, TypeError) as err:
            raise BadInputError(None, f"workers > 1 need a picklable load and represent ({err})") from None
        rows = _rows_in_processes(names, settings, load, int(workers), progress)
    else:
        rows = []
        load = _curet_members_once(load)
        with single_threaded_blas():
            for i, source in enumerate(names):
                rows.append(_census_row(source, load=load, **settings))
                if progress is not None:
                    progress(i + 1, len(names), rows[-1])
    return Census(rows=tuple(rows), F=int(F), P=int(P), threshold=float(threshold), rule=rule, fit=fit,
                  seconds=time.perf_counter() - t0)


#: The loader of a census worker process (``_start_worker``): the census' ``load`` behind
#: ``_curet_members_once``, so that each process parses a CURET file once. Set once per spawned
#: worker, never in the parent.
_WORKER_LOAD: list[Callable[[str], BRDF]] = []


def _start_worker(load: Callable[[str], BRDF]) -> None:
    """Initializer of a census worker: one BLAS thread and one ducc0 thread (the workers share
    the cores), and the loader."""
    threadpool_limits(limits=1)  # stays in force for the worker's life
    ducc0.misc.resize_thread_pool(1)
    _WORKER_LOAD.append(_curet_members_once(load))


def _worker_row(source: str, settings: dict[str, Any]) -> CensusRow:
    """One row in a worker process (``_start_worker`` ran)."""
    return _census_row(source, load=_WORKER_LOAD[-1], **settings)


def _rows_in_processes(
    sources: list[str], settings: dict[str, Any], load: Callable[[str], BRDF], workers: int,
    progress: Callable[[int, int, CensusRow], None] | None,
) -> list[CensusRow]:
    """The rows of ``sources`` in ``workers`` spawned processes, in the order of ``sources``.

    A process that dies breaks its pool: the rows it had not finished are computed again, each
    alone in a fresh one-process pool, and a source whose own process dies is a failed row."""
    context = multiprocessing.get_context("spawn")  # no fork of a process holding BLAS/ducc0 threads
    rows: dict[int, CensusRow] = {}

    def finish(i: int, row: CensusRow) -> None:
        rows[i] = row
        if progress is not None:
            progress(len(rows), len(sources), row)

    def run(indexes: list[int], n_workers: int) -> list[int]:
        """Rows of ``indexes``; returns those lost to a dead process."""
        lost: list[int] = []
        with ProcessPoolExecutor(n_workers, mp_context=context, initializer=_start_worker,
                                 initargs=(load,)) as pool:
            futures: dict[Future[CensusRow], int] = {pool.submit(_worker_row, sources[i], settings): i
                                                     for i in indexes}
            for future in as_completed(futures):
                try:
                    finish(futures[future], future.result())
                except BrokenProcessPool:
                    lost.append(futures[future])
        return sorted(lost)

    lost = run(list(range(len(sources))), min(workers, len(sources)))
    for i in lost:
        t0 = time.perf_counter()
        if run([i], 1):
            finish(i, _failed(sources[i], "", "", BadInputError(
                sources[i], "the worker process analysing it died (killed for memory, or a crash)"), t0))
    return [rows[i] for i in range(len(sources))]
