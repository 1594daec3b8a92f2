"""``shrm demo``: the whole pipeline on built-in data, in under two minutes.

Tabulates two built-in analytic materials into MERL files, chooses their orders, fits a
model, prefilters an SHRM, renders a preview and writes reports with a summary table,
printing where each output went (``cli/report/demo.py``).
"""

from __future__ import annotations

import argparse
import time

from ..brdf_io.errors import BadInputError
from .common import print_json, progress_shown, say, stderr
from .report.demo import run_demo


def run(args: argparse.Namespace) -> int:
    if not 32 <= args.size <= 2048:
        raise BadInputError(None, f"--size must be in [32, 2048], got {args.size}")
    t0 = time.perf_counter()
    show = progress_shown(args)

    def progress(step: str) -> None:
        if show:
            stderr.print(f"[{time.perf_counter() - t0:5.1f} s] {step} ...", markup=False, highlight=False)

    def report_progress(event: str, name: str, detail: str) -> None:
        if show and event in ("stage", "done"):
            stderr.print(f"[{time.perf_counter() - t0:5.1f} s]   report {name}: {detail}", markup=False,
                         highlight=False)

    steps = run_demo(args.out, progress=progress, report_progress=report_progress, size=args.size)
    failed = next((s.info.get("n_failed", 0) for s in steps if s.step == "reports"), 0)
    if args.json:
        print_json({"out_dir": str(args.out), "seconds": time.perf_counter() - t0, "open": str(steps[-1].paths[-2]),
                    "n_failed": failed,
                    "steps": [{"step": s.step, "detail": s.detail, "seconds": s.seconds,
                               "paths": [str(p) for p in s.paths], **s.info} for s in steps]})
        return 0 if not failed else 1
    for step in steps:
        say(f"{step.step}: {step.detail} ({step.seconds:.1f} s)")
        for path in step.paths:
            say(f"    {path}")
    say(f"demo finished in {time.perf_counter() - t0:.1f} s; open {steps[-1].paths[-2]} in a browser")
    return 0 if not failed else 1
