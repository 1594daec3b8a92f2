"""Spec strings for analytic BRDFs and the ``load_brdf`` entry point.

Grammar (see ``data_specs/spec_strings.md``)::

    spec   := name [":" param ("," param)*]
    param  := key "=" value
    value  := number | number "/" number "/" number | word

A value written ``r/g/b`` is an RGB triple. Lafortune lobes are numbered by a suffix on
the lobe keys: ``cxy, cz, n, ks`` (lobe 1), ``cxy2, cz2, n2, ks2`` (lobe 2), ...
Parameter values are parsed and range-checked by :mod:`~shrmkit.brdf_io.spec_params`.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .brdf import BRDF
from .cornell import read_cornell
from .curet import curet_samples, read_curet
from .errors import BadInputError
from .gonio import gonio_wavelengths, read_gonio_csv
from .jsonutil import loads_strict
from .limits import read_bytes, regular_file
from .merl import read_merl
from .models import (
    ALPHA_RANGE,
    MAX_EXPONENT,
    MAX_LAFORTUNE_COEFF,
    MAX_LOBE_PEAK,
    MAX_LOBES,
    MAX_SCALE,
    SIGMA_RANGE,
    CookTorrance,
    Lafortune,
    LafortuneLobe,
    Lambert,
    PhongLobe,
    SimplifiedMicrofacet,
    lafortune_lobe_peak,
)
from .rgl import RGL_INCIDENT, read_rgl
from .spec_params import SpecParams, parse_params
from .table import read_table
from .zernike import MAX_ORDER as MAX_ZERNIKE_ORDER
from .zernike import MAX_ZERNIKE_COEFF, ZernikeBRDF, basis_count

__all__ = [
    "parse_spec", "brdf_from_spec", "load_brdf", "brdf_sources", "BRDF_FILE_TYPES", "BrdfFileType", "MODEL_NAMES",
    "MAX_JSON_BYTES",
]

_SPEC_RE = re.compile(r"^\s*([a-z][a-z0-9_-]*)\s*(?::(.*))?$")
#: Largest ``.json`` model file read, bytes (a fit document is a few kilobytes).
MAX_JSON_BYTES = 2**24


def parse_spec(spec: str) -> tuple[str, dict[str, str]]:
    """Split ``name:key=value,...`` into the name and a dict of raw value strings
    (:func:`~shrmkit.brdf_io.spec_params.parse_params`)."""
    if not spec.strip().isprintable():
        raise BadInputError(repr(spec), "a spec string cannot hold control characters (line breaks, NUL, ...)")
    match = _SPEC_RE.match(spec)
    if not match:
        raise BadInputError(spec, "not a spec string of the form name:key=value,...")
    name, body = match.group(1), match.group(2)
    items = body.split(",") if body and body.strip() else []
    return name, parse_params(spec, items)


def _phong(p: SpecParams) -> BRDF:
    return PhongLobe(s=p.scalar("s", None, 0.0, MAX_EXPONENT), ks=p.color("ks", 1.0, 0.0, MAX_SCALE))


def _microfacet(p: SpecParams) -> BRDF:
    return SimplifiedMicrofacet(sigma=p.scalar("sigma", None, *SIGMA_RANGE), ks=p.color("ks", 1.0, 0.0, MAX_SCALE))


def _lambert(p: SpecParams) -> BRDF:
    return Lambert(albedo=p.color("albedo", 0.8, 0.0, 1.0))


def _lafortune(p: SpecParams) -> BRDF:
    kd = p.color("kd", 0.0, 0.0, 1.0)
    lobes = []
    suffixes = {re.sub(r"^(cxy|cz|n|ks)", "", k) for k in p.raw if re.match(r"^(cxy|cz|n|ks)\d*$", k)}
    numbered = [s for s in suffixes if s]
    if any(len(s) > 2 or s.startswith("0") for s in numbered) or len(suffixes) > MAX_LOBES:
        shown = sorted(s if len(s) <= 8 else s[:8] + "..." for s in numbered)
        raise BadInputError(p.spec, f"lafortune lobes must be numbered 1, 2, ..., {MAX_LOBES} (got {shown})")
    order = sorted(suffixes, key=lambda s: 1 if s == "" else int(s))
    for k, sfx in enumerate(order, start=1):
        if (sfx == "" and k != 1) or (sfx != "" and int(sfx) != k):
            raise BadInputError(p.spec, f"lafortune lobes must be numbered 1, 2, 3, ... (got {order})")
        lobe = LafortuneLobe(
            cxy=p.color(f"cxy{sfx}", -1.0, -MAX_LAFORTUNE_COEFF, MAX_LAFORTUNE_COEFF),
            cz=p.color(f"cz{sfx}", 1.0, -MAX_LAFORTUNE_COEFF, MAX_LAFORTUNE_COEFF),
            n=p.color(f"n{sfx}", None, 0.0, MAX_EXPONENT),
            ks=p.color(f"ks{sfx}", 1.0, 0.0),
        )
        peak = lafortune_lobe_peak(lobe.cxy, lobe.cz, lobe.n, lobe.ks)
        if np.any(peak > MAX_LOBE_PEAK):
            raise BadInputError(
                p.spec, f"lafortune lobe {k}: peak ks*max(|cxy|,|cz|)^n = {float(peak.max()):.3g} exceeds "
                f"{MAX_LOBE_PEAK:g} 1/sr",
            )
        lobes.append(lobe)
    return Lafortune(kd=kd, lobes=tuple(lobes))


def _cook_torrance(p: SpecParams) -> BRDF:
    return CookTorrance(
        kd=p.color("kd", 0.0, 0.0, 1.0),
        ks=p.color("ks", 1.0, 0.0, MAX_SCALE),
        alpha=p.scalar("alpha", None, *ALPHA_RANGE),
        f0=p.color("f0", 0.04, 0.0, 1.0),
        distribution=p.choice("dist", "beckmann", ("beckmann", "ggx")),
    )


def _zernike(p: SpecParams) -> BRDF:
    # brdf_io/zernike.py, "Spec string": n_max, then exactly basis_count(n_max) coefficients c0, c1, ...
    n_max = p.integer("n_max", None, 0, MAX_ZERNIKE_ORDER)
    count = basis_count(n_max)
    extra = sorted(k for k in p.raw if re.fullmatch(r"c\d+", k) and (len(k) > 6 or int(k[1:]) >= count))
    if extra:
        raise BadInputError(p.spec, f"order {n_max} has {count} Zernike coefficients c0..c{count - 1}; "
                            f"got {extra[0]}")
    coeffs = np.stack([p.color(f"c{a}", None, -MAX_ZERNIKE_COEFF, MAX_ZERNIKE_COEFF) for a in range(count)])
    return ZernikeBRDF(coeffs, n_max)


_MODELS: dict[str, Callable[[SpecParams], BRDF]] = {
    "phong": _phong,
    "microfacet": _microfacet,
    "lambert": _lambert,
    "lafortune": _lafortune,
    "cook-torrance": _cook_torrance,
    "zernike": _zernike,
}
MODEL_NAMES = tuple(_MODELS)


def brdf_from_spec(spec: str) -> BRDF:
    """Build an analytic BRDF from a spec string such as ``"phong:s=32"``.

    Raises
    ------
    BadInputError
        Unknown model or parameter, a missing parameter, or a value out of range.
    """
    spec = spec.strip()  # a line break read along with the spec is not part of it
    name, raw = parse_spec(spec)
    if name not in _MODELS:
        raise BadInputError(spec, f"unknown BRDF model {name!r}; known: {', '.join(MODEL_NAMES)}")
    params = SpecParams(spec, raw, owner=name)
    brdf = _MODELS[name](params)
    params.finish()
    return brdf


def _read_model_json(path: Path) -> BRDF:
    """The model of a ``.json`` file with a string key ``model_spec`` (data_specs/fit_json.md)."""
    size = regular_file(path, "JSON model file")
    if size > MAX_JSON_BYTES:
        raise BadInputError(path, f"JSON model file of {size:,} bytes; at most {MAX_JSON_BYTES:,}")
    doc = loads_strict(read_bytes(path, "JSON model file"), path, "JSON model file")
    if not isinstance(doc, dict):
        raise BadInputError(path, f"JSON model file holds a JSON {type(doc).__name__}, not an object")
    spec = doc.get("model_spec")
    if not isinstance(spec, str):
        raise BadInputError(path, "JSON model file has no string key 'model_spec'")
    try:
        return brdf_from_spec(spec)
    except BadInputError as err:
        shown = spec if len(spec) <= 200 else spec[:200] + "..."
        raise BadInputError(path, f"model_spec {shown!r}: {err.problem}") from None


@dataclass(frozen=True)
class BrdfFileType:
    """One entry of the BRDF file-type registry (keyed by suffix).

    ``read(path)`` — or ``read(path, selector)`` when ``selector`` says what the part after
    ``#`` in ``"file#…"`` picks — returns the BRDF; ``members(path)`` lists the selectors
    a whole file expands to (``shrm report FILE`` analyses each), None for one-BRDF files.
    """

    read: Callable[..., BRDF]
    what: str
    selector: str | None = None
    members: Callable[[Path], list[str]] | None = None


def _read_rgl_selected(path: Path, selector: str | None = None) -> BRDF:
    """An RGL file; ``file.bsdf#camera`` / ``file.bsdf#light`` names the direction that plays
    the file's incident direction ω_i (:data:`~shrmkit.brdf_io.rgl.RGL_INCIDENT`; default camera,
    as Mitsuba 3 renders the format: data_specs/rgl_bsdf.md)."""
    if selector is None:
        return read_rgl(path)
    key = selector.strip().lower()
    if key not in RGL_INCIDENT:
        raise BadInputError(
            f"{path}#{selector}", f"unknown RGL incident direction {selector!r}; valid: {', '.join(RGL_INCIDENT)}"
        )
    return read_rgl(path, table_direction=RGL_INCIDENT[key])


def _curet_members(path: Path) -> list[str]:
    return [str(n) for n in curet_samples(path)]


def _gonio_members(path: Path) -> list[str]:
    return [f"{w:g}" for w in gonio_wavelengths(path)]


# suffix -> file type: a new format touches this entry and its reader module
BRDF_FILE_TYPES: dict[str, BrdfFileType] = {
    ".binary": BrdfFileType(read_merl, "MERL table (data_specs/merl_binary.md)"),
    ".npz": BrdfFileType(read_table, "shrmkit table (data_specs/brdf_table.md)"),
    ".brdf": BrdfFileType(read_cornell, "Cornell scattered measurements (data_specs/cornell_brdf.md)"),
    ".bsdf": BrdfFileType(_read_rgl_selected, "RGL measured material, Mitsuba tensor_file (data_specs/rgl_bsdf.md)",
                          selector="incident direction: camera (default, as Mitsuba renders) or light"),
    ".dat": BrdfFileType(read_curet, "CURET abrdf.dat beside table.txt (data_specs/curet.md)",
                         selector="sample number 1..61 or name", members=_curet_members),
    ".csv": BrdfFileType(read_gonio_csv, "gonioreflectometer CSV (data_specs/gonio_csv.md)",
                         selector="wavelength in nm", members=_gonio_members),
    ".json": BrdfFileType(lambda path: _read_model_json(path), "fitted model (data_specs/fit_json.md)"),
}


def _split_selector(text: str) -> tuple[str, str | None]:
    """``"file.dat#12"`` -> (``"file.dat"``, ``"12"``) for file types with a selector."""
    base, sep, selector = text.rpartition("#")
    if sep and Path(base).suffix.lower() in BRDF_FILE_TYPES and BRDF_FILE_TYPES[Path(base).suffix.lower()].selector:
        return base, selector
    return text, None


def brdf_sources(spec_or_path: str | Path) -> list[str]:
    """The BRDFs a command-line argument names: ``[text]`` for a spec or a one-BRDF file,
    ``["FILE#sel", …]`` for a whole multi-BRDF file (the 61 CURET samples, each
    wavelength of a gonioreflectometer CSV).

    Raises
    ------
    BadInputError
        As the file's reader, when its members cannot be listed.
    """
    text = str(spec_or_path)
    base, selector = _split_selector(text)
    kind = BRDF_FILE_TYPES.get(Path(base).suffix.lower())
    if selector is not None or kind is None or kind.members is None or not _exists(Path(base)):
        return [text]
    members = kind.members(Path(base))
    return [text] if len(members) <= 1 else [f"{base}#{m}" for m in members]


def load_brdf(spec_or_path: str | Path) -> BRDF:
    """Load a BRDF from a spec string (``"microfacet:sigma=0.2"``) or a file.

    Files are recognised by extension (:data:`BRDF_FILE_TYPES`): ``.binary`` (MERL),
    ``.npz`` (shrmkit table), ``.brdf`` (Cornell scattered measurements), ``.bsdf`` (RGL
    measured material; ``file.bsdf#light`` takes the light as the file's incident direction
    instead of the default camera, data_specs/rgl_bsdf.md), ``.dat`` (CURET:
    ``abrdf.dat#12`` picks sample 12, by number or name), ``.csv`` (gonioreflectometer
    table: ``PTFE.data.csv#532`` picks 532 nm),
    ``.json`` (a fitted model: an object with a string key ``model_spec``, strict UTF-8
    JSON of at most :data:`MAX_JSON_BYTES`). :func:`brdf_sources` expands a whole
    multi-BRDF file into its members.

    Returns
    -------
    BRDF
        An analytic model, a :class:`~shrmkit.brdf_io.merl.MerlBRDF` or
        :class:`~shrmkit.brdf_io.table.TableBRDF` (``eval`` gives ρ in 1/sr, shape
        (..., 3)), or a :class:`~shrmkit.brdf_io.cornell.ScatteredBRDF`.

    Raises
    ------
    BadInputError
        A missing file, a folder, FIFO or device (refused before it is opened), an unknown
        file type, any problem its reader finds (naming the file; a bad ``model_spec``
        inside a ``.json`` file names the file and the spec), or a bad spec (the message
        names the spec, the parameter and its value; parameter bounds in
        ``data_specs/spec_strings.md``).

    Examples
    --------
    A model from a spec string; ρ of a Lambertian surface is albedo/π for every pair of
    directions above the surface, and 0 when one is below it:

    >>> import numpy as np
    >>> brdf = load_brdf("lambert:albedo=0.2/0.5/0.8")
    >>> brdf.eval(np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8]))
    array([0.06366198, 0.15915494, 0.25464791])
    >>> brdf.eval(np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, -0.8]))
    array([0., 0., 0.])

    RH02's Phong lobe, ρ̂ = (s + 1)/(2π) cos^s of the angle between L and the mirror
    direction of V; at L = V = N that is 9/(2π) for s = 8:

    >>> N = np.array([0.0, 0.0, 1.0])
    >>> load_brdf("phong:s=8").rho_hat(N, N)
    array([1.43239449, 1.43239449, 1.43239449])

    A table file (data_specs/brdf_table.md): ``tests/resources/tiny_table.npz`` holds
    ρ = (0.1 + 0.2 θ_i/90°, 0.3 + 0.1 θ_o/90°, 0.2 + 0.1 φ_d/180°) on the grid corners,
    which the interpolation (trilinear in angle) reproduces exactly in between:

    >>> table = load_brdf("tests/resources/tiny_table.npz")
    >>> type(table).__name__, table.values.shape
    ('TableBRDF', (2, 2, 2, 3))
    >>> theta_i, theta_o = np.radians(60.0), np.radians(30.0)
    >>> L = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])
    >>> V = np.array([0.0, np.sin(theta_o), np.cos(theta_o)])  # φ_d = 90°
    >>> table.eval(L, V)
    array([0.23333333, 0.33333333, 0.25      ])

    A bad parameter names the spec, the key and the value:

    >>> load_brdf("microfacet:sigma=-1")
    Traceback (most recent call last):
    ...
    shrmkit.brdf_io.errors.BadInputError: microfacet:sigma=-1: parameter sigma=-1 outside [0.005, 2]
    """
    text = str(spec_or_path)
    shown = text if text.isprintable() else repr(text)  # errors stay one line
    if not text.strip() or "\0" in text:
        raise BadInputError(repr(text), "neither a BRDF file nor a BRDF spec (empty, or holds NUL)")
    base, selector = _split_selector(text)
    path = Path(base)
    known = tuple(BRDF_FILE_TYPES)
    kind = BRDF_FILE_TYPES.get(path.suffix.lower())
    if kind is not None:
        if not _exists(path):
            raise BadInputError(shown if selector is None else path, "no such file")
        return kind.read(path) if selector is None else kind.read(path, selector)
    if ":" in text or text.split(":")[0] in _MODELS:
        return brdf_from_spec(text)
    if _exists(path):
        raise BadInputError(shown, f"unknown BRDF file type {path.suffix!r}; known: {', '.join(known)}")
    raise BadInputError(shown, f"neither an existing file nor a BRDF spec ({', '.join(MODEL_NAMES)})")


def _exists(path: Path) -> bool:
    """Whether ``path`` names anything (a name too long for the OS names nothing)."""
    try:
        return path.exists()
    except (OSError, ValueError):
        return False
