"""``shrm export``: hand a BRDF or a prefiltered environment to the tools people render with.

* ``--to mitsuba | mitsuba-dict | pbrt | materialx`` (or the output suffix ``.xml``, ``.json``,
  ``.pbrt``, ``.mtlx``): a material snippet of the BRDF (a fit document, a spec, any file
  ``shrm report`` reads). A model without an exact counterpart in the renderer is exported as
  the closest material, said in one line with its measured error (worst view band first);
* ``--to merl`` (``.binary``): the BRDF tabulated as a MERL table, read back and checked;
* ``--to dds`` (``.dds``, needs ``--env``): the environment GGX-prefiltered as an engine's cube
  mip chain (level m of N holds roughness m/(N − 1)), with ``OUTPUT.json`` beside it stating
  the roughness of every level and the level the BRDF's own roughness reads.

Formats and mappings: ``data_specs/export.md``. Every file is written atomically; errors are
one line, exit status 2, nothing written.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
from rich.table import Table

from ..analysis.material_export import closest_shared_model, export_material
from ..analysis.prefiltered_cube import ggx_cube_chain, material_lod
from ..brdf_io.atomic import atomic_paths, check_writable
from ..brdf_io.errors import BadInputError
from ..brdf_io.export_formats import export_format
from ..brdf_io.export_material import material_text, write_material
from ..brdf_io.merl import read_merl, tabulate_merl, write_merl
from ..brdf_io.models import CookTorrance, PhongLobe, SimplifiedMicrofacet
from ..brdf_io.specs import load_brdf
from .common import (
    load_analysis_brdf,
    load_env_arg,
    print_json,
    print_table,
    rgl_brdf_arg,
    stdout,
)


def _material_name(args: argparse.Namespace, out: Path) -> str:
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", out.name.split(".")[0]) or "material"
    name = stem if args.name is None else args.name
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise BadInputError(None, f"--name {name!r}: use letters, digits, '-', '_' or '.'")
    return name


def _check_outputs(paths: list[Path]) -> None:
    """Every output path writable before the work starts (``data_specs/export.md``, output paths):
    not a folder, no file where a folder of the path should be (one line naming it); a missing
    folder is created, as every verb's ``-o`` does (``brdf_io.atomic.check_writable``)."""
    for path in paths:
        for folder in path.parents:
            if folder.exists() or folder.is_symlink():
                if not folder.is_dir():
                    raise BadInputError(path, f"{folder} is a file, not a folder")
                break
        check_writable(path)


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    fmt = export_format(args.to, out)
    if fmt.kind != "cube-mip-chain":
        for option, value in (("--env", args.env), ("--levels", args.levels)):
            if value is not None:
                raise BadInputError(None, f"{option} is for --to dds or ktx2, not {fmt.name}")
    elif args.env is None:
        raise BadInputError(None, f"--to {fmt.name} needs --env (the environment to prefilter)")
    _check_outputs([out, _sidecar(out)] if fmt.kind == "cube-mip-chain" else [out])
    representation = None
    if fmt.kind == "brdf-table":  # a table needs values everywhere: scattered data through their representation
        source_brdf, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)
        if choice is not None:
            representation = choice.as_dict()
            if not args.json:
                stdout.print(choice.line(), markup=False, soft_wrap=True)
        doc = _export_merl(args, out, brdf)
    else:  # a material (or the roughness a chain is read at) is fitted to the data themselves, scattered or not
        source_brdf = load_brdf(rgl_brdf_arg(args.brdf, args))
        doc = (_export_material(args, fmt.name, out, source_brdf) if fmt.kind == "material"
               else _export_dds(args, out, source_brdf))
    doc = {"format": fmt.name, "output": str(out), "source": source_brdf.name, **doc,
           "representation": representation}
    if args.json:
        print_json(doc)
    return 0


def _export_material(args: argparse.Namespace, target: str, out: Path, brdf: Any) -> dict[str, Any]:
    name = _material_name(args, out)
    result = export_material(brdf, target)
    write_material(out, material_text(result.material, name, result.error_line(), model_note=result.model_note))
    if not args.json:
        if result.model_note:
            stdout.print(result.model_note, markup=False, soft_wrap=True)
        if result.material.exact and not result.model_note:
            stdout.print(f"exact: {target}'s material is the model {result.model.to_spec()}", markup=False,
                         soft_wrap=True)
        elif result.material.note:
            stdout.print(f"not exact: {result.material.note}", markup=False, soft_wrap=True)
        stdout.print(result.error_line(), markup=False, soft_wrap=True)
        stdout.print(f"wrote {out} (material {name!r})", markup=False, soft_wrap=True)
    return {"name": name, **result.as_dict()}


def _export_merl(args: argparse.Namespace, out: Path, brdf: Any) -> dict[str, Any]:
    values = tabulate_merl(brdf)
    write_merl(out, values)
    back = read_merl(out).values  # the file read back with our reader: layout and scale checked
    present = ~np.isnan(values)
    if not np.array_equal(present, ~np.isnan(back)):
        raise BadInputError(out, "read back with missing samples where none were written (please report)")
    scale = np.maximum(np.abs(values[present]), 1e-300)
    readback = float(np.max(np.abs(back[present] - values[present]) / scale)) if present.any() else 0.0
    missing = int(np.count_nonzero(np.any(~present, axis=0)))
    note = None
    if isinstance(brdf, PhongLobe | SimplifiedMicrofacet):
        note = ("the model is not reciprocal (it defines rho cos theta_i): the table keeps one ordering of each "
                "(L, V) pair (data_specs/merl_binary.md)")
    if not args.json:
        if note:
            stdout.print(f"note: {note}", markup=False, soft_wrap=True)
        stdout.print(f"tabulated {brdf.name} at the 90 x 90 x 180 MERL samples: {missing:,} missing "
                     "(L or V below the surface, or no data); read back: max relative difference "
                     f"{readback:.2g}", markup=False, soft_wrap=True)
        stdout.print(f"wrote {out} ({out.stat().st_size:,} bytes)", markup=False, soft_wrap=True)
    return {"missing_samples": missing, "readback_max_rel": readback, "bytes": out.stat().st_size, "note": note}


def _sidecar(out: Path) -> Path:
    """The side file of a cube chain: ``OUTPUT.json`` beside it."""
    return out.with_name(out.name + ".json")


def _export_dds(args: argparse.Namespace, out: Path, brdf: Any) -> dict[str, Any]:
    size = int(args.face_size)
    if size & (size - 1):
        raise BadInputError(None, f"--face-size {size}: must be a power of two")
    env = load_env_arg(args.env, args)
    model, note = closest_shared_model(brdf)
    alpha = float(model.alpha) if isinstance(model, CookTorrance) and np.any(np.asarray(model.ks) > 0) else None
    chain = ggx_cube_chain(env, face_size=size, n_levels=args.levels)
    sidecar = _sidecar(out)
    n = len(chain.levels)
    lod = None if alpha is None else material_lod(min(alpha, 1.0), n)
    doc = {
        "format": "shrmkit-cube-chain", "format_version": 1, "file": out.name, "dds_format": args.dds_format,
        "environment": env.name, "face_size": size, "faces": ["+X", "-X", "+Y", "-Y", "+Z", "-Z"],
        "frame": "y-up cube-map frame: project X = z_c, Y = -x_c, Z = y_c (face +Y is the zenith)",
        "roughness_rule": "level m of N holds perceptual roughness m/(N-1), GGX alpha = roughness^2 "
                          "(glTF: lod = roughness * (N - 1))",
        "levels": [{"level": m, "size": int(level.shape[1]), "roughness": r, "alpha": a, "prefilter_rows": rows}
                   for m, (level, r, a, rows) in enumerate(zip(chain.levels, chain.roughness, chain.alpha,
                                                                chain.rows, strict=True))],
        "brdf": brdf.name, "brdf_model": model.to_spec(), "brdf_model_note": note or None,
        "brdf_alpha": alpha, "brdf_lod": lod, "seconds": chain.seconds,
    }
    if alpha is not None and n == 1:
        doc["roughness_rule"] = "one level: roughness 0 (the environment itself), no rougher level"
        doc["brdf_note"] = (f"a one-level chain holds roughness 0 only: it cannot represent the material's "
                            f"roughness {np.sqrt(alpha):.3g} (GGX alpha {alpha:.3g}); use --levels 2 or more")
    elif alpha is not None and alpha > 1.0:
        doc["brdf_note"] = f"alpha {alpha:.3g} is rougher than the last level (alpha 1): it reads level {n - 1}"
    new = [path for path in (out, sidecar) if not path.exists() and not path.is_symlink()]
    try:
        with atomic_paths([out, sidecar]) as (tmp, tmp_json):
            export_format(args.to, out).write_cube(tmp, chain.levels, fmt=args.dds_format)  # DDS or KTX2
            tmp_json.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    except BadInputError:
        # the container moved into place and then its side file failed (a folder made since the
        # check): take back what this run created, so that the pair appears together or not at all
        for path in new:
            if path.is_file() and not path.is_symlink():
                path.unlink(missing_ok=True)
        raise
    if not args.json:
        if note:
            stdout.print(note, markup=False, soft_wrap=True)
        table = Table(title=f"GGX-prefiltered cube mip chain of {env.name} ({args.dds_format})")
        for col in ("level", "face", "roughness", "GGX alpha", "prefilter rows"):
            table.add_column(col, justify="right")
        for level in doc["levels"]:
            table.add_row(str(level["level"]), f"{level['size']}^2", f"{level['roughness']:.4g}",
                          f"{level['alpha']:.4g}", str(level["prefilter_rows"]))
        print_table(table)
        if lod is None:
            stdout.print(f"{brdf.name} has no specular lobe: it reads no level of the chain", markup=False,
                         soft_wrap=True)
        elif n == 1:
            stdout.print(f"note: {doc['brdf_note']}", markup=False, soft_wrap=True)
        else:
            stdout.print(f"{model.to_spec()}: GGX alpha {alpha:.4g} reads level {lod:.3g} of 0..{n - 1}",
                         markup=False, soft_wrap=True)
        stdout.print(f"wrote {out} and {sidecar.name} ({chain.seconds:.2f} s)", markup=False, soft_wrap=True)
    return {"sidecar": str(sidecar), **{k: v for k, v in doc.items() if k not in ("format", "file")}}
