"""Cornell gonioreflectometer ``.brdf`` files (scattered spectral measurements), input.

The ASCII format (``data_specs/cornell_brdf.md``): ``#`` comment lines; the number of
wavelengths (31); the wavelengths in nm (400..700 step 10, may wrap over lines); then one
row per measurement, ``theta_i phi_i theta_s phi_s`` in radians followed by one spectral
BRDF value (1/sr) per wavelength. Both directions point away from the surface, in the
standard spherical convention ω = (sin θ cos φ, sin θ sin φ, cos θ): φ_i = 0 and the
mirror direction of the incident one is at φ_s = π (the data's specular peaks are there).

Public objects: :class:`ScatteredBRDF`, :func:`read_cornell`.

References: [CornellBRDF]; [PBRT2] §8.6.2 (``IrregIsotropicBRDF``), which reads the same files.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .brdf import BRDF, Kind
from .colour import WAVELENGTHS_NM, spectral_to_linear_srgb
from .errors import BadInputError, ScatteredEvalError
from .limits import TEXT_PEAK_PER_BYTE, check_elements, read_bytes
from .spec_params import MAX_NUMBER_CHARS, NonFiniteNumberError, parse_number

__all__ = ["ScatteredBRDF", "read_cornell", "SCATTERED_EVAL_MESSAGE", "MAX_MEASURED_RHO", "MAX_WAVELENGTHS"]

SCATTERED_EVAL_MESSAGE = (
    "scattered measurements cannot be evaluated everywhere: fit a model "
    "(shrm fit / shrmkit.fit_brdf) first"
)


def _direction(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """ω = (sin θ cos φ, sin θ sin φ, cos θ) (DESIGN §2)."""
    return np.stack((np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)), axis=-1)


class ScatteredBRDF(BRDF):
    """Scattered BRDF measurements: rho known only at the measured direction pairs.

    Attributes
    ----------
    L, V
        (n, 3) unit vectors in the local frame (normal +z), both away from the surface:
        L is the file's incident direction (θ_i, φ_i), V its scattered one (θ_s, φ_s).
        By reciprocity rho(L, V) = rho(V, L), so the choice does not change rho.
    rgb
        (n, 3) linear sRGB rho in 1/sr (brdf_io/colour.py: D65, white-balanced), with
        components outside the sRGB gamut (negative; saturated blues and reds) clipped to 0,
        since a BRDF cannot be negative.
    n_clipped
        How many components of ``rgb`` were clipped (``spectral_to_linear_srgb(spectral)``
        gives the unclipped values).
    spectral
        (n, n_wavelengths) spectral rho in 1/sr.
    wavelengths
        The wavelengths in nm.
    name, source
        File stem and path.
    """

    kind: Kind = "scattered"

    def __init__(
        self,
        L: np.ndarray,
        V: np.ndarray,
        rgb: np.ndarray,
        *,
        spectral: np.ndarray | None = None,
        wavelengths: np.ndarray | None = None,
        name: str = "scattered",
        source: str | None = None,
        n_clipped: int = 0,
    ) -> None:
        self.L = np.asarray(L, dtype=np.float64)
        self.V = np.asarray(V, dtype=np.float64)
        self.rgb = np.asarray(rgb, dtype=np.float64)
        self.n_clipped = n_clipped
        self.spectral = spectral
        self.wavelengths = wavelengths
        self.name = name
        self.source = source

    def __len__(self) -> int:
        return self.L.shape[0]

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """Not available: raises :class:`ScatteredEvalError` (fit a model first)."""
        raise ScatteredEvalError(f"{self.name}: {SCATTERED_EVAL_MESSAGE}")


#: Largest spectral BRDF value accepted, 1/sr. The Cornell data peak at 655 1/sr; a value a
#: thousand times larger than any measured specular peak is a broken file, not a measurement.
MAX_MEASURED_RHO = 1e6
#: Largest wavelength count accepted in the header (the reader converts exactly 31).
MAX_WAVELENGTHS = 1000


def _number(path: Path, line_no: int, token: str) -> float:
    """One decimal number token (``1``, ``-0.5``, ``2.5e-3``; :func:`parse_number`);
    BadInputError otherwise."""
    try:
        return parse_number(token, strip=False)
    except NonFiniteNumberError as err:
        detail = " (overflows a float)" if err.overflow else ""
        raise BadInputError(path, f"line {line_no}: non-finite number {token!r}{detail}") from None
    except ValueError:
        shown = token if len(token) <= MAX_NUMBER_CHARS else token[:MAX_NUMBER_CHARS] + "..."
        raise BadInputError(path, f"line {line_no}: {shown!r} is not a number") from None


def read_cornell(path: str | os.PathLike[str]) -> ScatteredBRDF:
    """Read a Cornell ``.brdf`` file (data_specs/cornell_brdf.md).

    Returns
    -------
    ScatteredBRDF
        With ``L`` the incident and ``V`` the scattered directions, (n, 3) unit vectors;
        ``spectral`` the file's values, (n, 31) in 1/sr; ``rgb`` their linear sRGB
        (brdf_io/colour.py), clipped at 0, (n, 3) in 1/sr.

    Raises
    ------
    BadInputError
        Missing file, a FIFO, device or folder (refused before it is opened), a file over
        the size limit, non-ASCII or non-numeric content, a number token other than a
        decimal number (``nan``, ``inf``, ``1e999``, more than 64 characters), a wavelength
        count that is not a whole number in [1, 1000], a wavelength list other than the 31
        values 400, 410, ..., 700 nm, a row with the wrong number of values (truncated
        file), θ outside [0, π/2], |φ| above 2π, negative values or values above
        :data:`MAX_MEASURED_RHO`, no rows.
    """
    path = Path(path)
    try:
        # memory plan: the text, its lines and the rows (4.0 B per file byte measured on 27 MB)
        text = read_bytes(path, "Cornell .brdf file", peak_per_byte=TEXT_PEAK_PER_BYTE).decode("ascii")
    except UnicodeDecodeError as err:
        raise BadInputError(path, f"cannot read Cornell .brdf file: not ASCII text (byte {err.start})") from None
    wavelengths, data, row_lines = _parse_lines(path, text.splitlines())
    theta_i, phi_i, theta_s, phi_s = data[:, :4].T
    _check_angles(path, theta_i, phi_i, theta_s, phi_s, row_lines)
    spectral = data[:, 4:]
    _check_values(path, spectral, row_lines)
    rgb = spectral_to_linear_srgb(spectral)
    return ScatteredBRDF(
        L=_direction(theta_i, phi_i),  # incident direction = light
        V=_direction(theta_s, phi_s),  # scattered direction = view; mirror of L at phi_s = phi_i + pi
        rgb=np.maximum(rgb, 0.0),
        n_clipped=int(np.sum(rgb < 0)),
        spectral=spectral,
        wavelengths=np.array(wavelengths),
        name=path.stem,
        source=str(path),
    )


def _wavelength_count(path: Path, line_no: int, count: float) -> int:
    """Header 1: the number of wavelengths, a whole number in [1, :data:`MAX_WAVELENGTHS`]."""
    if count != int(count) or not 1 <= count <= MAX_WAVELENGTHS:
        raise BadInputError(
            path, f"line {line_no}: wavelength count {count!r} is not a positive integer "
            f"(at most {MAX_WAVELENGTHS})"
        )
    return int(count)


def _parse_lines(path: Path, lines: list[str]) -> tuple[list[float], np.ndarray, list[int]]:
    """The wavelengths (nm), the measurement rows (n, 4 + 31) (θ_i, φ_i, θ_s, φ_s in radians, then
    the spectral values in 1/sr) and each row's line number, from the file's lines."""
    n_wavelengths: int | None = None
    wavelengths: list[float] = []
    data: np.ndarray | None = None
    n_rows = 0
    row_lines: list[int] = []
    for line_no, line in enumerate(lines, start=1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        numbers = [_number(path, line_no, tok) for tok in body.split()]
        if n_wavelengths is None:
            # header 1: the number of wavelengths (possibly followed by the first ones)
            n_wavelengths = _wavelength_count(path, line_no, numbers[0])
            numbers = numbers[1:]
        if len(wavelengths) < n_wavelengths:
            # header 2: the wavelengths, which may wrap over several lines
            wavelengths.extend(numbers)
            if len(wavelengths) > n_wavelengths:
                raise BadInputError(
                    path, f"line {line_no}: {len(wavelengths)} wavelengths listed, the header says {n_wavelengths}"
                )
            continue
        # data: theta_i phi_i theta_s phi_s, then one value per wavelength, one row per line
        if len(numbers) != 4 + n_wavelengths:
            raise BadInputError(
                path, f"line {line_no}: {len(numbers)} numbers, expected 4 angles + {n_wavelengths} values"
            )
        if data is None:  # at most one row per remaining line: checked, then allocated once
            shape = (len(lines) - line_no + 1, 4 + n_wavelengths)
            check_elements(path, shape, "Cornell measurement rows")
            data = np.empty(shape)
        data[n_rows] = numbers
        n_rows += 1
        row_lines.append(line_no)
    _check_wavelengths(path, n_wavelengths, wavelengths)
    if data is None:
        raise BadInputError(path, "no measurement rows")
    return wavelengths, data[:n_rows], row_lines


def _check_wavelengths(path: Path, n_wavelengths: int | None, wavelengths: list[float]) -> None:
    """The header is complete and lists the 31 wavelengths 400, 410, ..., 700 nm."""
    if n_wavelengths is None or len(wavelengths) < n_wavelengths:
        raise BadInputError(path, "no wavelength header (count, then the wavelengths in nm)")
    if n_wavelengths != WAVELENGTHS_NM.size or not np.allclose(wavelengths, WAVELENGTHS_NM):
        shown = wavelengths if len(wavelengths) <= 40 else [*wavelengths[:40], "..."]
        raise BadInputError(
            path, f"wavelengths {shown} are not the 31 values 400, 410, ..., 700 nm this reader converts"
        )


def _check_angles(path: Path, theta_i: np.ndarray, phi_i: np.ndarray, theta_s: np.ndarray, phi_s: np.ndarray,
                  row_lines: list[int]) -> None:
    """θ in [0, π/2] and |φ| <= 2π (radians, 1e-6 slack); the first bad row's line otherwise."""
    thetas = np.stack((theta_i, theta_s), axis=1)
    bad = np.any((thetas < 0) | (thetas > np.pi / 2 + 1e-6), axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise BadInputError(
            path, f"line {row_lines[k]}: theta_i={float(theta_i[k])!r}, theta_s={float(theta_s[k])!r} outside [0, pi/2]"
        )
    bad = (np.abs(phi_i) > 2 * np.pi + 1e-6) | (np.abs(phi_s) > 2 * np.pi + 1e-6)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise BadInputError(
            path, f"line {row_lines[k]}: phi_i={float(phi_i[k])!r}, phi_s={float(phi_s[k])!r} outside [-2pi, 2pi]"
        )


def _check_values(path: Path, spectral: np.ndarray, row_lines: list[int]) -> None:
    """Spectral values in [0, :data:`MAX_MEASURED_RHO`] 1/sr; the first bad row's line otherwise."""
    bad = np.any(spectral < 0, axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise BadInputError(path, f"line {row_lines[k]}: negative BRDF value {float(spectral[k].min())!r}")
    bad = np.any(spectral > MAX_MEASURED_RHO, axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise BadInputError(
            path, f"line {row_lines[k]}: BRDF value {float(spectral[k].max())!r} above {MAX_MEASURED_RHO:g} 1/sr "
            "(not a plausible measurement)"
        )
