"""Cornell gonioreflectometer ``.brdf`` files (scattered spectral measurements), input.

The ASCII format (``data_specs/cornell_brdf.md``): ``#`` comment lines; the number of
wavelengths (31); the wavelengths in nm (400..700 step 10, may wrap over lines); then one
row per measurement, ``theta_i phi_i theta_s phi_s`` in radians followed by one spectral
BRDF value (1/sr) per wavelength. Both directions point away from the surface, in the
standard spherical convention ω = (sin θ cos φ, sin θ sin φ, cos θ): φ_i = 0 and the
mirror direction of the incident one is at φ_s = π (the data's specular peaks are there).

Public objects: :class:`ScatteredBRDF`, :func:`read_cornell`.

References
----------
Cornell University Program of Computer Graphics measurements, as distributed with pbrt-v2
(scenes/brdfs/); M. Pharr, G. Humphreys, "Physically Based Rendering", 2nd ed., §8.6.2
(``IrregIsotropicBRDF``), which reads the same files.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .brdf import BRDF, Kind
from .colour import WAVELENGTHS_NM, spectral_to_linear_srgb
from .errors import BadInputError, ScatteredEvalError

__all__ = ["ScatteredBRDF", "read_cornell", "SCATTERED_EVAL_MESSAGE"]

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


def _numbers(path: Path, line_no: int, text: str) -> list[float]:
    try:
        return [float(tok) for tok in text.split()]
    except ValueError:
        bad = next(tok for tok in text.split() if not _is_float(tok))
        raise BadInputError(path, f"line {line_no}: {bad!r} is not a number") from None


def _is_float(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def read_cornell(path: str | os.PathLike[str]) -> ScatteredBRDF:
    """Read a Cornell ``.brdf`` file (data_specs/cornell_brdf.md).

    Returns
    -------
    ScatteredBRDF
        With ``L`` the incident and ``V`` the scattered directions, ``spectral`` the
        file's values, ``rgb`` their linear sRGB (brdf_io/colour.py), clipped at 0.

    Raises
    ------
    BadInputError
        Unreadable or non-numeric content, a wavelength count or list other than
        31 values 400, 410, ..., 700 nm, a row with the wrong number of values (truncated
        file), angles outside the upper hemisphere, non-finite or negative values, no rows.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="ascii")
    except (OSError, UnicodeDecodeError) as err:
        raise BadInputError(path, f"cannot read Cornell .brdf file ({err})") from None
    n_wavelengths: int | None = None
    wavelengths: list[float] = []
    rows: list[list[float]] = []
    row_lines: list[int] = []
    for line_no, line in enumerate(text.splitlines(), start=1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        numbers = _numbers(path, line_no, body)
        if n_wavelengths is None:
            # header 1: the number of wavelengths (possibly followed by the first ones)
            count = numbers[0]
            if count != int(count) or count < 1:
                raise BadInputError(path, f"line {line_no}: wavelength count {count!r} is not a positive integer")
            n_wavelengths = int(count)
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
        rows.append(numbers)
        row_lines.append(line_no)
    if n_wavelengths is None or len(wavelengths) < n_wavelengths:
        raise BadInputError(path, "no wavelength header (count, then the wavelengths in nm)")
    if n_wavelengths != WAVELENGTHS_NM.size or not np.allclose(wavelengths, WAVELENGTHS_NM):
        raise BadInputError(
            path, f"wavelengths {wavelengths} are not the 31 values 400, 410, ..., 700 nm this reader converts"
        )
    if not rows:
        raise BadInputError(path, "no measurement rows")
    data = np.array(rows)
    bad = ~np.all(np.isfinite(data), axis=1)
    if np.any(bad):
        raise BadInputError(path, f"line {row_lines[int(np.argmax(bad))]}: non-finite number")
    theta_i, phi_i, theta_s, phi_s = data[:, :4].T
    thetas = np.stack((theta_i, theta_s), axis=1)
    bad = np.any((thetas < 0) | (thetas > np.pi / 2 + 1e-6), axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise BadInputError(
            path, f"line {row_lines[k]}: theta_i={theta_i[k]!r}, theta_s={theta_s[k]!r} outside [0, pi/2]"
        )
    spectral = data[:, 4:]
    bad = np.any(spectral < 0, axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise BadInputError(path, f"line {row_lines[k]}: negative BRDF value {spectral[k].min()!r}")
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
