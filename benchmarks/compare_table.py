"""Comparison table: SHRM vs Kautz & McCool 2000, Cabral, Olano, Nemec 1999 and Green, Kautz,
Durand 2007 on the Grace probe.

Run: ``.venv/bin/python benchmarks/compare_table.py [OUT_DIR]`` (needs ../shared/data). Writes
``compare_<name>.json``, ``compare_<name>.md`` and ``strip_<name>.png`` for a sharp microfacet,
a Lafortune fit of Cornell krylon_blue, and a MERL file written from a Cook–Torrance model.
The numbers come from ``analysis.compare``; the strip is drawn by ``render.strip`` from the
representations the comparison built.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from shrmkit.analysis.compare import CompareOptions, compare_representations
from shrmkit.analysis.fit import fit_brdf
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.merl import write_merl
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.common import to_jsonable
from shrmkit.render.strip import write_comparison_strip

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="compare_"))
    out.mkdir(parents=True, exist_ok=True)
    env = load_env(DATA / "env" / "grace_latlong.exr", flip=True, up="y", height=64)
    krylon = fit_brdf(DATA / "brdf" / "cornell" / "krylon_blue.brdf", "lafortune").brdf
    merl = write_merl(out / "ct_ggx.binary",
                      load_brdf("cook-torrance:kd=0.05/0.08/0.12,ks=1,alpha=0.15,f0=0.9/0.6/0.3,dist=ggx"))
    options = CompareOptions(rsibr_reference_height=16)
    for name, brdf in (("microfacet", load_brdf("microfacet:sigma=0.1")), ("krylon_blue_lafortune", krylon),
                       ("merl_cook_torrance", load_brdf(merl))):
        result = write_comparison_strip(compare_representations(brdf, env, options), out / f"strip_{name}.png")
        (out / f"compare_{name}.json").write_text(json.dumps(to_jsonable(result), indent=1))
        (out / f"compare_{name}.md").write_text(result["markdown"])
        print(result["markdown"])  # noqa: T201
    print(f"wrote {out}")  # noqa: T201


if __name__ == "__main__":
    main()
