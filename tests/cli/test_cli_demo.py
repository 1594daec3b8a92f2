"""`shrm demo`: the whole pipeline on built-in data, from a clean folder."""

from __future__ import annotations

import json

import numpy as np
import pytest

import shrmkit
from shrmkit.cli.report.demo import DEMO_MATERIALS


@pytest.mark.slow
def test_demo_end_to_end(demo_run):
    """`shrm demo` from a clean folder (the run of the demo_run fixture of tests/conftest.py,
    which tests/cli/report/test_live_preview.py opens in a browser too)."""
    assert demo_run.code == 0
    out = demo_run.out
    printed = demo_run.printed
    for step in ("MERL files", "orders", "fit", "prefilter", "render", "reports"):
        assert f"{step}:" in printed
    # every path printed exists (relative to the folder the demo ran in)
    paths = [line.strip() for line in printed.splitlines() if line.startswith("    ")]
    assert paths and all((demo_run.cwd / p).exists() for p in paths)
    assert all((demo_run.cwd / p).resolve().is_relative_to(out.resolve()) for p in paths)
    # the MERL files hold the analytic materials: compare with direct evaluation of the spec
    rng = np.random.default_rng(1)
    L = rng.normal(size=(200, 3))
    V = rng.normal(size=(200, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]) + 0.3, np.abs(V[:, 2]) + 0.3
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for name, spec in DEMO_MATERIALS.items():
        table = shrmkit.load_brdf(out / "brdfs" / f"{name}.binary")
        exact = shrmkit.load_brdf(spec).eval(L, V)
        got = table.eval(L, V)
        assert np.sqrt(np.mean((got - exact) ** 2) / np.mean(exact**2)) < 0.1
    fit = json.loads((out / "fits" / "red-plastic.fit.json").read_text())
    assert fit["errors"]["rel_rms"] < 0.05  # a Lafortune lobe fits a tabulated Lafortune lobe
    assert (out / "render" / "red-plastic.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "shrm" / "red-plastic.shrm.npz").is_file()
    summary = (out / "report" / "summary.csv").read_text().splitlines()
    assert len(summary) == 3 and all(",ok," in row for row in summary[1:])
