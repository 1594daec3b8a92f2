"""Fit-error table: the old headline (relative RMS over all samples) against the worst view band.

For every scattered measurement in ../shared/data — the 5 Cornell paints, the 61 CURET samples,
NIST PTFE at its 4 wavelengths and its random set — each candidate representation of
``analysis.fit.representation`` (one-lobe Lafortune, Cook–Torrance, cross-validated Zernike) is
fitted as ``shrm orders`` / ``shrm report`` / ``shrm census`` fit it
(``choose_representation`` with its defaults: samples to 80°, 5-fold cross-validation, seed 0),
and the table gives, per model:

- ``headline``: the relative RMS of ρ cos θ_i over all the measured samples, on the samples the
  model was fitted to — the number ``shrm fit`` printed alone before issue 24;
- ``worst``: the worst view band (θ_o bands of ``summary.DEFAULT_BANDS_DEG`` with at least 10
  samples) of the same fit on the same samples — what ``shrm fit`` now prints beside it and
  judges by (``FAILED`` above ``FIT_FAIL_BAND_REL_RMS`` = 0.5);
- ``held-out``: the worst view band of the held-out predictions (each sample predicted by a fit
  that never saw it) — what the chooser ranks by and what every verb prints beside the orders.

then the representation chosen and its verdict (held-out worst band ≤ 0.5). For a Zernike fit
the headline and worst band are its training errors at the (order, ridge) the cross-validation
chose. Cornell and NIST are printed whole; CURET as counts and its 10 worst rows (by the chosen
representation's held-out worst band); every row goes to ``fit_error_table.csv`` under ``--out``
(default ``<tempdir>/fit_error_table``; never into the repository).

Run:  .venv/bin/python benchmarks/fit_error_table.py [--workers 2] [--out DIR] [--only cornell nist curet]
"""

from __future__ import annotations

import argparse
import csv
import multiprocessing
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from shrmkit.analysis.census import census_sources
from shrmkit.analysis.fit.representation import CANDIDATES, choose_representation
from shrmkit.analysis.fit.summary import FIT_FAIL_BAND_REL_RMS
from shrmkit.brdf_io.errors import ShrmError
from shrmkit.brdf_io.specs import load_brdf

__all__ = ["main", "table_row"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "brdf"
GROUPS = {
    "cornell": ["cornell"],
    "nist": ["nist_ptfe/PTFE.data.csv", "nist_ptfe/PTFE.data.random.csv"],
    "curet": ["curet/abrdf.dat"],
}
SHORT = {"lafortune": "Laf", "cook-torrance": "CT", "zernike": "Zer"}


def _band(band: dict[str, Any] | None) -> tuple[float, str]:
    if band is None:
        return float("nan"), ""
    return float(band["rel_rms"]), f"{band['lo_deg']:g}-{band['hi_deg']:g}"


def table_row(group: str, source: str) -> dict[str, Any]:
    """One material: every candidate's headline, worst band and held-out worst band, the choice
    and its verdict (flat, CSV-ready). A source that cannot be fitted gives its error."""
    t = os.times()
    t0 = time.perf_counter()
    row: dict[str, Any] = {"group": group, "source": source, "name": "", "error": ""}
    try:
        brdf = load_brdf(source)
        row["name"] = str(brdf.name)
        choice = choose_representation(brdf)
    except (ShrmError, OSError, ValueError) as err:
        row["error"] = " ".join(str(err).split())
        return row
    doc = choice.as_dict()
    row["n_samples"] = choice.n_samples
    for cand in doc["candidates"]:
        key = SHORT[cand["model"]]
        if cand["error"]:
            row[f"{key}_error"] = cand["error"]
            continue
        row[f"{key}_headline"] = cand["training_rel_rms"]
        row[f"{key}_worst"], row[f"{key}_worst_band"] = _band(cand["training_worst_band"])
        row[f"{key}_held_out"], row[f"{key}_held_out_band"] = _band(cand["held_out_worst_band"])
        row[f"{key}_held_out_all"] = cand["held_out_rel_rms"]
        row[f"{key}_detail"] = cand["detail"]
    chosen = choice.chosen
    row["chosen"] = choice.label()
    row["chosen_model"] = choice.model
    row["chosen_held_out"] = chosen.score
    row["verdict"] = "ok" if choice.success else "FAILED"
    row["anisotropy"] = "" if choice.isotropy is None else choice.isotropy.anisotropy
    row["cpu_seconds"] = (lambda e: e.user - t.user + e.system - t.system)(os.times())
    row["seconds"] = time.perf_counter() - t0
    return row


def _fmt(value: Any) -> str:
    return "—" if value is None or value == "" or value != value else f"{value:.3g}"


def _cell(row: dict[str, Any], key: str) -> str:
    if f"{key}_error" in row:
        return "not fitted"
    mark = lambda v: f"**{_fmt(v)}**" if v == v and v > FIT_FAIL_BAND_REL_RMS else _fmt(v)  # noqa: E731
    return (f"{_fmt(row.get(f'{key}_headline'))} / {mark(row.get(f'{key}_worst', float('nan')))} / "
            f"{mark(row.get(f'{key}_held_out', float('nan')))}")


def markdown(rows: list[dict[str, Any]]) -> str:
    """Markdown table: per model headline / worst band / held-out worst band (bold above 0.5)."""
    head = ("| material | " + " | ".join(f"{SHORT[m]}: headline / worst / held-out" for m in CANDIDATES)
            + " | chosen (held-out worst band) | verdict |")
    lines = [head, "|" + "---|" * (len(CANDIDATES) + 3)]
    for r in rows:
        if r["error"]:
            lines.append(f"| {r['name'] or r['source']} | error: {r['error']} |" + " |" * (len(CANDIDATES) + 1))
            continue
        short = r["chosen"].replace(" terms", "").replace("zernike order", "Zernike")
        lines.append(f"| {r['name']} | " + " | ".join(_cell(r, SHORT[m]) for m in CANDIDATES)
                     + f" | {short}: {_fmt(r['chosen_held_out'])} | {r['verdict']} |")
    return "\n".join(lines)


def counts(rows: list[dict[str, Any]]) -> str:
    """What the headline hid, per model: fits whose headline is at most 0.5 but whose worst band
    (own samples) or held-out worst band is above it."""
    ok = [r for r in rows if not r["error"]]
    out = [f"{len(ok)} materials ({len(rows) - len(ok)} could not be fitted)"]
    for m in CANDIDATES:
        k = SHORT[m]
        fitted = [r for r in ok if f"{k}_error" not in r]
        good_head = [r for r in fitted if r[f"{k}_headline"] <= FIT_FAIL_BAND_REL_RMS]
        hid_train = sum(1 for r in good_head if r[f"{k}_worst"] > FIT_FAIL_BAND_REL_RMS)
        hid_held = sum(1 for r in good_head if r[f"{k}_held_out"] > FIT_FAIL_BAND_REL_RMS)
        fail_train = sum(1 for r in fitted if r[f"{k}_worst"] > FIT_FAIL_BAND_REL_RMS)
        fail_held = sum(1 for r in fitted if r[f"{k}_held_out"] > FIT_FAIL_BAND_REL_RMS)
        out.append(f"- {m}: headline ≤ 0.5 in {len(good_head)} of {len(fitted)}; worst band > 0.5 in {fail_train} "
                   f"({hid_train} of them with a headline ≤ 0.5); held-out worst band > 0.5 in {fail_held} "
                   f"({hid_held} with a headline ≤ 0.5)")
    chosen: dict[str, int] = {}
    for r in ok:
        chosen[r["chosen_model"]] = chosen.get(r["chosen_model"], 0) + 1
    failed = [r["name"] for r in ok if r["verdict"] != "ok"]
    out.append("- chosen: " + ", ".join(f"{m} {n}" for m, n in sorted(chosen.items()))
               + f"; FAILED (held-out worst band > 0.5): {len(failed)}" + (f" ({', '.join(failed)})" if failed else ""))
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=DATA, help=f"the shared brdf folder (default {DATA})")
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "fit_error_table")
    parser.add_argument("--workers", type=int, default=1, help="processes (spawned; default 1)")
    parser.add_argument("--only", nargs="+", choices=tuple(GROUPS), default=list(GROUPS))
    parser.add_argument("--worst", type=int, default=10, help="CURET rows printed (worst held-out first)")
    args = parser.parse_args(argv)
    if not args.data.exists():
        print(f"{args.data}: shared data not found (only in the project workspace); nothing to do", file=sys.stderr)
        return 1
    tasks = [(g, s) for g in args.only for item in GROUPS[g] for s in census_sources([args.data / item])]
    t = os.times()
    t0 = time.perf_counter()
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            rows = list(pool.map(table_row, *zip(*tasks, strict=True)))
    else:
        rows = [table_row(g, s) for g, s in tasks]
    cpu = (lambda e: e.user - t.user + e.system - t.system + e.children_user - t.children_user
           + e.children_system - t.children_system)(os.times())
    print(f"Fit errors, relative RMS of ρ cos θ_i (chooser defaults: samples to 80°, 5-fold CV, seed 0). "
          f"Each model cell: headline (all samples, own fit) / worst view band (own fit) / held-out worst band; "
          f"bold above {FIT_FAIL_BAND_REL_RMS:g}.\n")
    for group in args.only:
        rows_g = [r for r in rows if r["group"] == group]
        print(f"### {group} ({len(rows_g)})\n")
        print(counts(rows_g) + "\n")
        shown = rows_g
        if group == "curet":
            shown = sorted((r for r in rows_g if not r["error"]), key=lambda r: -r["chosen_held_out"])[: args.worst]
            shown += [r for r in rows_g if r["error"]]
            print(f"The {len(shown)} worst by the chosen representation's held-out worst band:\n")
        print(markdown(shown) + "\n")
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "fit_error_table.csv"
    fields: list[str] = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    with open(path, "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    print(f"{len(rows)} materials in {time.perf_counter() - t0:.1f} s wall, {cpu:.1f} s CPU "
          f"({args.workers} worker(s)); full table: {path}")
    return 0 if not any(r["error"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
