"""One order choice (issue 29): ``shrm orders`` and ``shrm report`` choose the same (F, P) for the
same BRDF and ε; orders forced on ``prefilter`` beyond what the map holds are clamped, said once,
and the metadata tells the orders used and asked."""

from __future__ import annotations

import json
import warnings

import pytest

from shrmkit.analysis.orders import DEFAULT_MAX_F, DEFAULT_MAX_P, OrdersClampedWarning
from shrmkit.analysis.shrm import prefilter
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.main import build_parser, main
from shrmkit.cli.report.collect import _orders
from shrmkit.cli.report.options import profile


def test_report_and_orders_share_the_caps_and_rule() -> None:
    """The search depends on the caps even below them (it starts from ε(min(F0, max_F), p)): the
    report's defaults are those of ``shrm orders``."""
    args = build_parser().parse_args(["orders", "phong:s=8"])
    options = profile()
    assert (options.max_F, options.max_P) == (args.max_F, args.max_P) == (DEFAULT_MAX_F, DEFAULT_MAX_P)
    assert (options.criterion, options.max_view_deg) == (args.criterion, args.max_view_deg)


def test_report_chooses_what_orders_chooses(capsys) -> None:
    spec, eps = "microfacet:sigma=0.15", 0.03
    assert main(["orders", spec, "--eps", str(eps), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    rows, _, _ = _orders(load_brdf(spec), profile().with_changes(tolerances=(eps,), eps=eps))
    row = next(r for r in rows if r["tolerance"] == eps)
    assert (row["F"], row["P"]) == (doc["F"], doc["P"])


def test_forced_orders_beyond_the_map_are_clamped_and_said() -> None:
    """A 16-row map holds the lighting to l = 15: F = 100 becomes 15, with one warning line, and
    the metadata keeps both."""
    with pytest.warns(OrdersClampedWarning, match=r"F=15 used, F=100 asked") as record:
        shrm = prefilter("builtin:constant,height=16", "phong:s=8", F=100, P=0, lights="none")
    assert len(record) == 1 and "\n" not in str(record[0].message)
    assert shrm.F == 15 and shrm.meta["orders_asked"] == {"F": 100, "P": 0}
    assert "orders asked (F=100, P=0)" in shrm.meta["orders_message"]
    assert "F=15 used, F=100 asked" in shrm.meta["orders_message"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        kept = prefilter("builtin:constant,height=16", "phong:s=8", F=6, P=0, lights="none")
    assert kept.F == 6 and "clamped" not in kept.meta["orders_message"]
    chosen = prefilter("builtin:constant,height=16", "phong:s=8", eps=0.1, lights="none")
    assert chosen.meta["orders_asked"] is None
