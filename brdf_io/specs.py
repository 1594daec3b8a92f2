"""Spec strings for analytic BRDFs and the ``load_brdf`` entry point.

Grammar (see ``data_specs/spec_strings.md``)::

    spec   := name [":" param ("," param)*]
    param  := key "=" value
    value  := number | number "/" number "/" number | word

A value written ``r/g/b`` is an RGB triple. Lafortune lobes are numbered by a suffix on
the lobe keys: ``cxy, cz, n, ks`` (lobe 1), ``cxy2, cz2, n2, ks2`` (lobe 2), ...
"""

from __future__ import annotations

import importlib
import json
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .brdf import BRDF
from .errors import BadInputError
from .models import (
    CookTorrance,
    Lafortune,
    LafortuneLobe,
    Lambert,
    PhongLobe,
    SimplifiedMicrofacet,
    rgb,
)

__all__ = ["parse_spec", "brdf_from_spec", "load_brdf", "MODEL_NAMES"]

_SPEC_RE = re.compile(r"^\s*([a-z][a-z0-9_-]*)\s*(?::(.*))?$")


def parse_spec(spec: str) -> tuple[str, dict[str, str]]:
    """Split ``name:key=value,...`` into the name and a dict of raw value strings."""
    match = _SPEC_RE.match(spec)
    if not match:
        raise BadInputError(spec, "not a spec string of the form name:key=value,...")
    name, body = match.group(1), match.group(2)
    params: dict[str, str] = {}
    if body and body.strip():
        for item in body.split(","):
            key, sep, value = item.partition("=")
            key, value = key.strip(), value.strip()
            if not sep or not key or not value:
                raise BadInputError(spec, f"parameter {item.strip()!r} is not of the form key=value")
            if key in params:
                raise BadInputError(spec, f"parameter {key!r} given twice")
            params[key] = value
    return name, params


class _Params:
    """Typed access to raw spec parameters, with one place for range checks."""

    def __init__(self, spec: str, raw: dict[str, str]) -> None:
        self.spec = spec
        self.raw = dict(raw)
        self.used: set[str] = set()

    def _number_list(self, key: str) -> list[float]:
        text = self.raw[key]
        try:
            values = [float(v) for v in text.split("/")]
        except ValueError:
            raise BadInputError(self.spec, f"parameter {key}={text!r} is not a number") from None
        if len(values) not in (1, 3):
            raise BadInputError(self.spec, f"parameter {key}={text!r}: give one value or r/g/b")
        if not all(np.isfinite(values)):
            raise BadInputError(self.spec, f"parameter {key}={text!r} is not finite")
        return values

    def color(self, key: str, default: float | None, lo: float = -np.inf, hi: float = np.inf,
              lo_open: bool = False) -> np.ndarray:
        if key not in self.raw:
            if default is None:
                raise BadInputError(self.spec, f"missing parameter {key!r}")
            return rgb(default)
        self.used.add(key)
        values = self._number_list(key)
        for v in values:
            if v < lo or v > hi or (lo_open and v == lo):
                bracket = "(" if lo_open else "["
                raise BadInputError(
                    self.spec, f"parameter {key}={self.raw[key]} outside {bracket}{lo:g}, {hi:g}]"
                )
        return rgb(values[0] if len(values) == 1 else values)

    def scalar(self, key: str, default: float | None, lo: float = -np.inf, hi: float = np.inf,
               lo_open: bool = False) -> float:
        value = self.color(key, default, lo, hi, lo_open)
        if key in self.raw and "/" in self.raw[key]:
            raise BadInputError(self.spec, f"parameter {key} takes one value, not r/g/b")
        return float(value[0])

    def choice(self, key: str, default: str, options: tuple[str, ...]) -> str:
        value = self.raw.get(key, default)
        self.used.add(key)
        if value not in options:
            raise BadInputError(self.spec, f"parameter {key}={value!r}: choose one of {options}")
        return value

    def finish(self) -> None:
        unknown = sorted(set(self.raw) - self.used)
        if unknown:
            raise BadInputError(self.spec, f"unknown parameter(s) {', '.join(unknown)}")


def _phong(p: _Params) -> BRDF:
    return PhongLobe(s=p.scalar("s", None, 0.0, 1e7), ks=p.color("ks", 1.0, 0.0))


def _microfacet(p: _Params) -> BRDF:
    return SimplifiedMicrofacet(
        sigma=p.scalar("sigma", None, 0.0, 2.0, lo_open=True), ks=p.color("ks", 1.0, 0.0)
    )


def _lambert(p: _Params) -> BRDF:
    return Lambert(albedo=p.color("albedo", 0.8, 0.0, 1.0))


def _lafortune(p: _Params) -> BRDF:
    kd = p.color("kd", 0.0, 0.0, 1.0)
    lobes = []
    suffixes = {re.sub(r"^(cxy|cz|n|ks)", "", k) for k in p.raw if re.match(r"^(cxy|cz|n|ks)\d*$", k)}
    order = sorted(suffixes, key=lambda s: 1 if s == "" else int(s))
    for k, sfx in enumerate(order, start=1):
        if (sfx == "" and k != 1) or (sfx != "" and int(sfx) != k):
            raise BadInputError(p.spec, f"lafortune lobes must be numbered 1, 2, 3, ... (got {order})")
        lobes.append(
            LafortuneLobe(
                cxy=p.color(f"cxy{sfx}", -1.0),
                cz=p.color(f"cz{sfx}", 1.0),
                n=p.color(f"n{sfx}", None, 0.0, 1e7),
                ks=p.color(f"ks{sfx}", 1.0, 0.0),
            )
        )
    return Lafortune(kd=kd, lobes=tuple(lobes))


def _cook_torrance(p: _Params) -> BRDF:
    return CookTorrance(
        kd=p.color("kd", 0.0, 0.0, 1.0),
        ks=p.color("ks", 1.0, 0.0),
        alpha=p.scalar("alpha", None, 1e-4, 4.0),
        f0=p.color("f0", 0.04, 0.0, 1.0),
        distribution=p.choice("dist", "beckmann", ("beckmann", "ggx")),
    )


_MODELS: dict[str, Callable[[_Params], BRDF]] = {
    "phong": _phong,
    "microfacet": _microfacet,
    "lambert": _lambert,
    "lafortune": _lafortune,
    "cook-torrance": _cook_torrance,
}
MODEL_NAMES = tuple(_MODELS)


def brdf_from_spec(spec: str) -> BRDF:
    """Build an analytic BRDF from a spec string such as ``"phong:s=32"``.

    Raises
    ------
    BadInputError
        Unknown model or parameter, a missing parameter, or a value out of range.
    """
    name, raw = parse_spec(spec)
    if name not in _MODELS:
        raise BadInputError(spec, f"unknown BRDF model {name!r}; known: {', '.join(MODEL_NAMES)}")
    params = _Params(spec, raw)
    brdf = _MODELS[name](params)
    params.finish()
    return brdf


def _read_model_json(path: Path) -> BRDF:
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise BadInputError(path, f"not a readable JSON model file ({err})") from None
    spec = doc.get("model_spec") if isinstance(doc, dict) else None
    if not isinstance(spec, str):
        raise BadInputError(path, "JSON model file has no string key 'model_spec'")
    return brdf_from_spec(spec)


# extension -> (module in this package, reader function); imported only when used
_FILE_READERS = {
    ".binary": ("merl", "read_merl"),
    ".npz": ("table", "read_table"),
    ".brdf": ("cornell", "read_cornell"),
}


def _read_brdf_file(path: Path) -> BRDF:
    suffix = path.suffix.lower()
    if suffix == ".json":
        return _read_model_json(path)
    module_name, function_name = _FILE_READERS[suffix]
    module = importlib.import_module(f"{__package__}.{module_name}")
    return getattr(module, function_name)(path)


def load_brdf(spec_or_path: str | Path) -> BRDF:
    """Load a BRDF from a spec string (``"microfacet:sigma=0.2"``) or a file.

    Files are recognised by extension: ``.binary`` (MERL), ``.npz`` (shrmkit table),
    ``.brdf`` (Cornell scattered measurements), ``.json`` (a fitted model).
    """
    text = str(spec_or_path)
    path = Path(text)
    known = (*_FILE_READERS, ".json")
    if path.suffix.lower() in known:
        if not path.exists():
            raise BadInputError(path, "no such file")
        return _read_brdf_file(path)
    if ":" in text or text.split(":")[0] in _MODELS:
        return brdf_from_spec(text)
    if path.exists():
        raise BadInputError(path, f"unknown BRDF file type {path.suffix!r}; known: {', '.join(known)}")
    raise BadInputError(text, f"neither an existing file nor a BRDF spec ({', '.join(MODEL_NAMES)})")
