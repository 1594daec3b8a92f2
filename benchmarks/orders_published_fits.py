"""Orders (F, P) chosen for published Lafortune fits of real materials (RH02 §5.1, §7.1).

Reads two files of the shared data folder (never copied into the repository):

- ``brdf/fits/ngan2005_lafortune1lobe_merl.csv``: 100 one-lobe fits to MERL materials
  (Ngan, Durand, Matusik 2005), f = rho_d/π + rho_s (n+2)/(2π) ((Cxy(ux vx + uy vy)
  + Cz uz vz)/max(|Cxy|, |Cz|))^n;
- ``brdf/fits/lafortune_3lobe_pbrt_v1.txt``: six three-lobe RGB fits from pbrt-v1,
  f = diffuse/π + Σ_i (xy_i (wo.x wi.x + wo.y wi.y) + z_i wo.z wi.z)^e_i (negative base → 0),

builds :class:`shrmkit.brdf_io.models.Lafortune` models from them, runs
``choose_orders(eps)`` (default caps) on each and prints one row per material plus a
summary of the (F, eps=P) distribution. RH02 §7.1 reports P = 4 for a Lafortune skin fit at
eps < 0.03; the pbrt ``skin`` row is printed next to that.

Run:  .venv/bin/python benchmarks/orders_published_fits.py [--limit N] [--eps 0.03]
"""

from __future__ import annotations

import argparse
import csv
import re
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from shrmkit.analysis.orders import DEFAULT_MAX_F, DEFAULT_MAX_P, choose_orders
from shrmkit.brdf_io.models import Lafortune, LafortuneLobe, rgb

__all__ = ["Material", "load_ngan2005", "load_pbrt_lafortune", "main"]

DATA = Path("/work/shared/data")
NGAN_CSV = DATA / "brdf/fits/ngan2005_lafortune1lobe_merl.csv"
PBRT_TXT = DATA / "brdf/fits/lafortune_3lobe_pbrt_v1.txt"
RH02_SKIN_P = 4  # RH02 §7.1: P = 4 for a Lafortune skin fit at eps < 0.03

console = Console(width=200, highlight=False)


@dataclass(frozen=True)
class Material:
    """One published fit: its source, name, our model and the largest lobe exponent."""

    source: str
    name: str
    brdf: Lafortune
    max_n: float


def _finite(values: list[float], where: str) -> list[float]:
    if not all(np.isfinite(v) for v in values):
        raise ValueError(f"{where}: non-finite value in {values}")
    return values


def load_ngan2005(path: Path = NGAN_CSV) -> list[Material]:
    """One-lobe fits → Lafortune(kd = rho_d, lobe cxy = Cxy/m, cz = Cz/m, n, ks = rho_s (n+2)/(2π)).

    m = max(|Cxy|, |Cz|) is the normalization of the Ngan et al. form (data README): dividing
    the base by m before the power is the same as scaling the lobe coefficients by 1/m.
    """
    with path.open(newline="") as handle:
        rows = [line for line in handle if not line.startswith("#")]
    out = []
    for k, row in enumerate(csv.DictReader(rows), start=1):
        where = f"{path}:{row.get('name', k)}"
        rho_d = _finite([float(row[f"rho_d_{c}"]) for c in "rgb"], where)
        rho_s = _finite([float(row[f"rho_s_{c}"]) for c in "rgb"], where)
        cxy, cz, n = _finite([float(row["Cxy"]), float(row["Cz"]), float(row["n"])], where)
        m = max(abs(cxy), abs(cz))
        if m <= 0 or n < 0:
            raise ValueError(f"{where}: degenerate lobe Cxy={cxy}, Cz={cz}, n={n}")
        lobe = LafortuneLobe(cxy=rgb(cxy / m), cz=rgb(cz / m), n=rgb(n), ks=rgb(rho_s) * (n + 2.0) / (2.0 * np.pi))
        out.append(Material("ngan2005", row["name"], Lafortune(kd=rgb(rho_d), lobes=(lobe,)), n))
    return out


_ENTRY = re.compile(r"^\s*(\w+)\s*=\s*\{([^}]*)\}\s*;")


def load_pbrt_lafortune(path: Path = PBRT_TXT) -> list[Material]:
    """pbrt-v1 three-lobe fits → Lafortune(kd = diffuse, lobes (cxy = xy_i, cz = z_i, n = e_i, ks = 1)).

    ``_safe_pow`` in the model clamps a negative base to 0, as the data README asks.
    """
    sections: dict[str, dict[str, list[float]]] = {}
    current = None
    for line in path.read_text().splitlines():
        header = re.match(r"^\s*\[(\w+)\]\s*$", line)
        if header:
            current = sections.setdefault(header.group(1), {})
            continue
        entry = _ENTRY.match(line)
        if entry and current is not None:
            values = [float(v) for v in entry.group(2).split(",")]
            if len(values) != 3:
                raise ValueError(f"{path}: {entry.group(1)} needs 3 values, got {values}")
            current[entry.group(1)] = _finite(values, f"{path}:{entry.group(1)}")
    out = []
    for name, entries in sections.items():
        n_lobes = sum(1 for key in entries if key.startswith("xy"))
        lobes = tuple(
            LafortuneLobe(cxy=rgb(entries[f"xy{i}"]), cz=rgb(entries[f"z{i}"]), n=rgb(entries[f"e{i}"]), ks=rgb(1.0))
            for i in range(n_lobes)
        )
        max_n = max(max(entries[f"e{i}"]) for i in range(n_lobes))
        out.append(Material("pbrt-v1", name, Lafortune(kd=rgb(entries["diffuse"]), lobes=lobes), max_n))
    return out


@dataclass
class Row:
    material: Material
    F: int = -1
    P: int = -1
    eps: float = float("nan")
    capped: bool = False
    converged: bool = False
    seconds: float = float("nan")
    message: str = ""
    error: str = ""


def run(materials: list[Material], eps: float) -> list[Row]:
    rows = []
    for mat in materials:
        row = Row(mat)
        t0 = time.perf_counter()
        try:
            oc = choose_orders(mat.brdf, eps=eps)
        except Exception as exc:  # a benchmark reports every failure instead of stopping
            row.error = f"{type(exc).__name__}: {exc}"
        else:
            row.F, row.P, row.eps, row.capped, row.converged = oc.F, oc.P, oc.eps, oc.capped, oc.converged
            row.message = oc.message
            if not np.all(np.isfinite(oc.table)):
                row.error = "non-finite entries in the ε table"
        row.seconds = time.perf_counter() - t0
        rows.append(row)
    return rows


def print_rows(rows: list[Row], eps: float) -> None:
    table = Table(title=f"choose_orders(eps={eps:g}), caps F <= {DEFAULT_MAX_F}, P <= {DEFAULT_MAX_P}", box=None)
    for col in ("source", "material", "max n", "F", "P", "ε(F,P)", "capped", "converged", "seconds", "note"):
        table.add_column(col, justify="left" if col in ("source", "material", "note") else "right")
    for r in rows:
        note = r.error or r.message
        table.add_row(
            r.material.source,
            r.material.name,
            f"{r.material.max_n:.4g}",
            str(r.F) if r.F >= 0 else "-",
            str(r.P) if r.P >= 0 else "-",
            f"{r.eps:.4f}",
            "CAPPED" if r.capped else "no",
            "yes" if r.converged else "NO",
            f"{r.seconds:.2f}",
            note[:90],
        )
    console.print(table)


def print_summary(rows: list[Row], eps: float) -> None:
    ok = [r for r in rows if not r.error]
    console.print(f"\nSummary over {len(rows)} materials ({len(ok)} without error):")
    if ok:
        Ps = np.array([r.P for r in ok])
        Fs = np.array([r.F for r in ok])
        hist = Table(title="histogram of P", box=None)
        hist.add_column("P", justify="right")
        hist.add_column("count", justify="right")
        hist.add_column("materials (first 6)", justify="left")
        for p in np.unique(Ps):
            names = [r.material.name for r in ok if r.P == p]
            hist.add_row(str(p), str(len(names)), ", ".join(names[:6]) + (" …" if len(names) > 6 else ""))
        console.print(hist)
        q = np.quantile(Fs, [0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0])
        console.print(
            "F quantiles: min {:.0f}, 10% {:.0f}, 25% {:.0f}, median {:.0f}, 75% {:.0f}, 90% {:.0f}, max {:.0f}".format(
                *q
            )
        )
        secs = np.array([r.seconds for r in rows])
        console.print(
            f"capped: {sum(r.capped for r in ok)}; not converged: {sum(not r.converged for r in ok)}; "
            f"ε above tolerance without the capped flag: {sum((r.eps > eps) and not r.capped for r in ok)}; "
            f"NaN ε: {sum(not np.isfinite(r.eps) for r in ok)}"
        )
        console.print(
            f"time per material: median {np.median(secs):.2f} s, max {secs.max():.2f} s, total {secs.sum():.1f} s"
        )
    errors = [r for r in rows if r.error]
    console.print(f"errors: {len(errors)}")
    for r in errors:
        console.print(f"  {r.material.source}/{r.material.name}: {r.error}")
    skin = [r for r in rows if r.material.name == "skin"]
    for r in skin:
        console.print(
            f"\nskin (pbrt-v1 three-lobe fit): F = {r.F}, P = {r.P}, ε = {r.eps:.4f} at tolerance {eps:g} — "
            f"RH02 §7.1 (a Lafortune skin fit, eps < 0.03): P = {RH02_SKIN_P}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--limit", type=int, default=None, help="only the first N Ngan et al. fits (all six pbrt fits always)"
    )
    parser.add_argument("--quick", action="store_true", help="same as --limit 8")
    parser.add_argument("--eps", type=float, default=0.03)
    args = parser.parse_args(argv)
    if not NGAN_CSV.is_file() or not PBRT_TXT.is_file():
        console.print(f"shared data missing ({NGAN_CSV} / {PBRT_TXT}): nothing to do")
        return 1
    limit = 8 if args.quick and args.limit is None else args.limit
    t0 = time.perf_counter()
    ngan = load_ngan2005()
    pbrt = load_pbrt_lafortune()
    console.print(f"loaded {len(ngan)} Ngan et al. one-lobe fits and {len(pbrt)} pbrt-v1 three-lobe fits")
    materials = pbrt + (ngan if limit is None else ngan[:limit])
    rows = run(materials, args.eps)
    print_rows(rows, args.eps)
    print_summary(rows, args.eps)
    console.print(f"total wall time {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
