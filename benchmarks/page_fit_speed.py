"""CPU of the view page's budget rule (``render._page_fit.fit_coefficients``) now and at an earlier
revision of that module (``--against``, default bfe2357, before the best-first search), interleaved,
min of ``--repeats``; with the choice (P', rows) of each and the largest differences between them:
the maps' (relative to their largest magnitude) and the stated error's (relative).

Cases (issue 22): the SHRMs (ε = 0.03) of ``cook-torrance:alpha=0.1,dist=ggx`` and ``phong:s=512``
under ``builtin:sky`` at 32 and 128 rows, and of ``../shared/data/brdf/rgl/cc_iris_purple_gem_rgb.bsdf``
(32 rows, ``max_F`` 96, as the quick report) when present; each under the bytes the quick report's
live view (3 MiB page) and ``shrm view`` (8 MiB page) left to its maps (measured once, kept here).
Phong s = 512 is azimuth-free (P = 0): one map, it fits, nothing is computed.

Run:  .venv/bin/python benchmarks/page_fit_speed.py [--against REV] [--repeats N]
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from types import ModuleType

import numpy as np
from rich.console import Console
from rich.table import Table

import shrmkit
from shrmkit.analysis.shrm import SHRM
from shrmkit.render import _page_fit
from shrmkit.render._page_fit import CoefficientFit

__all__ = ["main"]

ROOT = Path(__file__).resolve().parents[1]
IRIS = ROOT.parent / "shared" / "data" / "brdf" / "rgl" / "cc_iris_purple_gem_rgb.bsdf"

#: (BRDF, env rows, max_F, {page: bytes left to the maps}), the bytes as the quick report
#: (``shrm report --quick``) and ``shrm view`` computed them for these SHRMs.
CASES: list[tuple[str, int, int | None, dict[str, int]]] = [
    ("cook-torrance:alpha=0.1,dist=ggx", 32, None, {"report": 2_204_016, "view": 6_141_951}),
    ("cook-torrance:alpha=0.1,dist=ggx", 128, None, {"report": 2_019_858, "view": 5_957_625}),
    ("phong:s=512", 32, None, {"report": 2_200_746}),
    ("phong:s=512", 128, None, {"report": 2_016_897, "view": 5_957_916}),
    (str(IRIS), 32, 96, {"report": 1_837_644}),
]

console = Console(width=180, highlight=False)


def module_at(rev: str, folder: Path) -> ModuleType:
    """``render/_page_fit.py`` as it was at ``rev`` (``git show``), imported beside the current one."""
    text = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:render/_page_fit.py"],
                          capture_output=True, text=True, check=True).stdout
    path = folder / "_page_fit_at_rev.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("shrmkit.render._page_fit_at_rev", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def cpu(modules: tuple[ModuleType, ModuleType], shrm: SHRM, max_bytes: int, repeats: int
        ) -> tuple[list[float], list[CoefficientFit]]:
    """Min CPU seconds of each module's ``fit_coefficients`` on ``shrm`` and its result, interleaved."""
    seconds = [float("inf")] * len(modules)
    fits: list[CoefficientFit] = []
    for _ in range(repeats):
        fits = []
        for i, module in enumerate(modules):
            start = time.process_time()
            fits.append(module.fit_coefficients(shrm.coeffs, shrm.P, max_bytes))
            seconds[i] = min(seconds[i], time.process_time() - start)
    return seconds, fits


def positive(text: str) -> int:
    """``--repeats``: an integer of at least 1."""
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"must be an integer of at least 1, got {text!r}")
    return int(text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="bfe2357", help="git revision to compare with (default bfe2357)")
    parser.add_argument("--repeats", type=positive, default=3, metavar="N",
                        help="interleaved runs per case (default 3)")
    args = parser.parse_args(argv)
    table = Table(title=f"fit_coefficients CPU, now vs {args.against} (min of {args.repeats}, interleaved)")
    for column in ("BRDF", "rows", "SHRM maps", "page", "bytes", f"{args.against} (P', h×w)", "now (P', h×w)",
                   "added rel. RMS", f"{args.against} ms", "now ms", "ratio", "max Δ maps", "Δ error"):
        table.add_column(column, justify="left" if column in ("BRDF", "page") else "right")
    with tempfile.TemporaryDirectory() as tmp:
        before = module_at(args.against, Path(tmp))
        for brdf, rows, max_F, budgets in CASES:
            if brdf == str(IRIS) and not IRIS.is_file():
                console.print(f"[{IRIS} not found: case skipped]")
                continue
            env = shrmkit.load_env(f"builtin:sky,height={rows}")
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the RGL file's out-of-gamut note
                shrm = shrmkit.prefilter(env, brdf, eps=0.03, max_F=max_F)
            for page, max_bytes in budgets.items():
                (now_s, then_s), (now, then) = cpu((_page_fit, before), shrm, max_bytes, args.repeats)
                same = (now.P, now.coeffs.shape) == (then.P, then.coeffs.shape)
                d_maps = (np.abs(now.coeffs - then.coeffs).max() / max(np.abs(then.coeffs).max(), 1e-300)
                          if same else float("nan"))
                d_err = abs(now.added_rel_rms - then.added_rel_rms) / max(then.added_rel_rms, 1e-300)
                shape = f"{shrm.coeffs.shape[0]}×{shrm.coeffs.shape[1]}×{shrm.coeffs.shape[2]}"
                table.add_row(Path(brdf).name, str(rows), shape, page, f"{max_bytes:,}",
                              f"{then.P}, {then.coeffs.shape[1]}×{then.coeffs.shape[2]}",
                              f"{now.P}, {now.coeffs.shape[1]}×{now.coeffs.shape[2]}" + ("" if same else " DIFFERENT"),
                              f"{now.added_rel_rms:.4g}", f"{then_s * 1e3:.0f}", f"{now_s * 1e3:.0f}",
                              f"{then_s / max(now_s, 1e-9):.1f}", f"{d_maps:.1e}", f"{d_err:.1e}")
    console.print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
