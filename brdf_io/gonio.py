"""Gonioreflectometer CSV files (NIST-style Mueller-matrix BRDF tables, [Germer17]), input.

:func:`read_gonio_csv` reads the unpolarised BRDF f_r11 ([Nic77]; the other Mueller elements
are ignored) of one wavelength (:func:`gonio_wavelengths` lists them) as a :class:`ScatteredBRDF`,
its columns found by name (:data:`GONIO_COLUMNS`). Both directions point away from the surface,
evaluated with the *signed* θ as written: a negative θ_i is the source at |θ_i| on the opposite
azimuth (NIST's convention, checked on the data). Columns, conventions, wavelengths and errors:
``data_specs/gonio_csv.md``.
"""

from __future__ import annotations

import csv
import io
import os
import re
from pathlib import Path

import numpy as np

from .cornell import ScatteredBRDF
from .errors import BadInputError
from .limits import TEXT_PEAK_PER_BYTE, check_elements, read_bytes
from .spec_params import MAX_NUMBER_CHARS, NonFiniteNumberError, parse_number

__all__ = ["GONIO_COLUMNS", "read_gonio_csv", "gonio_wavelengths"]

#: Column used → accepted header names (lower case).
GONIO_COLUMNS: dict[str, tuple[str, ...]] = {
    "lambda": ("lambda", "wavelength"),
    "thetai": ("thetai", "theta_i"),
    "phii": ("phi", "phii", "phi_i"),
    "thetar": ("thetar", "theta_r"),
    "phir": ("phir", "phi_r"),
    "f_r11": ("f_r11", "fr11", "brdf"),
}

#: Rows whose wavelength is within this many nm of the requested one are used.
WAVELENGTH_TOLERANCE_NM = 0.5


def _columns(path: Path, header: list[str]) -> dict[str, int]:
    names = [h.strip().lower() for h in header]
    found: dict[str, int] = {}
    missing = []
    for key, accepted in GONIO_COLUMNS.items():
        hits = [k for k, name in enumerate(names) if name in accepted]
        if len(hits) > 1:
            raise BadInputError(path, f"line 1: column {key!r} appears {len(hits)} times ({[header[k] for k in hits]})")
        if hits:
            found[key] = hits[0]
        else:
            missing.append("/".join(accepted))
    if missing:
        raise BadInputError(
            path, f"line 1: missing column(s) {', '.join(missing)}; header has {', '.join(h.strip() for h in header)}"
        )
    return found


def _number(path: Path, line_no: int, key: str, field: str) -> float:
    """One decimal number field (:func:`parse_number`, blanks not allowed); BadInputError
    naming line and column otherwise (``nan``, ``inf``, ``1_000``, overflowing and empty
    fields included)."""
    shown = field[:MAX_NUMBER_CHARS]
    try:
        return parse_number(field, strip=False)
    except NonFiniteNumberError:
        raise BadInputError(path, f"line {line_no}: column {key}: {shown!r} is not finite") from None
    except ValueError:
        raise BadInputError(path, f"line {line_no}: column {key}: {shown!r} is not a number") from None


def _table(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(data (n, 6) in GONIO_COLUMNS order, line numbers (n,))."""
    raw = read_bytes(path, "gonioreflectometer CSV", peak_per_byte=TEXT_PEAK_PER_BYTE)  # 6.2 measured on 9 MB
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise BadInputError(path, f"not a UTF-8 text CSV file (byte {err.start})") from None
    # at most one row per line: size the arrays before parsing (limits.check_elements)
    n_lines = text.count("\n") + 1
    check_elements(path, (n_lines, len(GONIO_COLUMNS)), "gonioreflectometer rows")
    reader = csv.reader(io.StringIO(text))
    try:
        header = next(reader)
    except StopIteration:
        raise BadInputError(path, "empty file (expected a header line naming the columns)") from None
    except csv.Error as err:
        raise BadInputError(path, f"line 1: {err}") from None
    cols = _columns(path, header)
    keys = list(GONIO_COLUMNS)
    order = [cols[key] for key in keys]
    data = np.empty((n_lines, len(keys)))
    lines = np.empty(n_lines, dtype=np.int64)
    n = 0
    try:
        for record in reader:
            line_no = reader.line_num
            if not record or all(not field.strip() for field in record):
                continue
            if len(record) != len(header):
                raise BadInputError(path, f"line {line_no}: {len(record)} fields, the header has {len(header)}")
            data[n] = [_number(path, line_no, key, record[k].strip()) for key, k in zip(keys, order, strict=True)]
            lines[n] = line_no
            n += 1
    except csv.Error as err:
        raise BadInputError(path, f"line {reader.line_num}: {err}") from None
    if n == 0:
        raise BadInputError(path, "no measurement rows after the header")
    return data[:n], lines[:n]


def _wavelengths_nm(data: np.ndarray) -> np.ndarray:
    return np.unique(np.round(data[:, 0] * 1000.0, 3))


def gonio_wavelengths(path: str | os.PathLike[str]) -> list[float]:
    """The distinct wavelengths of a gonioreflectometer CSV, in nm, ascending.

    Raises
    ------
    BadInputError
        As :func:`read_gonio_csv` (missing columns, non-numeric or non-finite entries).
    """
    data, _ = _table(Path(path))
    return [float(w) for w in _wavelengths_nm(data)]


def _parse_wavelength(path: Path, wavelength_nm: float | str) -> float:
    if isinstance(wavelength_nm, str):
        match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?\d+)?)\s*(nm|um|µm)?\s*", wavelength_nm)
        if not match:
            raise BadInputError(path, f"wavelength {wavelength_nm!r} is not a number of nm (e.g. '532' or '532nm')")
        value = float(match.group(1)) * (1000.0 if match.group(2) in ("um", "µm") else 1.0)
    else:
        value = float(wavelength_nm)
    if not (np.isfinite(value) and value > 0):
        raise BadInputError(path, f"wavelength {wavelength_nm!r} must be a positive number of nm")
    return value


def read_gonio_csv(path: str | os.PathLike[str], wavelength_nm: float | str | None = None) -> ScatteredBRDF:
    """Read a gonioreflectometer BRDF CSV (NIST PTFE layout, ``data_specs/gonio_csv.md``).

    Parameters
    ----------
    path
        The CSV file.
    wavelength_nm
        Wavelength to use, in nm (a number, or a string ``"532"``, ``"532nm"``, ``"0.532um"``);
        required when the file holds several. Rows within 0.5 nm are used.

    Returns
    -------
    ScatteredBRDF
        ``L`` (n, 3) toward the source, ``V`` (n, 3) toward the detector (unit vectors,
        normal +z, ω = (sin θ cos φ, sin θ sin φ, cos θ) with θ as
        signed in the file: ``data_specs/gonio_csv.md``), ``rgb`` (n, 3) f_r11 in 1/sr
        repeated (negative values clamped to 0, ``n_clipped`` = 3 × their number),
        ``spectral`` (n, 1) f_r11, ``wavelengths`` [λ in nm], ``name`` ``<stem>@<λ>nm``.

    Raises
    ------
    BadInputError
        Unreadable or non-UTF-8 file, more lines than ``SHRM_MAX_ELEMENTS`` allows (checked
        before parsing), missing or duplicate columns (the message lists the header), a row
        with another number of fields than the header, a used entry that is not a finite
        decimal number (with the line number and column), |θ| > 90°, several wavelengths and
        none chosen (they are listed), a requested wavelength the file lacks, no rows.
    """
    path = Path(path)
    data, lines = _table(path)
    available = _wavelengths_nm(data)
    listed = ", ".join(f"{w:g}" for w in available)
    if wavelength_nm is None:
        if len(available) > 1:
            first = f"{available[0]:g}"
            raise BadInputError(
                path, f"{len(available)} wavelengths in the file ({listed} nm): choose one, e.g. '{path}#{first}' "
                f"or read_gonio_csv(path, wavelength_nm={first})",
            )
        chosen = float(available[0])
    else:
        chosen = _parse_wavelength(path, wavelength_nm)
    keep = np.abs(data[:, 0] * 1000.0 - chosen) <= WAVELENGTH_TOLERANCE_NM
    if not np.any(keep):
        raise BadInputError(path, f"no rows at {chosen:g} nm; the file has {listed} nm")
    data, lines = data[keep], lines[keep]
    _, theta_i, phi_i, theta_r, phi_r, f = data.T
    for name, theta in (("thetai", theta_i), ("thetar", theta_r)):
        bad = np.abs(theta) > 90.0 + 1e-9
        if np.any(bad):
            k = int(np.argmax(bad))
            raise BadInputError(path, f"line {lines[k]}: {name} = {theta[k]:g}° outside [−90°, 90°]")
    ti, pi_, tr, pr = (np.radians(a) for a in (theta_i, phi_i, theta_r, phi_r))
    L = np.stack((np.sin(ti) * np.cos(pi_), np.sin(ti) * np.sin(pi_), np.cos(ti)), axis=-1)
    V = np.stack((np.sin(tr) * np.cos(pr), np.sin(tr) * np.sin(pr), np.cos(tr)), axis=-1)
    negative = f < 0
    grey = np.maximum(f, 0.0)
    return ScatteredBRDF(
        L=L,
        V=V,
        rgb=np.repeat(grey[:, None], 3, axis=1),
        spectral=f[:, None].copy(),
        wavelengths=np.array([chosen]),
        n_clipped=3 * int(np.count_nonzero(negative)),
        name=f"{path.stem}@{chosen:g}nm",
        source=str(path),
    )
