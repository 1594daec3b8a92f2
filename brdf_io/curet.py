"""CURET BRDF measurements (``abrdf.dat`` + ``table.txt``), input: one scattered BRDF per sample.

Format (``data_specs/curet.md``): two ASCII files in one folder.

``table.txt``
    205 rows ``index θ_v φ_v θ_i φ_i``: the measurement index 1..205, then the view (camera)
    and the illumination (source) directions, in radians, in the standard spherical
    convention ω = (sin θ cos φ, sin θ sin φ, cos θ) with both directions pointing away from the
    surface (the mirror direction of (θ_i, φ_i) is (θ_i, φ_i + π); the measured specular peaks
    sit there). Polar angles reach 83.9°.
``abrdf.dat``
    61 rows: the sample number 1..61, then 205 BRDF values in 1/sr, averaged over the camera's
    R, G and B, in the order of ``table.txt``'s rows.

Values are grey, so ``rgb`` repeats the value in the three channels. 29 of the 12,505 values
are slightly negative (measurement noise on dark samples: 28 on sample 61, one on sample 4,
down to −0.016 1/sr); they are clamped to 0 and counted in ``n_clipped`` (which counts RGB
components, as for every :class:`~shrmkit.brdf_io.cornell.ScatteredBRDF`: 3 per clamped value).

Public objects: :func:`read_curet`, :func:`read_curet_all`, :func:`curet_samples`,
:func:`curet_sample_name`, :data:`CURET_SAMPLE_NAMES`, :func:`curet_files`.

Reference: [CURET99] (the paper, and the database's BRDF files and sample list).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .cornell import ScatteredBRDF
from .errors import BadInputError
from .limits import TEXT_PEAK_PER_BYTE, read_bytes
from .spec_params import MAX_NUMBER_CHARS, NonFiniteNumberError, parse_number

__all__ = [
    "CURET_SAMPLE_NAMES",
    "CURET_N_MEASUREMENTS",
    "curet_files",
    "curet_samples",
    "curet_sample_name",
    "read_curet",
    "read_curet_all",
]

#: Measurements per sample (rows of ``table.txt``).
CURET_N_MEASUREMENTS = 205

#: CURET's sample names (the database's sample list). Samples 29–32 are zoomed views of
#: samples 2, 11, 12 and 14 (their BRDFs agree with those samples': median values within 15 %).
CURET_SAMPLE_NAMES: dict[int, str] = {
    1: "Felt", 2: "Polyester", 3: "Terrycloth", 4: "Rough Plastic", 5: "Leather", 6: "Sandpaper",
    7: "Velvet", 8: "Pebbles", 9: "Frosted Glass", 10: "Plaster_a", 11: "Plaster_b", 12: "Rough Paper",
    13: "Artificial Grass", 14: "Roof Shingle", 15: "Aluminum Foil", 16: "Cork", 17: "Rough Tile",
    18: "Rug_a", 19: "Rug_b", 20: "Styrofoam", 21: "Sponge", 22: "Lambswool", 23: "Lettuce Leaf",
    24: "Rabbit Fur", 25: "Quarry Tile", 26: "Loofa", 27: "Insulation", 28: "Crumpled Paper",
    29: "Polyester (zoomed)", 30: "Plaster_b (zoomed)", 31: "Rough Paper (zoomed)", 32: "Roof Shingle (zoomed)",
    33: "Slate_a", 34: "Slate_b", 35: "Painted Spheres", 36: "Limestone", 37: "Brick_a", 38: "Ribbed Paper",
    39: "Human Skin", 40: "Straw", 41: "Brick_b", 42: "Corduroy", 43: "Salt Crystals", 44: "Linen",
    45: "Concrete_a", 46: "Cotton", 47: "Stones", 48: "Brown Bread", 49: "Concrete_b", 50: "Concrete_c",
    51: "Corn Husk", 52: "White Bread", 53: "Plant", 54: "Wood_a", 55: "Orange Peel", 56: "Wood_b",
    57: "Peacock Feather", 58: "Tree Bark", 59: "Cracker_a", 60: "Cracker_b", 61: "Moss",
}


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")


def curet_sample_name(sample: int) -> str:
    """The database's name of sample ``sample`` (1..61), e.g. 15 → ``"Aluminum Foil"``.

    Raises
    ------
    BadInputError
        No such sample number.
    """
    if sample not in CURET_SAMPLE_NAMES:
        raise BadInputError(None, f"CURET sample {sample!r} does not exist (1..61)")
    return CURET_SAMPLE_NAMES[sample]


def curet_files(path: str | os.PathLike[str]) -> tuple[Path, Path]:
    """(``abrdf.dat``, ``table.txt``) for a CURET folder, or for either file of the pair.

    Parameters
    ----------
    path
        The folder holding both files, the ``abrdf.dat`` file (any name: the table is the
        ``table.txt`` beside it) or the ``table.txt`` file (the values are ``abrdf.dat``).

    Raises
    ------
    BadInputError
        A missing folder or file (the message names which).
    """
    path = Path(path)
    if path.is_dir():
        values, table = path / "abrdf.dat", path / "table.txt"
    elif path.name.lower() == "table.txt":
        values, table = path.with_name("abrdf.dat"), path
    else:
        values, table = path, path.with_name("table.txt")
    for file, what in ((values, "CURET values file abrdf.dat"), (table, "CURET angle table table.txt")):
        if not file.exists():
            raise BadInputError(file, f"no such file ({what}; both must be in the same folder)")
    return values, table


def _number(path: Path, line_no: int, token: str, nonfinite: Callable[[str], object] | None = None) -> float:
    """One decimal number token (``1``, ``-0.5``, ``2.5e-3``; :func:`parse_number`);
    BadInputError otherwise (``nan``, ``inf``, ``1_000``, hexadecimal and overflowing tokens
    included). With ``nonfinite``, a non-finite token is NaN and its message goes there instead."""
    try:
        return parse_number(token, strip=False)
    except NonFiniteNumberError:
        message = f"line {line_no}: non-finite number {token[:MAX_NUMBER_CHARS]!r}"
        if nonfinite is None:
            raise BadInputError(path, message) from None
        nonfinite(message)
        return float("nan")
    except ValueError:
        raise BadInputError(path, f"line {line_no}: {token[:MAX_NUMBER_CHARS]!r} is not a number") from None


def _rows(
    path: Path, what: str, n_numbers: int, max_rows: int, layout: str, bad: dict[int, str] | None = None
) -> list[tuple[int, list[float]]]:
    """(line number, numbers) of every non-blank line, each with exactly ``n_numbers`` numbers,
    at most ``max_rows`` rows; the counts are checked before any token is converted. With ``bad``,
    a non-finite number after a line's first token is not an error of the file: the line's
    message goes to ``bad[line number]`` and its numbers are NaN there (one bad sample of the
    values file fails alone)."""
    data = read_bytes(path, what, peak_per_byte=TEXT_PEAK_PER_BYTE)  # the memory plan of a text file
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as err:
        raise BadInputError(path, f"not an ASCII {what} (byte {err.start})") from None
    rows: list[tuple[int, list[float]]] = []
    for line_no, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if not tokens:
            continue
        if len(tokens) != n_numbers:
            raise BadInputError(path, f"line {line_no}: {len(tokens)} numbers, expected {n_numbers} ({layout})")
        if len(rows) == max_rows:
            raise BadInputError(path, f"line {line_no}: more than {max_rows} rows")
        record = None if bad is None else (lambda message, line_no=line_no: bad.setdefault(line_no, message))
        rows.append((line_no, [_number(path, line_no, tokens[0])]
                     + [_number(path, line_no, tok, record) for tok in tokens[1:]]))
    if not rows:
        raise BadInputError(path, f"empty {what}")
    return rows


def _direction(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    return np.stack((np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)), axis=-1)


@dataclass(frozen=True, eq=False)
class _Curet:
    """Both files parsed and checked."""

    L: np.ndarray  # (205, 3)
    V: np.ndarray  # (205, 3)
    values: dict[int, np.ndarray]  # sample -> (205,) raw values
    source: Path
    bad: dict[int, str] = field(default_factory=dict)  # sample -> why it cannot be read (its line)


def _read_table(path: Path) -> tuple[np.ndarray, np.ndarray]:
    rows = _rows(path, "CURET angle table", 5, CURET_N_MEASUREMENTS, "index θ_v φ_v θ_i φ_i")
    angles = []
    for k, (line_no, numbers) in enumerate(rows, start=1):
        if numbers[0] != k:
            raise BadInputError(path, f"line {line_no}: measurement index {numbers[0]:g}, expected {k}")
        theta_v, phi_v, theta_i, phi_i = numbers[1:]
        for name, theta in (("θ_v", theta_v), ("θ_i", theta_i)):
            if not -1e-6 <= theta <= np.pi / 2 + 1e-6:
                raise BadInputError(path, f"line {line_no}: {name} = {theta!r} rad outside [0, π/2]")
        if abs(phi_v) > 2 * np.pi + 1e-6 or abs(phi_i) > 2 * np.pi + 1e-6:
            raise BadInputError(path, f"line {line_no}: azimuth outside [−2π, 2π] (radians expected)")
        angles.append(numbers[1:])
    if len(angles) != CURET_N_MEASUREMENTS:
        raise BadInputError(path, f"{len(angles)} measurement rows, expected {CURET_N_MEASUREMENTS}")
    a = np.array(angles)
    V = _direction(a[:, 0], a[:, 1])  # camera = view
    L = _direction(a[:, 2], a[:, 3])  # source = light
    return L, V


def _read_values(path: Path, n: int) -> tuple[dict[int, np.ndarray], dict[int, str]]:
    bad_lines: dict[int, str] = {}
    rows = _rows(path, "CURET values file", 1 + n, 61, f"the sample number + {n} values", bad_lines)
    values: dict[int, np.ndarray] = {}
    bad: dict[int, str] = {}
    for line_no, numbers in rows:
        sample = numbers[0]
        if sample != int(sample) or not 1 <= sample <= 61:
            raise BadInputError(path, f"line {line_no}: sample number {sample:g} is not an integer in 1..61")
        if int(sample) in values:
            raise BadInputError(path, f"line {line_no}: sample {int(sample)} listed twice")
        values[int(sample)] = np.array(numbers[1:])
        if line_no in bad_lines:
            bad[int(sample)] = bad_lines[line_no]
    return values, bad


def _parse(path: str | os.PathLike[str]) -> _Curet:
    values_path, table_path = curet_files(path)
    L, V = _read_table(table_path)
    values, bad = _read_values(values_path, len(L))
    return _Curet(L=L, V=V, values=values, source=values_path, bad=bad)


def curet_samples(path: str | os.PathLike[str]) -> list[int]:
    """The sample numbers in a CURET ``abrdf.dat`` (all 61, 1..61, for the database's file).

    Parameters
    ----------
    path
        CURET folder, ``abrdf.dat`` or ``table.txt`` (:func:`curet_files`).

    Raises
    ------
    BadInputError
        Missing, unreadable or malformed files (as :func:`read_curet`).
    """
    return sorted(_parse(path).values)


def _select(sample: int | str | None, available: list[int], source: Path) -> int:
    if sample is None:
        raise BadInputError(
            source, f"a CURET file holds {len(available)} samples: choose one, e.g. '{source}#15' or "
            "read_curet(path, 15) (numbers 1..61 or names such as 'aluminum-foil')",
        )
    if isinstance(sample, str):
        text = sample.strip()
        if re.fullmatch(r"\d+", text):
            if len(text.lstrip("0")) > 6:  # int() refuses > 4300 digits with a ValueError; no sample is that large
                raise BadInputError(source, f"no sample {text[:12]}… ({len(text)} digits) in a CURET file (1..61)")
            sample = int(text)
        else:
            by_slug = {_slug(name): k for k, name in CURET_SAMPLE_NAMES.items()}
            if _slug(text) not in by_slug:
                raise BadInputError(source, f"no CURET sample named {sample!r}; see CURET_SAMPLE_NAMES")
            sample = by_slug[_slug(text)]
    if isinstance(sample, bool) or not isinstance(sample, int | np.integer):
        raise BadInputError(source, f"CURET sample must be a number 1..61 or a name, got {sample!r}")
    if int(sample) not in available:
        raise BadInputError(source, f"no sample {sample} in this file (it holds {available[0]}..{available[-1]})")
    return int(sample)


def _brdf(curet: _Curet, sample: int) -> ScatteredBRDF:
    if sample in curet.bad:
        raise BadInputError(curet.source, f"sample {sample}: {curet.bad[sample]}")
    raw = curet.values[sample]
    negative = raw < 0
    grey = np.maximum(raw, 0.0)
    name = CURET_SAMPLE_NAMES.get(sample, "")
    return ScatteredBRDF(
        L=curet.L.copy(),
        V=curet.V.copy(),
        rgb=np.repeat(grey[:, None], 3, axis=1),
        n_clipped=3 * int(np.count_nonzero(negative)),
        name=f"curet-{sample:02d}-{_slug(name)}" if name else f"curet-{sample:02d}",
        source=f"{curet.source}#{sample}",
    )


def read_curet(path: str | os.PathLike[str], sample: int | str | None = None) -> ScatteredBRDF:
    """Read one sample of the CURET BRDF database (``data_specs/curet.md``).

    Parameters
    ----------
    path
        The folder holding ``abrdf.dat`` and ``table.txt``, or either file.
    sample
        Sample number 1..61 (int or digit string), or its name from
        :data:`CURET_SAMPLE_NAMES` (case, spaces, ``_`` and ``-`` ignored: ``"aluminum-foil"``).

    Returns
    -------
    ScatteredBRDF
        205 measurements: ``L`` (205, 3) the illumination and ``V`` (205, 3) the view
        directions (unit vectors, normal +z, both away from the surface), ``rgb`` (205, 3) the
        grey value in 1/sr repeated in R, G, B with negative values clamped to 0,
        ``n_clipped`` = 3 × the number of clamped values, ``name`` ``curet-15-aluminum-foil``,
        ``source`` ``<abrdf.dat>#15``; ``spectral`` and ``wavelengths`` are None.

    Raises
    ------
    BadInputError
        No sample chosen (the message says how), an unknown sample, a missing file, non-ASCII
        content, a token that is not a finite decimal number, a row with the wrong number of
        values, too many rows, an index out of order, angles outside [0, π/2] (each naming the
        file and line).
    """
    curet = _parse(path)
    available = sorted(curet.values)
    return _brdf(curet, _select(sample, available, curet.source))


def read_curet_all(path: str | os.PathLike[str]) -> list[ScatteredBRDF]:
    """Every sample of a CURET ``abrdf.dat`` as :func:`read_curet` returns it, in sample order
    (the files are parsed once).

    Raises
    ------
    BadInputError
        As :func:`read_curet`.
    """
    curet = _parse(path)
    return [_brdf(curet, sample) for sample in sorted(curet.values)]
