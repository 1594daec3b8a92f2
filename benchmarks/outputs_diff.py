"""Before/after check of a refactoring: the same fixed commands under two checkouts, their JSON
and SHRM files compared with timings ignored (issue 27: typed records instead of ``SHRM.meta``).

    .venv/bin/python benchmarks/outputs_diff.py OLD_CHECKOUT NEW_CHECKOUT [--out DIR] [--no-report]

Each checkout is a directory holding the package's source (a ``git worktree``); it is imported as
``shrmkit`` through a symlink on ``PYTHONPATH``, with this venv's ``shrm``. Commands: five
``shrm prefilter --json -o X.shrm.npz`` (bands rule with a light, a measured-like Lafortune lobe at
ε = 0.01, ``--criterion rh02 --window none``, ``--window lanczos --cube``, a merged sun at 512 rows)
and ``shrm report --quick microfacet:sigma=0.1``. Compared: every JSON value and dict key order
(keys ``timings``, ``*_seconds``, ``seconds``, ``generated``, ``bytes`` ignored; the run's folder in
strings replaced), and every array of the ``.shrm.npz`` files byte for byte. Prints one line per
file; exits 1 when anything differs. ~3 min CPU per checkout.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

SHRM = str(Path(sys.executable).with_name("shrm"))
PREFILTERS = {
    "a": ["--env", "builtin:sky", "--brdf", "microfacet:sigma=0.1"],
    "b": ["--env", "builtin:studio,height=32", "--brdf", "lafortune:kd=0.02/0.015/0.005,cxy=-1,cz=1,n=300,ks=36/26/10",
          "--eps", "0.01"],
    "c": ["--env", "builtin:sky", "--brdf", "microfacet:sigma=0.1", "--criterion", "rh02", "--window", "none"],
    "d": ["--env", "builtin:studio,height=32", "--brdf", "microfacet:sigma=0.2", "--window", "lanczos", "--cube"],
    "e": ["--env", "builtin:sky,height=512", "--brdf", "microfacet:sigma=0.2", "--eps", "0.05"],
}
IGNORED = ("timings", "seconds", "generated", "bytes")


def _ignored(key: str) -> bool:
    return key in IGNORED or key.endswith("_seconds")


def differences(a: object, b: object, path: str = "$") -> list[str]:
    """Where two parsed JSON documents differ (values, list lengths, dict key order), ignored keys aside."""
    if isinstance(a, dict) and isinstance(b, dict):
        keys_a, keys_b = [k for k in a if not _ignored(k)], [k for k in b if not _ignored(k)]
        out = [] if keys_a == keys_b else [f"{path}: keys {keys_a} != {keys_b}"]
        return out + [d for k in keys_a if k in b for d in differences(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list):
        out = [] if len(a) == len(b) else [f"{path}: length {len(a)} != {len(b)}"]
        return out + [d for i, (x, y) in enumerate(zip(a, b, strict=False)) for d in differences(x, y, f"{path}[{i}]")]
    return [] if type(a) is type(b) and a == b else [f"{path}: {a!r} != {b!r}"]


def _load(path: Path, root: Path) -> tuple[object, dict[str, np.ndarray]]:
    if path.name.endswith(".npz"):
        with np.load(path) as z:
            text, arrays = str(z["header"][()]), {k: z[k] for k in z.files if k != "header"}
    else:
        text, arrays = path.read_text(), {}
    return json.loads(text.replace(str(root), "<OUT>")), arrays


def compare(old: Path, new: Path, old_root: Path, new_root: Path) -> list[str]:
    (a, arrays_a), (b, arrays_b) = _load(old, old_root), _load(new, new_root)
    out = differences(a, b)
    if sorted(arrays_a) != sorted(arrays_b):
        out.append(f"arrays {sorted(arrays_a)} != {sorted(arrays_b)}")
    out += [f"array {k} differs" for k in arrays_a if k in arrays_b and (
        arrays_a[k].dtype != arrays_b[k].dtype or arrays_a[k].tobytes() != arrays_b[k].tobytes())]
    return out


def run(checkout: Path, out: Path, report: bool) -> None:
    """The fixed commands with ``checkout`` imported as shrmkit, outputs under ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    pkg = Path(tempfile.mkdtemp(prefix="outputs_diff_"))
    (pkg / "shrmkit").symlink_to(checkout.resolve())
    env = {**os.environ, "PYTHONPATH": str(pkg)}
    for name, args in PREFILTERS.items():
        with open(out / f"{name}.json", "w") as stdout:
            subprocess.run([SHRM, "prefilter", *args, "-o", str(out / f"{name}.shrm.npz"), "--json"], stdout=stdout,
                           env=env, cwd=tempfile.gettempdir(), check=True)
    if report:
        subprocess.run([SHRM, "report", "--quick", "microfacet:sigma=0.1", "--out", str(out / "report"), "-q"],
                       env=env, cwd=tempfile.gettempdir(), check=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--out", type=Path, default=None, help="folder for the outputs (default: a temporary one)")
    parser.add_argument("--no-report", action="store_true", help="skip shrm report --quick (~2 min)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="outputs_diff_"))
    roots = {side: out / side for side in ("old", "new")}
    for side, checkout in (("old", args.old), ("new", args.new)):
        print(f"running {side}: {checkout}", file=sys.stderr)
        run(checkout, roots[side], not args.no_report)
    files = [f"{n}.json" for n in PREFILTERS] + [f"{n}.shrm.npz" for n in PREFILTERS]
    if not args.no_report:
        files.append("report/microfacet_sigma_0.1/report.json")
    failed = False
    for name in files:
        found = compare(roots["old"] / name, roots["new"] / name, roots["old"], roots["new"])
        failed |= bool(found)
        print(f"{name:42s} " + ("identical (timings ignored)" if not found else f"{len(found)} difference(s)"))
        for line in found[:10]:
            print(f"    {line}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
