"""Hostile and broken BRDF-side inputs: table ``.npz``, ``.shrm.npz``, MERL ``.binary``,
Cornell ``.brdf``, fit ``.json`` and spec strings.

Every case must end in a one-line :class:`BadInputError` that names the file (or spec),
quickly and without a large allocation, or load with finite values. The limits and bounds
are documented in data_specs/brdf_table.md, shrm_file.md, merl_binary.md, cornell_brdf.md,
spec_strings.md and fit_json.md.
"""

from __future__ import annotations

import io
import json
import math
import os
import struct
import tracemalloc
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.shrm import SHRM
from shrmkit.brdf_io.cornell import MAX_MEASURED_RHO, ScatteredBRDF, read_cornell
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.merl import read_merl
from shrmkit.brdf_io.models import (
    ALPHA_RANGE,
    MAX_EXPONENT,
    MAX_LAFORTUNE_COEFF,
    MAX_LOBE_PEAK,
    MAX_LOBES,
    MAX_SCALE,
    SIGMA_RANGE,
)
from shrmkit.brdf_io.specs import brdf_from_spec, load_brdf
from shrmkit.brdf_io.table import MAX_TABLE_RHO, read_table, write_table

# ------------------------------------------------------------------------------ helpers


def _npy(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=False)
    return buf.getvalue()


def _npy_raw(
    descr: str, shape: tuple[int, ...], data: bytes = b"", version: int = 1, header: str | None = None
) -> bytes:
    """A ``.npy`` member with a hand-written header (any shape, any descr) and ``data``."""
    text = header if header is not None else f"{{'descr': {descr!r}, 'fortran_order': False, 'shape': {shape!r}, }}"
    start = 10 if version == 1 else 12
    body = text.encode("latin1")
    body += b" " * ((-(start + len(body) + 1)) % 64) + b"\n"
    size = struct.pack("<H" if version == 1 else "<I", len(body))
    return b"\x93NUMPY" + bytes((version, 0)) + size + body + data


def _zip(path: Path, members: dict[str, bytes], compression: int = zipfile.ZIP_STORED) -> Path:
    with zipfile.ZipFile(path, "w", compression=compression) as archive:
        for name, payload in members.items():
            archive.writestr(name + ".npy", payload)
    return path


def _table_members() -> dict[str, bytes]:
    meta = {"format": "shrmkit-brdf-table", "format_version": 1, "units": "1/sr", "name": "x"}
    return {
        "theta_i": _npy(np.array([0.0, 0.5, 1.0])),
        "theta_o": _npy(np.array([0.0, 0.7, 1.4])),
        "phi_d": _npy(np.array([0.0, 1.0, 2.0, 3.0])),
        "values": _npy(np.full((3, 3, 4, 3), 0.25)),
        "metadata": _npy(np.array(json.dumps(meta))),
    }


def _shrm_header(**change: object) -> dict[str, object]:
    header: dict[str, object] = {
        "format": "shrmkit-shrm", "version": 1, "F": 3, "P": 1, "tolerance": 0.05,
        "eps": {"brdf": 0.01, "bound": None}, "grid": "latlong", "orientation": "z-up", "meta": {"brdf": "x"},
        "cube": None,
    }
    header.update(change)
    return header


def _shrm_members(header: object = None, coeffs: np.ndarray | None = None, cube: np.ndarray | None = None,
                  header_text: str | None = None) -> dict[str, bytes]:
    coeffs = np.full((4, 4, 8, 3), 0.5, np.float32) if coeffs is None else coeffs
    text = header_text if header_text is not None else json.dumps(_shrm_header() if header is None else header)
    members = {"coeffs": _npy(coeffs), "header": _npy(np.array(text))}
    if cube is not None:
        members["cube"] = _npy(cube)
    return members


def _raises_naming(path: Path | str, load: Callable[[], object], match: str | None = None) -> BadInputError:
    with pytest.raises(BadInputError, match=match) as info:
        load()
    text = str(info.value)
    assert str(path) in text, text
    assert "\n" not in text, text
    return info.value


def _small_peak(load: Callable[[], object], limit_bytes: int = 64 * 2**20) -> None:
    """``load`` raises BadInputError and allocates (traced by Python and numpy) under the limit."""
    tracemalloc.start()
    try:
        with pytest.raises(BadInputError):
            load()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < limit_bytes, f"peak {peak / 2**20:.0f} MiB"


# ------------------------------------------------------------------ 1. npz declared sizes


@pytest.mark.parametrize("shape", [(10**9,), (2**40,), (2**20, 2**20, 3), (-1, 3)])
@pytest.mark.parametrize("reader", ["table", "shrm"])
def test_npz_member_declaring_a_huge_array_is_refused_before_allocation(tmp_path, shape, reader):
    if reader == "table":
        members = _table_members()
        members["values"] = _npy_raw("<f8", shape, b"\0" * 64)
        path, load = _zip(tmp_path / "huge.npz", members), read_table
    else:
        members = _shrm_members()
        members["coeffs"] = _npy_raw("<f4", shape, b"\0" * 64)
        path, load = _zip(tmp_path / "huge.shrm.npz", members), shrmkit.load_shrm
    assert path.stat().st_size < 4096
    _raises_naming(path, lambda: load(path))
    _small_peak(lambda: load(path))


@pytest.mark.parametrize(
    ("member", "descr", "message"),
    [
        ("values", "|O", "expected floating point"),  # pickled objects: never unpickled
        ("values", "<c16", "expected floating point"),
        ("values", "|S8", "expected floating point"),
        ("values", "|b1", "expected floating point"),
        ("metadata", "<f8", "expected a JSON string"),
        ("theta_i", "<U3", "expected a real-number"),
    ],
)
def test_npz_member_of_the_wrong_dtype_is_refused(tmp_path, member, descr, message):
    members = _table_members()
    shape = () if member == "metadata" else (3,)
    members[member] = _npy_raw(descr, shape, b"\0" * (3 * np.dtype(descr).itemsize))
    path = _zip(tmp_path / "dtype.npz", members)
    _raises_naming(path, lambda: read_table(path), message)


def test_npz_huge_or_broken_npy_headers_are_refused(tmp_path):
    cases = {
        # a 4 GiB header length (format 2.0)
        "length": b"\x93NUMPY\x02\x00" + struct.pack("<I", 2**32 - 1) + b"{",
        "version": b"\x93NUMPY\x07\x00" + struct.pack("<H", 10) + b"{}        ",
        "magic": b"NOTNUMPY" + b"\0" * 100,
        "syntax": _npy_raw("", (), header="{'descr': '<f8', 'fortran_order': False, 'shape': (3,"),
        "keys": _npy_raw("", (), header="{'descr': '<f8'}"),
        "descr": _npy_raw("", (), header="{'descr': '<U99999999999999', 'fortran_order': False, 'shape': (), }"),
        "subarray": _npy_raw("", (), header="{'descr': [('a', '<f8', (1000000000,))], 'fortran_order': False, "
                                            "'shape': (3,), }"),
        "string": _npy_raw("<U500000000", ()),  # 2 GB declared string
        "nested": _npy_raw("", (), header="(" * 5000 + ")" * 5000),
    }
    for name, payload in cases.items():
        members = _table_members()
        members["values" if name not in ("string",) else "metadata"] = payload
        path = _zip(tmp_path / f"{name}.npz", members)
        _raises_naming(path, lambda p=path: read_table(p))


def test_npz_member_size_must_match_its_declared_shape(tmp_path):
    members = _table_members()
    members["values"] = _npy_raw("<f8", (3, 3, 4, 3), b"\0" * 80)  # 10 of 108 values
    path = _zip(tmp_path / "short.npz", members)
    _raises_naming(path, lambda: read_table(path), "truncated or padded")
    members["values"] = _npy(np.ones((3, 3, 4, 3))) + b"\0" * 8
    path = _zip(tmp_path / "long.npz", members)
    _raises_naming(path, lambda: read_table(path), "truncated or padded")


def test_npz_zip_bombs_and_odd_archives_are_refused(tmp_path, monkeypatch):
    # a member declaring far more than deflate can produce from its compressed bytes
    path = _zip(tmp_path / "bomb.npz", _table_members(), zipfile.ZIP_DEFLATED)
    data = bytearray(path.read_bytes())
    central = data.index(b"PK\x01\x02")
    struct.pack_into("<I", data, central + 24, 2**31)  # uncompressed size of the first member
    path.write_bytes(bytes(data))
    _raises_naming(path, lambda: read_table(path), "ratio")
    # a member over the size limit, honestly compressed
    monkeypatch.setenv("SHRM_MAX_ELEMENTS", "1000")
    path = tmp_path / "big.npz"
    write_table(path, np.full((30, 30, 30), 0.1), theta_i=np.linspace(0, 1, 30), theta_o=np.linspace(0, 1, 30),
                phi_d=np.linspace(0, 3, 30))
    _raises_naming(path, lambda: read_table(path), "limit")
    monkeypatch.delenv("SHRM_MAX_ELEMENTS")
    assert read_table(path).values.shape == (30, 30, 30)
    # a corrupt deflate stream, a bad CRC, a compression method numpy never writes
    good = _zip(tmp_path / "good.npz", _table_members(), zipfile.ZIP_DEFLATED).read_bytes()
    local = good.index(b"PK\x03\x04")
    name_len, extra_len = struct.unpack_from("<HH", good, local + 26)
    start = local + 30 + name_len + extra_len
    broken = bytearray(good)
    broken[start : start + 8] = b"\xff" * 8
    (tmp_path / "deflate.npz").write_bytes(bytes(broken))
    _raises_naming(tmp_path / "deflate.npz", lambda: read_table(tmp_path / "deflate.npz"))
    crc = bytearray(good)
    struct.pack_into("<I", crc, crc.index(b"PK\x01\x02") + 16, 12345)
    struct.pack_into("<I", crc, local + 14, 12345)
    (tmp_path / "crc.npz").write_bytes(bytes(crc))
    _raises_naming(tmp_path / "crc.npz", lambda: read_table(tmp_path / "crc.npz"))
    bz = _zip(tmp_path / "bz.npz", _table_members(), zipfile.ZIP_BZIP2)
    _raises_naming(bz, lambda: read_table(bz), "compression method")


def test_table_values_and_metadata_limits(tmp_path):
    members = _table_members()
    members["values"] = _npy(np.full((3, 3, 4, 3), 1e300))
    path = _zip(tmp_path / "big_values.npz", members)
    _raises_naming(path, lambda: read_table(path), f"above {MAX_TABLE_RHO:g}".replace("+", r"\+"))
    for text in ('{"format": "shrmkit-brdf-table", "format_version": NaN}', "[1, 2]", "[" * 100000,
                 '{"format": "shrmkit-brdf-table", "format_version": 1.0, "units": "1/sr"}',
                 '{"format": "shrmkit-brdf-table", "format_version": ' + "1" * 5000 + "}"):
        members = _table_members()
        members["metadata"] = _npy(np.array(text))
        path = _zip(tmp_path / "meta.npz", members)
        _raises_naming(path, lambda p=path: read_table(p))
    members = _table_members()
    meta = {"format": "shrmkit-brdf-table", "format_version": 1, "units": "1/sr", "name": "two\nlines"}
    members["metadata"] = _npy(np.array(json.dumps(meta)))
    assert read_table(_zip(tmp_path / "named.npz", members)).name == "named"


# ------------------------------------------------------------------ 2. SHRM header


def test_shrm_hand_built_round_trip_keeps_unknown_tolerance(tmp_path):
    coeffs = np.random.default_rng(0).normal(size=(4, 4, 8, 3)).astype(np.float32)
    back = shrmkit.load_shrm(SHRM(F=3, P=1, coeffs=coeffs).save(tmp_path / "hand.shrm.npz"))
    assert math.isnan(back.tolerance) and np.array_equal(back.coeffs, coeffs) and (back.F, back.P) == (3, 1)


_BAD_HEADERS = {
    "not an object": [1, 2],
    "no F": {k: v for k, v in _shrm_header().items() if k != "F"},
    "no meta": {k: v for k, v in _shrm_header().items() if k != "meta"},
    "no eps": {k: v for k, v in _shrm_header().items() if k != "eps"},
    "F string": _shrm_header(F="3"),
    "F float": _shrm_header(F=1.5),
    "F bool": _shrm_header(F=True),
    "F negative": _shrm_header(F=-1),
    "F huge": _shrm_header(F=10**9),
    "P negative": _shrm_header(P=-2),
    "P float": _shrm_header(P=1.0),
    "P mismatch": _shrm_header(P=2),
    "tolerance negative": _shrm_header(tolerance=-0.1),
    "tolerance 1": _shrm_header(tolerance=1.0),
    "tolerance string": _shrm_header(tolerance="x"),
    "eps list": _shrm_header(eps=[]),
    "eps value": _shrm_header(eps={"brdf": "x"}),
    "grid": _shrm_header(grid="cube"),
    "orientation": _shrm_header(orientation=None),
    "meta list": _shrm_header(meta=[]),
    "cube claimed": _shrm_header(cube="faces"),
    "cube number": _shrm_header(cube=3),
    "version": _shrm_header(version=2),
    "version bool": _shrm_header(version=True),
    "format": _shrm_header(format="other"),
}


@pytest.mark.parametrize("case", list(_BAD_HEADERS))
def test_shrm_header_is_validated_on_load(tmp_path, case):
    path = _zip(tmp_path / "h.shrm.npz", _shrm_members(_BAD_HEADERS[case]))
    _raises_naming(path, lambda: shrmkit.load_shrm(path))


@pytest.mark.parametrize("text", ['{"format": "shrmkit-shrm", "tolerance": NaN}', "{", "[" * 100000, "",
                                  '{"F": ' + "7" * 5000 + "}"])
def test_shrm_header_must_be_strict_json(tmp_path, text):
    path = _zip(tmp_path / "j.shrm.npz", _shrm_members(header_text=text))
    _raises_naming(path, lambda: shrmkit.load_shrm(path))


@pytest.mark.parametrize(
    ("coeffs", "cube", "header", "message"),
    [
        (np.zeros((4, 0, 0, 3), np.float32), None, None, "W = 2H"),  # zero-size map
        (np.zeros((4, 4, 4, 3), np.float32), None, None, "W = 2H"),
        (np.zeros((4, 4, 8, 3), np.float64), None, None, "float32"),
        (np.zeros((4, 4, 8, 2), np.float32), None, None, "does not match P"),
        (np.zeros((4, 4, 8), np.float32), None, None, "float32"),
        (np.full((4, 4, 8, 3), np.nan, np.float32), None, None, "non-finite"),
        (None, np.zeros((4, 5, 3, 3, 3), np.float32), _shrm_header(cube="faces"), "cube array"),
        (None, np.zeros((4, 6, 3, 2, 3), np.float32), _shrm_header(cube="faces"), "cube array"),
        (None, np.full((4, 6, 2, 2, 3), np.inf, np.float32), _shrm_header(cube="faces"), "non-finite"),
        (None, np.zeros((4, 6, 2, 2, 3), np.float32), None, "cube array but its header"),
    ],
)
def test_shrm_arrays_are_validated_on_load(tmp_path, coeffs, cube, header, message):
    path = _zip(tmp_path / "a.shrm.npz", _shrm_members(header, coeffs, cube))
    _raises_naming(path, lambda: shrmkit.load_shrm(path), message)


def test_shrm_missing_members(tmp_path):
    members = _shrm_members()
    del members["header"]
    path = _zip(tmp_path / "m.shrm.npz", members)
    _raises_naming(path, lambda: shrmkit.load_shrm(path), "missing key")


# ------------------------------------------------------------------ 3. Cornell


_WAVELENGTHS = " ".join(str(w) for w in range(400, 710, 10))


def _cornell(count: str = "31", row_value: str = "0.2", phi_s: str = "3.0") -> str:
    row = " ".join(["0.5", "0", "0.4", phi_s] + [row_value] + ["0.2"] * 30)
    return f"# test\n{count}\n{_WAVELENGTHS}\n{row}\n"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (_cornell(count="inf"), "non-finite"),
        (_cornell(count="nan"), "non-finite"),
        (_cornell(count="1e9"), "not a positive integer"),
        (_cornell(count="0"), "not a positive integer"),
        (_cornell(count="1" * 5000), "not a number"),
        (_cornell(row_value="1e308"), "above"),
        (_cornell(row_value=f"{MAX_MEASURED_RHO * 1.01:g}"), "above"),
        (_cornell(row_value="1e999"), "non-finite"),
        (_cornell(row_value="-inf"), "non-finite"),
        (_cornell(row_value="1_0"), "not a number"),
        (_cornell(row_value="0x10"), "not a number"),
        (_cornell(phi_s="1e300"), "outside"),
        (_cornell() + "0.5 0 0.4\n", "3 numbers"),  # a header only / a truncated row
        ("31\n400 410\n", "no wavelength header"),
        ("", "no wavelength header"),
    ],
)
def test_cornell_numbers_are_checked(tmp_path, text, message):
    path = tmp_path / "c.brdf"
    path.write_text(text)
    _raises_naming(path, lambda: read_cornell(path), message)


def test_cornell_plausible_values_load(tmp_path):
    path = tmp_path / "ok.brdf"
    path.write_text(_cornell(row_value="9e5"))
    brdf = read_cornell(path)
    assert np.all(np.isfinite(brdf.rgb)) and brdf.spectral.max() == 9e5


# ------------------------------------------------------------------ 4. specs and fit JSON


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("phong:s=" + "1" * 5000, "at most 64 characters"),
        ("phong:s=0." + "1" * 5000, "at most 64 characters"),
        ("lafortune:n" + "1" * 5000 + "=1", "numbered"),
        ("lafortune:n=1,n02=1", "numbered"),
        ("lafortune:" + ",".join(f"n{k}=1" for k in range(2, MAX_LOBES + 2)) + ",n=1", "numbered"),
        ("phong:s=1e999", "not finite"),
        ("phong:s=1_0", "not a number"),
        ("phong:s=1,ks=1e308", "outside"),
        (f"phong:s={MAX_EXPONENT * 10:g}", "outside"),
        ("microfacet:sigma=1e-4", "outside"),
        ("microfacet:sigma=0.2,ks=1e7", "outside"),
        ("cook-torrance:alpha=1e-5", "outside"),
        ("cook-torrance:alpha=0.2,ks=1e308", "outside"),
        ("lafortune:n=1e7,cz=2", "peak"),
        ("lafortune:n=1,ks=1e300", "peak"),
        ("lafortune:n=0,cxy=1e300", "outside"),
        ("lafortune:n=3,cz=1e10,ks=1e300", "outside"),
    ],
)
def test_spec_numbers_and_parameter_bounds(spec, message):
    with pytest.raises(BadInputError, match=message) as info:
        load_brdf(spec)
    assert spec in str(info.value) and len(str(info.value).split(": ", 1)[1]) < 400


def _dense_pairs() -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs: a grid with θ up to exactly π/2 (all pairs), every direction with its
    mirror and itself (the peaks), and directions a denormal away from the horizon."""
    theta = np.concatenate((np.linspace(0, np.pi / 2, 19), [np.pi / 2 - 1e-9, np.pi / 2 - 1e-15]))
    phi = np.linspace(-np.pi, np.pi, 13)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack((np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), axis=-1).reshape(-1, 3)
    tiny = np.array([[1.0, 0.0, 5e-324], [0.6, 0.8, 1e-300], [1.0, 0.0, 1e-20], [0.0, -1.0, 1e-17]])
    d = np.vstack((d, tiny / np.linalg.norm(tiny, axis=1, keepdims=True)))
    L, V = (a.reshape(-1, 3) for a in np.broadcast_arrays(d[:, None], d[None, :]))
    mirror = d * np.array([-1.0, -1.0, 1.0])
    return np.vstack((L, d, d)), np.vstack((V, mirror, d))


_EXTREME_SPECS = [
    f"phong:s={MAX_EXPONENT:g},ks={MAX_SCALE:g}",
    f"phong:s=0,ks={MAX_SCALE:g}",
    f"phong:s=1,ks={MAX_SCALE:g}",
    f"microfacet:sigma={SIGMA_RANGE[0]:g},ks={MAX_SCALE:g}",
    f"microfacet:sigma={SIGMA_RANGE[1]:g},ks={MAX_SCALE:g}",
    "lambert:albedo=1",
    f"lafortune:kd=1,cxy=-1,cz=1,n={MAX_EXPONENT:g},ks={MAX_LOBE_PEAK:g}",
    f"lafortune:cxy={MAX_LAFORTUNE_COEFF:g},cz=-{MAX_LAFORTUNE_COEFF:g},n=0,ks={MAX_LOBE_PEAK:g}",
    f"lafortune:cxy=-{MAX_LAFORTUNE_COEFF:g},cz={MAX_LAFORTUNE_COEFF:g},n=1,ks={MAX_LOBE_PEAK / 1e6:g}",
    f"lafortune:cxy=0.5,cz=0.5,n={MAX_EXPONENT:g},ks=1e300",  # tiny base, huge ks: peak 0
    "lafortune:kd=1," + ",".join(
        f"cxy{s}=-1,cz{s}=1,n{s}=2,ks{s}={MAX_LOBE_PEAK:g}" for s in ["", *map(str, range(2, MAX_LOBES + 1))]
    ),
] + [
    f"cook-torrance:kd=1,ks={MAX_SCALE:g},alpha={alpha:g},f0={f0},dist={dist}"
    for alpha in ALPHA_RANGE for f0 in (0, 1) for dist in ("beckmann", "ggx")
]


@pytest.mark.parametrize("spec", _EXTREME_SPECS)
def test_models_stay_finite_at_their_parameter_bounds(spec):
    brdf = brdf_from_spec(spec)
    L, V = _dense_pairs()
    rho, rho_hat = brdf.eval(L, V), brdf.rho_hat(L, V)
    assert np.all(np.isfinite(rho)) and np.all(np.isfinite(rho_hat))
    assert rho.min() >= 0 and rho_hat.min() >= 0
    assert rho.max() <= MAX_TABLE_RHO  # so every tabulation of a valid spec can be written
    assert brdf_from_spec(brdf.to_spec()).to_spec() == brdf.to_spec()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (json.dumps({"model_spec": "microfacet:sigma=1e-4"}).encode(), "model_spec 'microfacet:sigma=1e-4'"),
        (json.dumps({"model_spec": "phong:s=" + "9" * 5000}).encode(), "at most 64 characters"),
        (json.dumps({"model_spec": "nonsense"}).encode(), "model_spec"),
        (json.dumps({"model_spec": ["phong:s=1"]}).encode(), "string key 'model_spec'"),
        (json.dumps([{"model_spec": "phong:s=1"}]).encode(), "JSON list"),
        (json.dumps({"model_spec": "phong:s=1"}).encode("utf-16"), "UTF-8"),
        (b'{"model_spec": "phong:s=1", "x": NaN}', "NaN"),
        (b'{"model_spec": "phong:s=1", "x": -Infinity}', "Infinity"),
        (b'{"model_spec": "phong:s=1", "x": 1e400}', "overflows"),
        (b'{"model_spec": "phong:s=1", "x": ' + b"1" * 5000 + b"}", "digits"),
        (b"[" * 100000 + b"]" * 100000, "nested too deeply"),
        (b"", "not a valid"),
        (b'{"model_spec": "phong:s=1"', "not a valid"),
    ],
)
def test_fit_json_problems_name_the_file(tmp_path, content, message):
    path = tmp_path / "fit.json"
    path.write_bytes(content)
    _raises_naming(path, lambda: load_brdf(path), message)


# ------------------------------------------------------------------ 5. MERL


def _merl_bytes(dims: tuple[int, int, int] = (90, 90, 180), n: int | None = None) -> bytearray:
    n = dims[0] * dims[1] * dims[2] if n is None else n
    data = bytearray(12 + 24 * n)
    struct.pack_into("<3i", data, 0, *dims)
    return data


@pytest.mark.parametrize("dims", [(2**31 - 1,) * 3, (90, 90, 2**31 - 1), (1, 1, 1), (180, 90, 90), (0, 90, 180)])
def test_merl_declared_dims_are_checked_before_reading(tmp_path, dims):
    path = tmp_path / "dims.binary"
    path.write_bytes(bytes(_merl_bytes(dims, n=1)))
    _raises_naming(path, lambda: read_merl(path))
    _small_peak(lambda: read_merl(path), 2**20)


def test_merl_values(tmp_path):
    data = _merl_bytes()
    struct.pack_into("<d", data, 12, -1.0)  # negative: missing
    struct.pack_into("<d", data, 20, 1e300)  # rho 6.7e296: refused
    path = tmp_path / "v.binary"
    path.write_bytes(bytes(data))
    _raises_naming(path, lambda: read_merl(path), "above")
    struct.pack_into("<d", data, 20, 1500.0)  # rho 1 in red
    path.write_bytes(bytes(data))
    brdf = read_merl(path)
    assert brdf.n_missing == 1 and np.isnan(brdf.values[0, 0, 0, 0]) and brdf.values[0, 0, 0, 1] == 1.0
    struct.pack_into("<d", data, 20, math.nan)
    path.write_bytes(bytes(data))
    _raises_naming(path, lambda: read_merl(path), "non-finite")


# ------------------------------------------------------------- 6./7. special files, odd files


_SUFFIXES = (".binary", ".npz", ".brdf", ".json", ".shrm.npz")


def _loader(suffix: str) -> Callable[[Path], object]:
    return shrmkit.load_shrm if suffix == ".shrm.npz" else load_brdf


@pytest.mark.parametrize("suffix", _SUFFIXES)
@pytest.mark.parametrize("kind", ["fifo", "devzero", "folder", "empty"])
def test_special_and_empty_files_are_refused_quickly(tmp_path, suffix, kind, finishes):
    path = tmp_path / f"x{suffix}"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "devzero":
        if not Path("/dev/zero").exists():
            pytest.skip("no /dev/zero")
        os.symlink("/dev/zero", path)
    elif kind == "folder":
        path.mkdir()
    else:
        path.write_bytes(b"")
    finished, err = finishes(lambda: _loader(suffix)(path))
    assert finished, f"still reading {path.name} after 10 s"
    assert isinstance(err, BadInputError), repr(err)
    assert str(path) in str(err) and "\n" not in str(err)


@pytest.mark.parametrize(
    ("suffix", "content"),
    [
        (".binary", struct.pack("<3i", 90, 90, 180)),  # a header only
        (".binary", b"\x01\x02"),
        (".brdf", b"# only a comment\n31\n"),
        (".brdf", "31\n".encode("utf-16")),
        (".npz", b"PK\x05\x06" + b"\0" * 18),  # an empty zip archive
        (".shrm.npz", b"PK\x05\x06" + b"\0" * 18),
        (".json", b"null"),
        (".json", b"\xef\xbb\xbf{}"),  # a UTF-8 byte-order mark
    ],
)
def test_odd_small_files_are_refused(tmp_path, suffix, content):
    path = tmp_path / f"odd{suffix}"
    path.write_bytes(content)
    _raises_naming(path, lambda: _loader(suffix)(path))


def test_odd_spec_strings_stay_on_one_line():
    for text in ("", "phong:s=-1\n", "x\x00.json", "lafortune:n=1,\nks=2", "a" * 5000, "b" * 300 + ".json",
                 "phong:s=1,ks=\x00"):
        with pytest.raises(BadInputError) as info:
            load_brdf(text)
        assert "\n" not in str(info.value)
    assert load_brdf("\tphong:s=8\n").to_spec() == "phong:s=8"  # surrounding white space is not part of it


# --------------------------------------------------------------- a seeded mutation fuzz


def _finite_or_refused(load: Callable[[], object], path: Path) -> str:
    """'clean' (BadInputError naming the file, one line) or 'valid' (finite values)."""
    try:
        result = load()
    except BadInputError as err:
        assert str(path) in str(err) and "\n" not in str(err), str(err)
        return "clean"
    L = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [1.0, 0.0, 1e-6]])
    V = np.array([[0.0, 0.0, 1.0], [-0.6, 0.0, 0.8], [-1.0, 0.0, 1e-6]])
    if isinstance(result, SHRM):
        values = result.radiance(L, V)
    elif isinstance(result, ScatteredBRDF):
        values = np.concatenate((result.rgb.ravel(), result.L.ravel(), result.V.ravel()))
    else:
        values = result.eval(L / np.linalg.norm(L, axis=1, keepdims=True), V / np.linalg.norm(V, axis=1, keepdims=True))
    assert np.all(np.isfinite(values)), values
    return "valid"


def _mutate_bytes(rng: np.random.Generator, seed: bytes) -> bytes:
    n = len(seed)
    kind = rng.integers(0, 4)
    if kind == 0:  # truncate, half the time inside the first 2 KB
        return seed[: int(rng.integers(0, min(n, 2048) if rng.random() < 0.5 else n))]
    data = bytearray(seed)
    if kind == 1:  # flip bytes, half of them in the first 1 KB
        for _ in range(int(rng.integers(1, 9))):
            w = int(rng.integers(0, min(n, 1024))) if rng.random() < 0.5 else int(rng.integers(0, n))
            data[w] = int(rng.integers(0, 256))
        return bytes(data)
    if kind == 2:  # an int32 field set to an extreme
        w = int(rng.integers(0, max(1, min(n - 4, 512)) // 4)) * 4
        value = int(rng.choice([0, -1, 2**31 - 1, -(2**31), 10**9, 65536]))
        data[w : w + 4] = (value & 0xFFFFFFFF).to_bytes(4, "little")
        return bytes(data)
    return seed + rng.integers(0, 256, int(rng.integers(1, 512)), dtype=np.uint8).tobytes()


def _mutate_npz(rng: np.random.Generator, seed: bytes) -> bytes:
    with zipfile.ZipFile(io.BytesIO(seed)) as archive:
        members = {name[:-4]: archive.read(name) for name in archive.namelist()}
    name = sorted(members)[int(rng.integers(0, len(members)))]
    array = np.load(io.BytesIO(members[name]), allow_pickle=False)
    kind = rng.integers(0, 4)
    if kind == 0:
        shape = tuple(int(v) for v in rng.choice([0, 1, 2, 3, 4, 8, 10**9, 2**40, -1], size=int(rng.integers(0, 5))))
        members[name] = _npy_raw(array.dtype.str, shape, array.tobytes())
    elif kind == 1:
        descr = str(rng.choice(["|O", "<c16", "|S3", "<i8", "<f2", ">f8", "|b1", "<U4", "<f4", "<f8"]))
        members[name] = _npy_raw(descr, array.shape, array.tobytes())
    elif kind == 2:
        cut = int(rng.integers(0, array.nbytes + 1))
        members[name] = _npy_raw(array.dtype.str, array.shape, array.tobytes()[:cut])
    else:
        values = [None, -2, 1.5, "x", 1e308, [], {}, 0, -1, 10**9]
        if array.dtype.kind == "U":
            doc = json.loads(str(array))
            key = str(rng.choice(sorted(doc)))
            doc[key] = values[int(rng.integers(0, len(values)))]
            members[name] = _npy(np.array(json.dumps(doc)))
        else:
            flat = array.astype(np.float64).ravel()
            if flat.size:
                flat[int(rng.integers(0, flat.size))] = rng.choice([np.nan, np.inf, -1.0, 1e300, 0.0])
            with np.errstate(over="ignore", invalid="ignore"):  # 1e300 as float32 is inf: fine
                members[name] = _npy(flat.reshape(array.shape).astype(array.dtype))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED if rng.random() < 0.5 else zipfile.ZIP_STORED) as archive:
        for key, payload in members.items():
            archive.writestr(key + ".npy", payload)
    return out.getvalue()


def _mutate_text(rng: np.random.Generator, seed: bytes) -> bytes:
    import re

    numbers = [m.span() for m in re.finditer(rb"-?\d+(\.\d+)?(e-?\d+)?", seed[:4096])]
    if not numbers or rng.random() < 0.3:
        return _mutate_bytes(rng, seed)
    a, b = numbers[int(rng.integers(0, len(numbers)))]
    value = [b"0", b"-1", b"1e308", b"nan", b"inf", b"99999999999", b"1" * 5000, b"1e-320", b"", b"0.5"][
        int(rng.integers(0, 10))]
    return seed[:a] + value + seed[b:]


def test_seeded_mutation_fuzz(tmp_path):
    """Mutations of valid files written by our writers (truncation, byte flips, int32 fields,
    rewritten .npy headers, header fields, numbers in text): every case is clean or valid."""
    rng = np.random.default_rng(20240611)
    seeds = tmp_path / "seeds"
    seeds.mkdir()
    table = write_table(seeds / "t.npz", brdf_from_spec("microfacet:sigma=0.3,ks=0.8"),
                        theta_i=np.radians([0.0, 30, 60, 89]), theta_o=np.radians([0.0, 45, 89]),
                        phi_d=np.radians([0.0, 90, 180]))
    shrm = SHRM(F=3, P=1, coeffs=rng.normal(size=(4, 4, 8, 3)).astype(np.float32), tolerance=0.1,
                eps={"brdf": 0.01}, meta={"brdf": "x"}).save(seeds / "s.shrm.npz")
    rows = [f"{ti:.4f} 0 {ts:.4f} {ps:.4f} " + " ".join(f"{v:.5f}" for v in rng.uniform(0.01, 0.5, 31))
            for ti, ts, ps in rng.uniform(0, 1.4, (6, 3))]
    cornell = seeds / "c.brdf"
    cornell.write_text("# seed\n31\n" + _WAVELENGTHS + "\n" + "\n".join(rows) + "\n")
    fit = seeds / "f.json"
    fit.write_text(json.dumps({"model_spec": "lafortune:cxy=-1,cz=1,n=20,ks=0.5,kd=0.2", "fit": {"e": 0.1}}))
    merl = _merl_bytes()
    struct.pack_into("<4d", merl, 12, 1.0, -1.0, 3.0, 4.0)
    cases = [
        (table, ".npz", load_brdf, (_mutate_npz, _mutate_bytes), 200),
        (shrm, ".shrm.npz", shrmkit.load_shrm, (_mutate_npz, _mutate_bytes), 200),
        (cornell, ".brdf", load_brdf, (_mutate_text, _mutate_bytes), 150),
        (fit, ".json", load_brdf, (_mutate_text, _mutate_bytes), 100),
        (None, ".binary", load_brdf, (_mutate_bytes,), 8),
    ]
    outcomes: dict[str, list[str]] = {}
    for seed_path, suffix, load, mutations, count in cases:
        seed = bytes(merl) if seed_path is None else seed_path.read_bytes()
        for k in range(count):
            content = mutations[k % len(mutations)](rng, seed)
            path = tmp_path / f"case{k}{suffix}"
            path.write_bytes(content)
            outcomes.setdefault(suffix, []).append(_finite_or_refused(lambda p=path, f=load: f(p), path))
            path.unlink()
    for suffix, seen in outcomes.items():
        assert "clean" in seen, suffix  # the mutations do reach the checks
