"""The fuzz harness (benchmarks/fuzz_readers.py): a fast seeded subset in CI.

Every reader gets ``SHRM_FUZZ_CASES`` mutated files (default 120; half or a third of that for the
four slowest readers; the full run in ``benchmarks/`` uses ≥ 10,000 cases in all). A case fails
when the reader crashes, hangs, blows memory up or accepts garbage; the test lists the failing
cases with the command that reruns one of them.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_harness_classifies_misbehaviour(benchmark_module):
    """The harness itself can fail a reader: each misbehaviour gets its own outcome."""
    outcomes = benchmark_module("fuzz_readers").self_test(timeout=8.0)
    assert outcomes == {
        "sleep": "hang", "die": "crash", "huge": "memory", "creep": "memory", "keyerror": "crash",
        "nan": "garbage", "unnamed": "garbage", "clean": "clean", "fine": "valid",
    }


@pytest.mark.slow
def test_seeded_fuzz_subset_has_no_failures(benchmark_module):
    harness = benchmark_module("fuzz_readers")
    per_reader = int(os.environ.get("SHRM_FUZZ_CASES", "120"))
    # the slowest readers per case get fewer cases (a smaller count is a prefix of the same cases): MERL
    # writes and reads 35 MB, EXR ~90 ms; the Cornell reader ~30 ms, and the degenerate tables are also
    # analysed (choose_orders, ~0.4 s each: half of the suite's fuzz CPU at 120 tables). At 60 cases every
    # one of the table's 8 and Cornell's 6 mutation kinds is drawn at least 5 times (9 degenerate tables)
    caps = {"merl": per_reader // 3, "exr": per_reader // 2, "table": per_reader // 2, "cornell": per_reader // 2}
    results = harness.run_fuzz(seed=20261130, per_reader=per_reader, workers=2, timeout=30.0, caps=caps, light=True)
    failures = [r for r in results if r["outcome"] in harness.FAILURES or harness._seed_refused(r)]
    listing = "\n".join(
        f"{r['outcome']} {r['reader']}:{r['index']} [{r['mutation']}] {r['detail']}" for r in failures[:30]
    )
    assert not failures, (
        f"{len(failures)} of {len(results)} fuzz cases failed (rerun one: python benchmarks/fuzz_readers.py "
        f"--seed 20261130 --show READER:INDEX):\n{listing}\n\n{harness.outcome_table(results)}"
    )
    readers = {r["reader"] for r in results}
    assert len(readers) >= 13 and len(results) == sum(min(per_reader, caps.get(r, per_reader)) for r in readers)
    # the mutations of issues 28/30 are drawn: windows, inflation, the pixel limit, degenerate tables
    # (which are also analysed: choose_orders must finish with finite orders and eps in [0, 1])
    drawn = " ".join(r["mutation"] for r in results)
    for kind in ("exr_window:", "npz_inflate:", "hdr_limit:", "degenerate table:"):
        assert kind in drawn, kind
