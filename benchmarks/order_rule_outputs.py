"""Before/after check of issue 27 point 4 (``OrderRule``) beside ``outputs_diff.py``: ``shrm orders
--json`` (default and ``--criterion rh02 --eps 0.01 --max-F 96``) and ``shrm compare --json`` (default, and
with the sampling range ``--max-view 70`` apart from the rule's ``--max-view-angle 60``) under two
checkouts, their JSON compared with ``outputs_diff.differences`` (timings ignored, also the compare rows'
``fit_s``, ``mip_stack_s``, ``update_s``, ``precompute_s``, ``*us_per_pair`` and the markdown, which
holds timings). Prints one line per command (and the differences); exits 1 when anything differs.

    .venv/bin/python benchmarks/order_rule_outputs.py OLD_CHECKOUT NEW_CHECKOUT

~1.5 min CPU per checkout.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from outputs_diff import differences  # noqa: E402

SHRM = str(Path(sys.executable).with_name("shrm"))
COMMANDS = {
    "orders": ["orders", "microfacet:sigma=0.1", "--json"],
    "orders_rh02": ["orders", "microfacet:sigma=0.1", "--json", "--criterion", "rh02", "--eps", "0.01",
                    "--max-F", "96"],
    "compare": ["compare", "phong:s=16", "--env", "builtin:studio", "--json"],
    "compare_rule": ["compare", "microfacet:sigma=0.2", "--env", "builtin:sky,height=32", "--json", "--max-view", "70",
                     "--max-view-angle", "60", "--eps", "0.05", "--pairs", "300", "--lobes", "1"],
}
TIMINGS = ("fit_s", "mip_stack_s", "update_s", "precompute_s", "us_per_pair", "markdown")


def run(checkout: Path, tag: str) -> dict[str, object]:
    """Every command's parsed ``--json`` output with ``checkout`` imported as ``shrmkit``."""
    pkg = Path(tempfile.mkdtemp(prefix=f"order_rule_{tag}_"))
    (pkg / "shrmkit").symlink_to(checkout.resolve())
    env = {**os.environ, "PYTHONPATH": str(pkg)}
    out = {}
    for name, cmd in COMMANDS.items():
        done = subprocess.run([SHRM, *cmd], capture_output=True, text=True, env=env, cwd=tempfile.gettempdir(),
                              check=True)
        out[name] = json.loads(done.stdout)
    return out


def main() -> int:
    old, new = run(Path(sys.argv[1]), "old"), run(Path(sys.argv[2]), "new")
    bad = False
    for name in COMMANDS:
        found = [d for d in differences(old[name], new[name]) if not any(t in d.split(":")[0] for t in TIMINGS)]
        print(f"{name:14s} {'identical (timings ignored)' if not found else f'{len(found)} differences'}")
        for d in found[:10]:
            print("   ", d)
        bad |= bool(found)
    return int(bad)


if __name__ == "__main__":
    sys.exit(main())
