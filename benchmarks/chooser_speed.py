"""The representation chooser's cost, old tree against this one, interleaved (issue 24).

``choose_representation`` (analysis/fit/representation.py) fits Lafortune, Cook–Torrance and a
cross-validated Zernike expansion to each scattered sample and cross-validates the nlopt models.
This script times it on CURET samples in fresh processes, alternating the old tree and this one
per sample (which goes first alternates too), and prints per sample: CPU seconds (user + sys of
the call, imports and reading excluded), the choice and its held-out worst view band, old and new,
and the held-out worst bands of the nlopt candidates (which the new fold fits may move; the
choice must not).

The old tree is any shrmkit checkout laid out as ``DIR/shrmkit`` (e.g.
``mkdir -p /tmp/old/shrmkit && git archive 0fd9af9 | tar -x -C /tmp/old/shrmkit``) and given as
``--old DIR``; it is put first on PYTHONPATH for its runs.

Run:  .venv/bin/python benchmarks/chooser_speed.py --old /tmp/old [--samples 1 7 12 ...]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

__all__ = ["main"]

CURET = Path("/work/shared/data/brdf/curet/abrdf.dat")
SAMPLES = (1, 7, 12, 20, 28, 33, 41, 50, 56, 61)


def worker(source: str) -> None:
    """One sample in this process: prints one JSON line."""
    import scipy.stats  # noqa: F401  (its import, ~0.5 s, is paid by the first fit: not the chooser's cost)

    from shrmkit.analysis.fit.representation import choose_representation
    from shrmkit.brdf_io.specs import load_brdf

    brdf = load_brdf(source)
    t = os.times()
    choice = choose_representation(brdf)
    t2 = os.times()
    c = choice.chosen
    print(json.dumps({
        "cpu": t2.user - t.user + t2.system - t.system, "wall": choice.seconds, "label": choice.label(),
        "worst": c.held_out_worst.rel_rms if c.held_out_worst is not None else c.held_out_rel_rms,
        "others": {o.model: o.score for o in choice.candidates if o.model != choice.model},
    }))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--old", type=Path, required=False, help="folder holding the old tree as DIR/shrmkit")
    parser.add_argument("--samples", type=int, nargs="+", default=list(SAMPLES), help="CURET sample numbers")
    parser.add_argument("--data", type=Path, default=CURET, help=f"CURET abrdf.dat (default {CURET})")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.worker)
        return 0
    if args.old is None or not (args.old / "shrmkit").is_dir():
        print("--old DIR with DIR/shrmkit (an old checkout) is needed; nothing to do")
        return 1
    if not args.data.exists():
        print(f"{args.data}: CURET data not found (only in the project workspace); nothing to do")
        return 1
    here = Path(__file__).resolve()
    rows = {}
    for i, sample in enumerate(args.samples):
        order = ("old", "new") if i % 2 == 0 else ("new", "old")
        for tree in order:
            env = dict(os.environ)
            env.pop("PYTHONPATH", None)
            if tree == "old":
                env["PYTHONPATH"] = str(args.old)
            done = subprocess.run([sys.executable, str(here), "--worker", f"{args.data}#{sample}"], env=env,
                                  capture_output=True, text=True, cwd=str(args.old if tree == "old" else here.parent))
            if done.returncode:
                print(done.stderr[-3000:])
                return 1
            rows[(sample, tree)] = json.loads(done.stdout.strip().splitlines()[-1])
        o, n = rows[(sample, "old")], rows[(sample, "new")]
        print(f"# {sample}: old {o['cpu']:.2f} s, new {n['cpu']:.2f} s", flush=True)
    print("\n| CURET | old CPU s | new CPU s | old choice | new choice | old held-out worst | new held-out worst "
          "| other candidates' held-out worst, old → new |")
    print("|---|---|---|---|---|---|---|---|")
    total = {"old": 0.0, "new": 0.0}
    same = 0
    for sample in args.samples:
        o, n = rows[(sample, "old")], rows[(sample, "new")]
        total["old"] += o["cpu"]
        total["new"] += n["cpu"]
        same += o["label"] == n["label"]
        others = ", ".join(f"{m} {o['others'].get(m, float('nan')):.4g} → {v:.4g}" for m, v in n["others"].items())
        print(f"| {sample} | {o['cpu']:.2f} | {n['cpu']:.2f} | {o['label']} | {n['label']} | {o['worst']:.4g} | "
              f"{n['worst']:.4g} | {others} |")
    k = len(args.samples)
    print(f"| mean | {total['old'] / k:.2f} | {total['new'] / k:.2f} | | | | | |")
    print(f"\nsame choice on {same} of {k} samples; CPU per sample {total['old'] / k:.2f} s → {total['new'] / k:.2f} s "
          f"({total['old'] / max(total['new'], 1e-9):.1f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
