"""Shared CLI helpers: consoles, tables and JSON output (the CLI's only I/O layer), loading a verb's
BRDF and environments; the parsers' argument types and options are in :mod:`~shrmkit.cli.options`
(numpy-free), re-exported here."""

from __future__ import annotations

import argparse
import contextlib
import glob
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.measure import Measurement
from rich.table import Table

from ..analysis.fit.representation import RepresentationChoice, choose_representation
from ..brdf_io.brdf import BRDF
from ..brdf_io.cubemap import CUBE_FACES
from ..brdf_io.env_rotation import env_rotation_matrix
from ..brdf_io.envmap import load_env
from ..brdf_io.errors import BadInputError
from ..brdf_io.hdr_codecs import IMAGE_SUFFIXES
from ..brdf_io.jsonutil import to_jsonable
from ..brdf_io.rgl import RGL_INCIDENT
from ..brdf_io.specs import load_brdf
from .options import (  # the parsers' options, numpy-free (cli/options.py), here for the verbs' and reports' use
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_pixel_rule_option,
    add_rgl_incident,
    add_window_option,
    brdf_help,
    number_in,
    positive_float,
    tolerance,
)
from .terms import ERROR_IMAGE_TERMS, in_cli_terms  # the library's words as options (numpy-free, cli/terms.py)

__all__ = [
    "say",
    "in_cli_terms",
    "ERROR_IMAGE_TERMS",
    "brdf_help",
    "add_env_orientation",
    "add_window_option",
    "add_lights_option",
    "add_pixel_rule_option",
    "add_order_rule",
    "add_rgl_incident",
    "rgl_brdf_arg",
    "load_analysis_brdf",
    "order_rule",
    "env_orientation",
    "env_rotation_arg",
    "env_rotation_angles",
    "env_sources_arg",
    "load_env_sequence",
    "load_env_arg",
    "load_oriented_env",
    "stdout",
    "stderr",
    "print_table",
    "number_in", "positive_float", "tolerance", "print_json", "to_jsonable"]

#: Width of tables written to a pipe or a file (logs, ``| cat``): there is no terminal to fit,
#: and rich's 80-column default squeezes cells to "…"; tables wider than this are split.
PIPE_WIDTH = 160
stdout = Console(highlight=False, width=None if sys.stdout.isatty() else PIPE_WIDTH)
stderr = Console(stderr=True, highlight=False)


def print_table(table: Table) -> None:
    """Print a rich ``table`` on stdout as it is when it fits the console, else one small
    "column: value" table per row (a narrow terminal gets every number whole, never "…")."""
    natural = Measurement.get(stdout, stdout.options.update(max_width=1 << 20), table).maximum
    if natural <= stdout.width:
        stdout.print(table)
        return
    headers = [str(column.header) for column in table.columns]
    cells = [list(column.cells) for column in table.columns]
    if table.title:
        stdout.print(table.title, markup=False)
    for i in range(table.row_count):
        part = Table(show_header=False, box=None, padding=(0, 1))
        part.add_column(justify="right", style="bold")
        part.add_column()
        for header, column in zip(headers, cells, strict=True):
            part.add_row(header, column[i])
        stdout.print(part)


def print_json(doc: dict[str, Any]) -> None:
    """One JSON object on stdout."""
    sys.stdout.write(json.dumps(to_jsonable(doc)) + "\n")


def say(text: str) -> None:
    """One line of plain text on :data:`stdout`, as ``print`` writes it (no markup, highlighting,
    emoji codes or wrapping)."""
    stdout.print(text, soft_wrap=True, markup=False, highlight=False, emoji=False)


def rgl_brdf_arg(source: str, args: argparse.Namespace) -> str:
    """``source`` (a BRDF spec or file) with :func:`add_rgl_incident`'s choice attached to an RGL
    ``.bsdf`` path that names none (``"x.bsdf"`` -> ``"x.bsdf#light"``); every other source as given.

    Raises
    ------
    BadInputError
        A ``FILE.bsdf#camera|light`` that contradicts an explicit ``--rgl-incident``.
    """
    choice = getattr(args, "rgl_incident", "camera")
    text = str(source)
    base, sep, selector = text.rpartition("#")
    if sep and Path(base).suffix.lower() == ".bsdf":
        if selector.strip().lower() in RGL_INCIDENT and selector.strip().lower() != choice and choice != "camera":
            raise BadInputError(text, f"names the RGL incident direction {selector!r}, --rgl-incident says {choice!r}")
        return text
    if Path(text).suffix.lower() == ".bsdf" and choice != "camera":
        return f"{text}#{choice}"
    return text


def progress_shown(args: argparse.Namespace) -> bool:
    """Whether a verb shows progress (spinners, bars, step lines) on stderr: not with ``--json``,
    ``-q/--quiet`` or ``--no-progress`` (issue 26: ``-q`` left a spinner frame in a log). The one
    rule of every verb."""
    return not any(getattr(args, key, False) for key in ("json", "quiet", "no_progress"))


def load_analysis_brdf(source: str, args: argparse.Namespace, *, quiet: bool = False
                       ) -> tuple[BRDF, BRDF, RepresentationChoice | None]:
    """The BRDF a verb analyses: (what the file holds, what is analysed, the representation choice).

    Every format ``report`` accepts is accepted: an evaluable BRDF is analysed as it is (choice
    None); scattered measurements (CURET, Cornell, gonioreflectometer CSV) are analysed through
    the representation with the smallest held-out worst-view-band error
    (``analysis.fit.representation.choose_representation``), whose one line the verb prints beside
    its orders and whose ``as_dict()`` its ``--json`` carries as ``representation``
    (data_specs/representation_json.md). ``quiet``: no spinner (nor without :func:`progress_shown`).

    Raises
    ------
    BadInputError
        As ``load_brdf``, or no representation could be fitted to the measurements.
    """
    brdf = load_brdf(rgl_brdf_arg(source, args))
    if getattr(brdf, "kind", None) != "scattered":
        return brdf, brdf, None
    busy = contextlib.nullcontext() if quiet or not progress_shown(args) else stderr.status(
        f"{brdf.name}: scattered measurements; choosing a representation by held-out error ...", spinner="dots")
    with busy:
        choice = choose_representation(brdf)
    return brdf, choice.brdf, choice


def order_rule(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments ``criterion``/``max_view_deg`` from :func:`add_order_rule`'s options."""
    return {"criterion": args.criterion, "max_view_deg": args.max_view_deg}


def env_orientation(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments of ``load_env`` from :func:`add_env_orientation`'s options."""
    return {"up": args.env_up, "flip": args.env_flip, "azimuth": args.env_azimuth,
            "layer": getattr(args, "env_layer", None), "part": getattr(args, "env_part", None)}


def env_rotation_angles(text: str, option: str = "--env-rotation") -> tuple[float, float, float]:
    """``AZ,EL[,ROLL]`` (degrees) as three angles (ROLL 0 when not given): the one parser of
    ``shrm render --env-rotation`` and ``shrm view --env-rotation``; :class:`BadInputError` (one
    line, exit 2) echoing the text otherwise."""
    parts = str(text).split(",")
    try:
        angles = [float(p) for p in parts]
    except ValueError:
        angles = []
    if len(angles) not in (2, 3) or not all(np.isfinite(angles)):
        raise BadInputError(None, f"{option} must be two or three finite numbers AZ,EL[,ROLL] in degrees, "
                            f"got {text!r}")
    return angles[0], angles[1], angles[2] if len(angles) == 3 else 0.0


def env_rotation_arg(text: str, option: str = "--env-rotation") -> np.ndarray:
    """``AZ,EL[,ROLL]`` (degrees, :func:`env_rotation_angles`) as the rotation matrix of
    ``brdf_io.env_rotation.env_rotation_matrix``."""
    return env_rotation_matrix(*env_rotation_angles(text, option))


def load_oriented_env(spec: str, *, up: str | None, flip: bool, azimuth: float, layer: str | None = None,
                      part: str | int | None = None, **kwargs: Any):
    """``load_env(spec)`` with the orientation options: ``up`` and ``flip`` describe how a map
    *file* is stored and are refused for built-ins (which have no file); ``azimuth`` rotates any
    map; ``layer`` and ``part`` pick the layer/part of an OpenEXR file (refused for built-ins;
    ``load_env`` refuses them for other formats). The one rule of every verb (``shrm report``
    included)."""
    if spec.strip().startswith("builtin:"):
        if up or flip:
            raise BadInputError(spec, "--env-up/--env-flip apply to map files, not to built-in environments")
        if layer is not None or part is not None:
            raise BadInputError(spec, "--env-layer/--env-part apply to OpenEXR files, not to built-in environments")
        return load_env(spec, azimuth=azimuth, **kwargs)
    return load_env(spec, up=up, flip=flip, azimuth=azimuth, layer=layer, part=part, **kwargs)


def load_env_arg(spec: str, args: argparse.Namespace, **kwargs: Any):
    """:func:`load_oriented_env` with the options of :func:`add_env_orientation`; a lat-long file
    read with the default orientation says so on stdout (:func:`orientation_note`), unless the
    verb prints ``--json``."""
    env = load_oriented_env(spec, **env_orientation(args), **kwargs)
    note = orientation_note(env, args)
    if note and not getattr(args, "json", False):
        stdout.print(note, markup=False, soft_wrap=True)
    return env


def _default_oriented(env: Any, args: argparse.Namespace) -> bool:
    """Whether ``env`` is a lat-long map *file* read with the default orientation (y-up), no
    ``--env-up`` given."""
    return getattr(args, "env_up", None) is None and "[latlong, up=y" in str(getattr(env, "source", ""))


def _orientation_tail(args: argparse.Namespace, them: str = "it") -> str:
    """What was applied beyond the default (``--env-flip``, ``--env-azimuth``), the convention, and
    the options *not* given that change the reading (an option given is not offered again)."""
    flip = bool(getattr(args, "env_flip", False))
    azimuth = float(getattr(args, "env_azimuth", 0.0) or 0.0)
    done = ((", rows flipped (--env-flip)" if flip else "")
            + (f", turned {azimuth:g} deg (--env-azimuth)" if azimuth else ""))
    ways = [f"--env-up z reads {them} as stored (z-up)"]
    if not flip:
        ways.append(f"--env-flip turns {them} upside down")
    if not azimuth:
        ways.append(f"--env-azimuth DEG turns {them} about the vertical")
    return (f"{done}, as Blender and three.js place panoramas (image centre facing +x; "
            f"data_specs/environment_maps.md); {', '.join(ways)}")


def orientation_note(env: Any, args: argparse.Namespace) -> str | None:
    """One line when a lat-long map *file* was read with the default orientation (y-up, the
    convention of panoramas in the wild: Poly Haven, three.js, Blender, Mitsuba 3), naming it and
    how to change it (the orientation options not given), so the guess is never silent. None for
    built-ins, cube maps, probes, OpenEXR ``envmap`` files (their format states the orientation)
    and an explicit ``--env-up``."""
    if not _default_oriented(env, args):
        return None
    return f"environment {env.name}: a lat-long file read y-up{_orientation_tail(args)}"


def orientation_notes(envs: Sequence[Any], args: argparse.Namespace) -> str | None:
    """:func:`orientation_note` of several maps (a sequence, a folder, ``shrm report --env A B``)
    as one line: how many lat-long files were read y-up (the first and last named) and how to
    change it; the single map's line when only one was; None when none was."""
    files = [env for env in envs if _default_oriented(env, args)]
    if len(files) <= 1:
        return orientation_note(files[0], args) if files else None
    names = f"{files[0].name} … {files[-1].name}" if len(files) > 2 else f"{files[0].name}, {files[-1].name}"
    of = f" of {len(envs)}" if len(files) < len(envs) else ""
    return f"environments: {len(files)}{of} lat-long files ({names}) read y-up{_orientation_tail(args, 'them')}"


_GLOB_CHARS = frozenset("*?[")


def _is_cube_folder(folder: Path) -> bool:
    """Whether ``folder`` holds cube-map faces (``px.hdr`` …), which ``load_env`` reads as one map."""
    return any((folder / f"{face}{s}").is_file() for face in CUBE_FACES for s in IMAGE_SUFFIXES)


def env_sources_arg(tokens: str | list[str]) -> tuple[list[str], bool]:
    """The environment maps named by ``--env``'s values, and whether they make a sequence.

    Each token is a spec (``builtin:…``), a map file, a cube-map folder (one map), a folder of
    map files (its ``.exr``/``.hdr``/``.pfm`` files, sorted by name: a time-lapse), or a glob
    pattern (``captures/*.exr``, sorted). The maps make a sequence (one frame each) when there
    are several tokens or a token named a folder of maps or a pattern.

    Raises
    ------
    BadInputError
        A folder with no map file, a pattern that matches none (one line naming it).
    """
    tokens = [tokens] if isinstance(tokens, str) else list(tokens)
    sources: list[str] = []
    sequence = len(tokens) > 1
    for token in tokens:
        path = Path(token)
        if token.strip().startswith("builtin:") or path.is_file():
            sources.append(token)
        elif path.is_dir() and not _is_cube_folder(path):
            found = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
            if not found:
                raise BadInputError(path, f"a folder of environment maps holds no {'/'.join(IMAGE_SUFFIXES)} file")
            sources += [str(p) for p in found]
            sequence = True
        elif _GLOB_CHARS & set(token) and not path.exists():
            matches = sorted(p for p in glob.glob(token) if Path(p).is_file())
            if not matches:
                raise BadInputError(token, "the pattern matches no file")
            sources += matches
            sequence = True
        else:
            sources.append(token)  # a cube-map folder, or a missing file that load_env names
    return sources, sequence


def load_env_sequence(sources: list[str], args: argparse.Namespace, **kwargs: Any) -> list:
    """:func:`load_env_arg` of every source, all before any is used: the first unreadable one raises
    its :class:`BadInputError` (one line naming the file) and nothing has been computed or written.
    The maps read with the default orientation are stated in one line (:func:`orientation_notes`),
    not one per map."""
    envs = [load_oriented_env(source, **env_orientation(args), **kwargs) for source in sources]
    note = orientation_notes(envs, args)
    if note and not getattr(args, "json", False):
        stdout.print(note, markup=False, soft_wrap=True)
    return envs
