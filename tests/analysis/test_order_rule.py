"""OrderRule (issue 27 point 4): the order rule as one value instead of five loose keywords.

References: the loose keywords of the same functions (the path before the rule), and the
constructor keywords of the options classes (their ``as_dict`` output must not change).
"""

from __future__ import annotations

import dataclasses
import inspect
import warnings

import pytest

from shrmkit.analysis import OrderRule
from shrmkit.analysis.compare import CompareOptions
from shrmkit.analysis.order_rule import RULE_FIELDS, resolve_rule
from shrmkit.analysis.orders import choose_orders, choose_orders_many, orders_on_grid_for
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.report.options import ReportOptions, profile

# cheap: a Phong lobe of low exponent needs few orders (well under a second per choice)
SPEC = "phong:s=8"


def test_rule_from_keywords_equals_explicit_rule() -> None:
    explicit = OrderRule(criterion="rh02", max_view_deg=70.0, eps=0.05, max_F=64, max_P=6)
    assert resolve_rule(None, criterion="rh02", max_view_deg=70, eps=0.05, max_F=64, max_P=6) == explicit
    assert resolve_rule(explicit, eps=0.05, max_view_deg=70) is explicit  # agreeing keywords: the rule itself
    assert OrderRule() == OrderRule(criterion="bands", max_view_deg=80.0, eps=0.03, max_F=512, max_P=20)
    assert OrderRule(eps=0.01).to_json() == {"criterion": "bands", "max_view_deg": 80.0, "eps": 0.01,
                                             "max_F": 512, "max_P": 20}
    assert OrderRule.from_json(explicit.to_json()) == explicit


@pytest.mark.parametrize("bad, match", [({"eps": 1.5}, "eps"), ({"criterion": "nope"}, "criterion"),
                                        ({"max_view_deg": 95.0}, "max view"), ({"max_F": 0}, "max_F"),
                                        ({"max_P": 65}, "max_P")])
def test_rule_validates(bad: dict, match: str) -> None:
    with pytest.raises(BadInputError, match=match):
        OrderRule(**bad)


def test_conflicting_rule_and_keyword_refused() -> None:
    brdf = load_brdf(SPEC)
    rule = OrderRule(eps=0.1)
    with pytest.raises(BadInputError, match=r"eps=0\.03 disagrees with rule\.eps=0\.1"):
        choose_orders(brdf, rule=rule, eps=0.03)
    with pytest.raises(BadInputError, match=r"criterion='rh02' disagrees with rule\.criterion='bands'"):
        choose_orders_many(brdf, (0.1,), rule=rule, criterion="rh02")
    with pytest.raises(BadInputError, match="max_view_deg"):
        orders_on_grid_for(brdf, 4, 0, rule=rule, max_view_deg=60.0)
    with pytest.raises(BadInputError, match="OrderRule"):
        choose_orders(brdf, rule={"eps": 0.1})


@pytest.mark.parametrize("keywords", [{"eps": 0.05}, {"eps": 0.1, "criterion": "rh02", "max_F": 16, "max_P": 2},
                                      {"eps": 0.05, "max_view_deg": 60.0}])
def test_choose_orders_rule_equals_keywords(keywords: dict) -> None:
    brdf = load_brdf(SPEC)
    by_keywords = choose_orders(brdf, **keywords)
    by_rule = choose_orders(brdf, rule=OrderRule(**keywords))
    assert (by_rule.F, by_rule.P, by_rule.eps, by_rule.capped) == (by_keywords.F, by_keywords.P, by_keywords.eps,
                                                                   by_keywords.capped)
    assert (by_rule.criterion, by_rule.max_view_deg, by_rule.tolerance) == (
        by_keywords.criterion, by_keywords.max_view_deg, by_keywords.tolerance)
    assert by_rule.rule == by_keywords.rule == OrderRule(**keywords)


def test_compare_options_alias_warns_and_maps() -> None:
    with pytest.warns(DeprecationWarning, match="max_view_deg"):
        options = CompareOptions(max_view_deg=70.0)
    assert options.sample_max_view_deg == 70.0
    assert options.rule_max_view_deg == options.rule.max_view_deg == 80.0  # the rule's limit is not the range
    with pytest.warns(DeprecationWarning, match="sample_max_view_deg"):
        assert options.max_view_deg == 70.0
    with pytest.raises(TypeError, match="not both"), warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        CompareOptions(max_view_deg=70.0, sample_max_view_deg=60.0)
    default = CompareOptions()
    assert (default.sample_max_view_deg, default.rule) == (88.0, OrderRule())


def test_options_hold_one_rule() -> None:
    """CompareOptions and ReportOptions keep their keywords: they set (and read) the rule's fields."""
    rule = OrderRule(eps=0.05, criterion="rh02", max_view_deg=70.0)
    compare = CompareOptions(eps=0.05, criterion="rh02", rule_max_view_deg=70.0)
    assert compare.rule == rule and (compare.eps, compare.criterion) == (0.05, "rh02")
    assert dataclasses.replace(compare, eps=0.1).rule == rule.replace(eps=0.1)
    assert compare.shrm_settings()["max_view_deg"] == 70.0
    report = ReportOptions(eps=0.05, criterion="rh02", max_view_deg=70.0, max_F=96)
    assert report.rule == rule.replace(max_F=96)
    assert report.with_changes(eps=0.01).rule == rule.replace(max_F=96, eps=0.01)
    quick = profile("quick").as_dict()
    assert (quick["eps"], quick["max_F"], quick["max_P"], quick["criterion"], quick["max_view_deg"]) == (
        0.03, 96, 20, "bands", 80.0)
    assert "rule" not in quick
    assert list(quick)[:2] == ["eps", "tolerances"] and set(RULE_FIELDS) <= set(quick)
    # a new rule given whole is taken (the keywords read back from the old rule used to win over it)
    other = OrderRule(eps=0.01, criterion="rh02", max_F=64)
    assert report.with_changes(rule=other).rule == other == dataclasses.replace(report, rule=other).rule
    with pytest.raises(TypeError):
        ReportOptions(tolerance=0.1)
    # positional eps as before the rule, and help() lists the keywords
    assert ReportOptions(0.05).rule.eps == 0.05
    assert list(inspect.signature(ReportOptions).parameters)[:3] == ["eps", "tolerances", "envs"]


def test_render_options_hold_one_rule() -> None:
    """RenderOptions (issue 27: the rule passed instead of criterion/max_view_deg) keeps its documented
    keywords, which set and read the rule's fields; the render's ε replaces the rule's in ``rule_at``."""
    from shrmkit.render.modes import RenderOptions

    rule = OrderRule(criterion="rh02", max_view_deg=60.0, max_F=64)
    options = RenderOptions(rule=rule)
    assert (options.criterion, options.max_view_deg) == ("rh02", 60.0)
    assert options.rule_at(0.01) == rule.replace(eps=0.01) and options.rule_at(None) is rule
    assert RenderOptions(criterion="rh02", max_view_deg=60).rule == OrderRule(criterion="rh02", max_view_deg=60.0)
    assert RenderOptions(rule=rule, max_view_deg=70).rule == rule.replace(max_view_deg=70.0)  # keyword over rule=
    assert dataclasses.replace(options, window="none").rule is rule
    assert dataclasses.replace(options, rule=OrderRule()).rule == OrderRule()  # a new rule wins, as a keyword does
    assert dataclasses.replace(options, criterion="bands").rule == rule.replace(criterion="bands")
    with pytest.raises(TypeError, match="max_view"):
        RenderOptions(max_view=60)
    assert RenderOptions().rule == OrderRule()
    with pytest.raises(BadInputError, match="max view angle"):
        RenderOptions(max_view_deg=100)


def test_builders_and_census_take_one_rule() -> None:
    """shrm_model / kautz_mccool_model / run_census take ``rule=``; a loose keyword that disagrees with
    it, or a rule that is not an OrderRule, is refused before any work (no prefilter, no row)."""
    from shrmkit.analysis.baselines import kautz_mccool_model, shrm_model
    from shrmkit.analysis.census import run_census

    rule = OrderRule(eps=0.05, criterion="rh02", max_view_deg=70.0, max_F=96)
    for build in (shrm_model, kautz_mccool_model):
        with pytest.raises(BadInputError, match="disagrees"):
            build("builtin:constant,height=4", SPEC, rule=rule, eps=0.01)
    census = run_census([], rule=rule)
    assert census.rule is rule and (census.eps, census.criterion, census.max_view_deg, census.max_F, census.max_P) == (
        0.05, "rh02", 70.0, 96, 20)
    assert {k: census.as_dict()[k] for k in rule.to_json()} == rule.to_json()
    assert run_census([]).rule == OrderRule()
    with pytest.raises(BadInputError, match="OrderRule"):
        run_census([], rule={"eps": 0.05})  # type: ignore[arg-type]


def test_report_cli_rule_over_the_profile() -> None:
    """``shrm report``'s options: the profile's rule (quick: max_F 96) with the rule options given."""
    import argparse

    from shrmkit.cli.cmd_report import options_from_args
    from shrmkit.cli.options_report import add_arguments

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    quick = options_from_args(parser.parse_args(["phong:s=8", "--quick", "--criterion", "rh02", "--eps", "0.05"]))
    assert quick.rule == OrderRule(criterion="rh02", eps=0.05, max_F=96) and quick.profile == "quick"
    raised = options_from_args(parser.parse_args(["phong:s=8", "--quick", "--max-F", "200", "--max-view-angle", "60"]))
    assert raised.rule == OrderRule(max_F=200, max_view_deg=60.0)
    assert options_from_args(parser.parse_args(["phong:s=8"])).rule == OrderRule()
