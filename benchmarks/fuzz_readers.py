"""Seeded fuzz harness over every reader: mutated files in, outcome table out.

Every reader of a user file (MERL ``.binary``, table ``.npz``, Cornell ``.brdf``, fit
``.json``, BRDF spec strings, ``.shrm.npz``, OpenEXR, Radiance RGBE, PFM, angular probes,
cube-map folders, PLY/OBJ meshes) is fed files mutated from valid seeds — written here
by our own writers, plus the real files in ``../shared/data`` when present — with
truncations, byte flips, int32 header fields set to extremes, numbers in text headers
replaced by 0/−1/huge/NaN/5000-digit values, ``.npy`` member headers rewritten inside
``.npz`` archives, NaN/Inf bit patterns in the data, appended garbage and special files
(FIFO, a link to ``/dev/zero``, an empty file, a folder); and files built to exhaust memory
or to analyse nothing (issues 28 and 30): OpenEXR windows and ``envmap`` attributes
(``exr_window``), table members that inflate up to a thousand-fold or whose zip directory
lies (``npz_inflate``), run-length ``.hdr`` files declaring up to the pixel limit
(``hdr_limit``), and degenerate tables (``degenerate``: one sample, all missing, one angle,
constant values, subnormal node spacing), which are also analysed (``choose_orders``).

Workers run with ``SHRM_MAX_MEMORY_BYTES`` at half the per-case budget: a reader's memory
plan (data_specs/limits.md) must refuse what would grow past the budget, so an estimate
short by more than 2× shows as a ``memory`` failure.

Each case runs in a worker process under an address-space limit (``--memory-gib``) and
a timeout (``--timeout``), and is classified:

``clean``
    :class:`~shrmkit.brdf_io.errors.BadInputError` whose message names the file;
``valid``
    loaded, and every value the loader returned is finite;
``crash``
    any other exception, or the worker died;
``hang``
    no answer within the timeout (the worker is killed and replaced);
``memory``
    MemoryError/bad_alloc, or the peak resident memory of the case grew by more than
    ``--memory-budget-mib``;
``garbage``
    loaded but with non-finite values, or a BadInputError that does not name the file.

Only ``clean`` and ``valid`` are acceptable. Cases are reproducible from
``(--seed, reader, case index)``; ``--show READER:INDEX`` reruns one case in this
process and prints its traceback.

Usage::

    python benchmarks/fuzz_readers.py                       # >= 10,000 cases, table
    python benchmarks/fuzz_readers.py --cases 300 --readers exr,hdr
    python benchmarks/fuzz_readers.py --show exr:17         # one case, traceback

``tests/test_fuzz_readers.py`` runs a fast seeded subset of this harness in CI.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
import zipfile
import zlib
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
OUTCOMES = ("clean", "valid", "crash", "hang", "memory", "garbage")
FAILURES = ("crash", "hang", "memory", "garbage")

EXTREME_INTS = (0, -1, 1, 2**31 - 1, -(2**31), 2**30, 65536, 1_000_000_000, 3)
EXTREME_TEXT = (
    b"0", b"-1", b"-0", b"1e308", b"-1e308", b"nan", b"inf", b"-inf", b"99999999999",
    b"4294967295", b"2147483648", b"1" * 5000, b"0.5", b"1e-320", b"",
)
NONFINITE_PATTERNS = (
    np.float32(np.nan).tobytes(), np.float32(np.inf).tobytes(), np.float32(-np.inf).tobytes(),
    np.float64(np.nan).tobytes(), np.float64(np.inf).tobytes(), np.float64(-1e300).tobytes(),
    np.float16(np.inf).tobytes(), np.float16(np.nan).tobytes(),
    # finite magnitudes no measurement has (a flipped exponent): refused where read, never summed
    np.float32(2.5e38).tobytes(), np.float32(-2.5e38).tobytes(), np.float64(1e39).tobytes(),
)
SPECIAL = ("fifo", "devzero", "empty", "folder")


# --------------------------------------------------------------------------------------
# seeds: valid files written by our writers (and real files when ../shared is there)
# --------------------------------------------------------------------------------------
@dataclass
class Reader:
    """One reader under test: its seeds and the mutations that suit its format."""

    name: str
    suffix: str
    seeds: list[Path] = field(default_factory=list)
    mutations: tuple[str, ...] = ("truncate", "flip", "int32", "nonfinite", "append", "zero", "special")
    text_seeds: list[str] = field(default_factory=list)  # spec strings (no file)


def _write_seeds(folder: Path) -> dict[str, Reader]:
    """Write one or more valid seed files per reader into ``folder``."""
    from shrmkit.analysis.fit.fit_file import write_fit_json  # noqa: F401  (import check)
    from shrmkit.analysis.shrm import prefilter
    from shrmkit.brdf_io.hdr_codecs import write_exr, write_hdr, write_pfm
    from shrmkit.brdf_io.merl import write_merl
    from shrmkit.brdf_io.specs import load_brdf
    from shrmkit.brdf_io.table import write_table

    rng = np.random.default_rng(7)
    readers: dict[str, Reader] = {}

    def add(name: str, suffix: str, paths: list[Path], **kw) -> None:
        readers[name] = Reader(name, suffix, [p for p in paths if p.exists()], **kw)

    brdf = load_brdf("microfacet:sigma=0.3,ks=0.8")
    merl = write_merl(folder / "seed.binary", load_brdf("lambert:albedo=0.5/0.4/0.3"))
    add("merl", ".binary", [merl], mutations=("truncate", "flip", "int32", "nonfinite", "append", "special"))

    table = folder / "seed_table.npz"
    write_table(table, brdf, theta_i=np.radians([0.0, 30, 60, 89]), theta_o=np.radians([0.0, 45, 89]),
                phi_d=np.radians([0.0, 90, 180]))
    add("table", ".npz", [table], mutations=("npy_header", "npy_data", "truncate", "flip", "append", "special",
                                             "npz_inflate", "degenerate"))

    cornell = [folder / "seed.brdf"]
    lines = ["# seed written by the fuzz harness", "31", " ".join(str(w) for w in range(400, 710, 10))]
    for _ in range(12):
        ti, ts = rng.uniform(0, 1.4, 2)
        ps = rng.uniform(0, 2 * np.pi)
        lines.append(f"{ti:.4f} 0 {ts:.4f} {ps:.4f} " + " ".join(f"{v:.5f}" for v in rng.uniform(0.01, 0.5, 31)))
    cornell[0].write_text("\n".join(lines) + "\n")
    cornell += sorted((SHARED / "brdf" / "cornell").glob("*.brdf"))[:1]
    add("cornell", ".brdf", cornell, mutations=("truncate", "flip", "text_number", "append", "zero", "special"))

    fit = folder / "seed_fit.json"
    fit.write_text(json.dumps({"model_spec": "lafortune:cxy=-1,cz=1,n=20,ks=0.5,kd=0.2", "fit": {"error": 0.1}}))
    add("fit_json", ".json", [fit], mutations=("truncate", "flip", "text_number", "json_value", "append", "special"))

    readers["spec"] = Reader(
        "spec", "", mutations=("spec",),
        text_seeds=["microfacet:sigma=0.2,ks=0.5", "phong:s=20,ks=0.8", "lambert:albedo=0.2/0.5/0.8",
                    "lafortune:cxy=-1,cz=1,n=20,ks=0.5", "cook-torrance:alpha=0.3,dist=ggx,kd=0.2"],
    )

    shrm = folder / "seed.shrm.npz"
    prefilter("builtin:constant,height=8", "phong:s=4", eps=0.1, size=8, F=3, P=1).save(shrm)
    add("shrm", ".shrm.npz", [shrm], mutations=("npy_header", "npy_data", "shrm_header", "truncate", "flip",
                                                "special"))

    image = rng.uniform(0.0, 4.0, (8, 16, 3)).astype(np.float32)
    image[2, 3] = 1000.0
    write_exr(folder / "seed.exr", image)
    write_exr(folder / "seed_half.exr", image, half=True)
    exr = [folder / "seed.exr", folder / "seed_half.exr"]
    exr += [SHARED / "env" / "openexr_images" / n for n in ("OrientationLatLong.exr", "OrientationCube.exr")]
    add("exr", ".exr", exr, mutations=("truncate", "flip", "int32", "nonfinite", "append", "zero", "special",
                                        "exr_window"))

    wide = rng.uniform(0.0, 4.0, (8, 16, 3)).astype(np.float32)
    write_hdr(folder / "seed_rle.hdr", wide)
    write_hdr(folder / "seed_flat.hdr", wide, rle=False)
    add("hdr", ".hdr", [folder / "seed_rle.hdr", folder / "seed_flat.hdr", SHARED / "env" / "ict_small" / "grace.hdr"],
        mutations=("truncate", "flip", "text_number", "int32", "append", "zero", "special", "hdr_limit"))

    write_pfm(folder / "seed.pfm", image)
    add("pfm", ".pfm", [folder / "seed.pfm"],
        mutations=("truncate", "flip", "text_number", "nonfinite", "append", "special"))

    write_pfm(folder / "seed_probe.pfm", rng.uniform(0.0, 2.0, (16, 16, 3)).astype(np.float32))
    add("probe", ".pfm", [folder / "seed_probe.pfm"],
        mutations=("truncate", "flip", "text_number", "nonfinite", "append", "special"))

    cube = folder / "seed_cube"
    cube.mkdir()
    for face in ("px", "nx", "py", "ny", "pz", "nz"):
        write_pfm(cube / f"{face}.pfm", rng.uniform(0.0, 2.0, (4, 4, 3)).astype(np.float32))
    add("cube", ".pfm", [cube], mutations=("truncate", "flip", "text_number", "nonfinite", "special"))

    rgl = sorted((SHARED / "brdf" / "rgl").glob("*.bsdf"))[:2]
    add("rgl", ".bsdf", rgl, mutations=("truncate", "flip", "int32", "nonfinite", "append", "zero", "special"))

    curet_src = SHARED / "brdf" / "curet"
    if (curet_src / "abrdf.dat").exists():
        curet = folder / "seed_curet"
        curet.mkdir()
        for name in ("abrdf.dat", "table.txt"):
            shutil.copyfile(curet_src / name, curet / name)
        add("curet", ".dat", [curet], mutations=("truncate", "flip", "text_number", "append", "zero", "special"))

    ptfe = SHARED / "brdf" / "nist_ptfe" / "PTFE.data.random.csv"
    if ptfe.exists():
        lines = ptfe.read_text().splitlines()
        gonio = folder / "seed_gonio.csv"
        gonio.write_text("\n".join(lines[:1] + [x for x in lines[1:] if x.startswith("0.532")][:400]) + "\n")
        add("gonio", ".csv", [gonio], mutations=("truncate", "flip", "text_number", "append", "zero", "special"))

    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=1)
    sphere.export(folder / "seed_ascii.ply", encoding="ascii")
    sphere.export(folder / "seed_binary.ply")
    add("ply", ".ply", [folder / "seed_ascii.ply", folder / "seed_binary.ply"],
        mutations=("truncate", "flip", "text_number", "nonfinite", "append", "special"))
    sphere.export(folder / "seed.obj")
    add("obj", ".obj", [folder / "seed.obj"], mutations=("truncate", "flip", "text_number", "append", "special"))
    return readers


# --------------------------------------------------------------------------------------
# mutations
# --------------------------------------------------------------------------------------
def _header_offset(rng: np.random.Generator, n: int) -> int:
    """An offset, half the time inside the first 1 KB (where the headers are)."""
    if n <= 1:
        return 0
    return int(rng.integers(0, min(n, 1024))) if rng.random() < 0.5 else int(rng.integers(0, n))


def _npz_members(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        return {name: archive.read(name) for name in archive.namelist()}


def _npz_bytes(members: dict[str, bytes]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_STORED) as archive:
        for name, payload in members.items():
            archive.writestr(name, payload)
    return out.getvalue()


def _mutate_npy_header(rng: np.random.Generator, payload: bytes) -> bytes:
    """Rewrite the shape or dtype in a ``.npy`` member's text header, keeping its length."""
    head_len = int.from_bytes(payload[8:10], "little") if payload[6:7] == b"\x01" else int.from_bytes(
        payload[8:12], "little")
    start = 10 if payload[6:7] == b"\x01" else 12
    header = payload[start:start + head_len].decode("latin1")
    choice = rng.integers(0, 4)
    if choice == 0:
        shape = "(" + ", ".join(str(int(v)) for v in rng.choice(
            [0, 1, 2, 3, 10**9, 2**40, 7, 65536], size=int(rng.integers(0, 5)))) + ",)"
        header = header[:header.index("'shape':")] + f"'shape': {shape}, }}"
    elif choice == 1:
        header = header.replace(header[header.index("'descr':"):header.index(",", header.index("'descr':"))],
                                "'descr': " + str(rng.choice(["'|O'", "'<c16'", "'|S3'", "'<i8'", "'<f2'", "'>f8'",
                                                               "'|b1'", "'<U4'"])))
    elif choice == 2:
        header = header.replace("'fortran_order': False", "'fortran_order': True")
    else:
        header = header[: int(rng.integers(0, len(header)))]
    body = header.encode("latin1")
    body = body + b" " * ((-(start + len(body) + 1)) % 64) + b"\n"
    size = len(body).to_bytes(2 if start == 10 else 4, "little")
    return payload[:8] + size + body + payload[start + head_len:]


#: Values an OpenEXR window corner is set to: a huge display window beside a small data window, a
#: 1 × 20,000 strip, inverted and extreme boxes (issue 30's small files that asked for 2–149 GiB).
EXR_WINDOW_VALUES = (0, -1, 1, 7, 19_999, 20_000, 65_535, 1_000_000, 2**30, 2**31 - 1, -(2**31))


def _mutate_exr_window(rng: np.random.Generator, seed: bytes) -> tuple[bytes, str]:
    """Rewrite an OpenEXR header's ``displayWindow`` or ``dataWindow`` (box2i: xMin yMin xMax yMax), or
    flip the ``envmap`` attribute between lat-long and cube (its aspect rule then no longer holds)."""
    data = bytearray(seed)
    targets = [name for name in (b"displayWindow", b"dataWindow", b"envmap") if name + b"\x00" in data[:4096]]
    if not targets:
        return bytes(data), "exr_window: no window attribute"
    name = targets[int(rng.integers(0, len(targets)))]
    at = data.index(name + b"\x00")
    type_end = data.index(b"\x00", at + len(name) + 1)
    value = type_end + 1 + 4  # after the type name and the int32 size
    if name == b"envmap":
        data[value] = 1 - data[value] if data[value] in (0, 1) else 0
        return bytes(data), f"exr_window: envmap flipped to {data[value]}"
    corner = int(rng.integers(0, 4))
    number = int(rng.choice(EXR_WINDOW_VALUES))
    data[value + 4 * corner : value + 4 * corner + 4] = (number & 0xFFFFFFFF).to_bytes(4, "little")
    return bytes(data), f"exr_window: {name.decode()}[{corner}] = {number}"


#: Files a mutation builds once per run (a 17 MB run-length picture, an archive inflating to 400 MB):
#: ``_prepare`` runs in the driver, so one build serves every case that draws it.
_BUILT: dict[tuple, bytes] = {}


def _npy_header(shape: tuple[int, ...], descr: str = "<f8") -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": descr, "fortran_order": False, "shape": shape})
    return buf.getvalue()


def _table_archive(seed: bytes, values_head: bytes, data_bytes: int, axes: tuple[int, int, int],
                   level: int = 6) -> bytes:
    """The seed table's metadata with axes of ``axes`` nodes and a deflated ``values`` member: the
    .npy header ``values_head`` then ``data_bytes`` bytes of 0.25 (float64), streamed (never held whole)."""
    members = _npz_members(seed)
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=level) as archive:
        for key, n in zip(("theta_i", "theta_o", "phi_d"), axes, strict=True):
            top = np.pi if key == "phi_d" else np.pi / 2
            archive.writestr(f"{key}.npy", _npy_bytes(np.linspace(0.0, top, n)), compress_type=zipfile.ZIP_STORED)
        archive.writestr("metadata.npy", members["metadata.npy"], compress_type=zipfile.ZIP_STORED)
        with archive.open("values.npy", "w", force_zip64=data_bytes > 2**31) as member:
            member.write(values_head)
            chunk = np.full(1 << 21, 0.25).tobytes()  # a repeated 8-byte value: deflate's ~1000:1
            left = data_bytes
            while left > 0:
                member.write(chunk[: min(left, len(chunk))])
                left -= len(chunk)
    return out.getvalue()


def _npy_bytes(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, array)
    return buf.getvalue()


def _patch_member_sizes(data: bytes, name: bytes, compressed: int | None, declared: int) -> bytes:
    """Rewrite member ``name``'s sizes in its local header and central directory entry (zip
    APPNOTE 4.3.7, 4.3.12; 32-bit fields)."""
    out = bytearray(data)
    local = out.index(name) - 30
    central = out.rindex(name) - 46
    for at in (local + 18, central + 20):
        comp = compressed if compressed is not None else int.from_bytes(out[at:at + 4], "little")
        out[at:at + 8] = comp.to_bytes(4, "little") + (declared & 0xFFFFFFFF).to_bytes(4, "little")
    return bytes(out)


#: ``npz_inflate`` variants: (θ_i nodes with 64 θ_o × 64 φ_d, RGB float64 of 0.25: 49K, 786K, 6.3M and 50M
#: values: 0.4, 6, 50 and 400 MB inflated from 0.4-400 KB), a lying directory, and 2²⁸ values declared
#: over 2.2 MB of stored deflate blocks (issue 30's 2.35 MB table that needed 8 GB).
NPZ_INFLATE_TI = (4, 64, 512, 4096)


def _mutate_npz_inflate(rng: np.random.Generator, seed: bytes, light: bool = False) -> tuple[bytes, str]:
    """``light``: the two smallest honest members only (no 50 and 400 MB builds; the CI subset)."""
    choice = int(rng.integers(0, len(NPZ_INFLATE_TI) + 2))
    if choice < len(NPZ_INFLATE_TI):
        n_ti = NPZ_INFLATE_TI[min(choice, 1) if light else choice]
        key = ("npz_inflate", n_ti, len(seed))
        if key not in _BUILT:
            shape = (n_ti, 64, 64, 3)
            _BUILT[key] = _table_archive(seed, _npy_header(shape), 8 * int(np.prod(shape)), shape[:3], level=1)
        return _BUILT[key], f"npz_inflate: {n_ti} x 64 x 64 x 3 float64 deflated"
    if choice == len(NPZ_INFLATE_TI):  # the directory lies: 10,000x the true size
        shape = (4, 64, 64, 3)
        data = _table_archive(seed, _npy_header(shape), 8 * int(np.prod(shape)), shape[:3], level=1)
        declared = 10_000 * (len(_npy_header(shape)) + 8 * int(np.prod(shape)))
        return _patch_member_sizes(data, b"values.npy", None, declared), f"npz_inflate: directory declares {declared:,}"
    shape = (1024, 1024, 256)
    key = ("npz_inflate_pad", len(seed))
    if key not in _BUILT:
        head = _npy_header(shape)
        deflate = zlib.compressobj(0, zlib.DEFLATED, -15)  # stored blocks: 2.2 MB in, 2.2 MB out
        stream = deflate.compress(head + bytes(2_200_000)) + deflate.flush(zlib.Z_SYNC_FLUSH)
        data = _table_archive(seed, b"", 0, (1024, 1024, 256))
        # splice the stream in as the values member's data (it was empty), then fix its sizes and the
        # central directory's offset
        local = data.index(b"values.npy") - 30
        start = local + 30 + len(b"values.npy") + int.from_bytes(data[local + 28:local + 30], "little")
        first_central = data.index(b"PK\x01\x02")
        old = first_central - start
        out = bytearray(data[:start] + stream + data[first_central:])
        shift = len(stream) - old
        end = out.rindex(b"PK\x05\x06")
        offset = int.from_bytes(out[end + 16:end + 20], "little")
        out[end + 16:end + 20] = (offset + shift).to_bytes(4, "little")
        _BUILT[key] = _patch_member_sizes(bytes(out), b"values.npy", len(stream), len(head) + 8 * 2**28)
    return _BUILT[key], "npz_inflate: 2^28 float64 declared over 2.2 MB of stored deflate blocks"


#: ``degenerate`` tables: (description, θ_i, θ_o, φ_d (degrees, or radians where noted), values builder)
def _degenerate_tables() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    r = np.radians
    six = r(np.linspace(0.0, 89.0, 6))
    one_measured = np.full((6, 6, 6, 3), np.nan)
    one_measured[2, 3, 1] = 0.5
    tiny = np.array([0.0, 5e-324])
    return [
        ("one sample", r([10.0]), r([20.0]), r([0.0]), np.full((1, 1, 1, 3), 0.3)),
        ("one scalar sample", r([0.0]), r([0.0]), r([0.0]), np.full((1, 1, 1), 0.3)),
        ("all missing", r([0.0, 30, 60]), r([0.0, 30, 60]), r([0.0, 90, 180]), np.full((3, 3, 3, 3), np.nan)),
        ("one theta_i", r([0.0]), six, r([0.0, 90, 180]), np.full((1, 6, 3, 3), 0.2)),
        ("one phi_d", six, six, r([0.0]), np.full((6, 6, 1, 3), 0.2)),
        ("constant", six, six, r([0.0, 90, 180]), np.full((6, 6, 3, 3), 0.2)),
        ("zeros", six, six, r([0.0, 90, 180]), np.zeros((6, 6, 3, 3))),
        ("one measured of 216", six, six, r(np.linspace(0.0, 180.0, 6)), one_measured),
        ("subnormal theta_i spacing", tiny, six, r([0.0, 90, 180]), np.full((2, 6, 3, 3), 0.2)),
        ("nodes 1e-9 apart", np.array([0.0, 1e-9]), np.array([0.0, 1e-9]), np.array([0.0, 1e-9]),
         np.full((2, 2, 2, 3), 0.2)),
        ("largest values", r([0.0, 45]), r([0.0, 45]), r([0.0, 180]), np.full((2, 2, 2, 3), 1e40)),
        ("tiny values", r([0.0, 45]), r([0.0, 45]), r([0.0, 180]), np.full((2, 2, 2, 3), 1e-300)),
        ("a spike", six, six, r(np.linspace(0.0, 180.0, 6)), np.where(np.arange(216 * 3).reshape(6, 6, 6, 3) == 0,
                                                                       1e6, 1e-6)),
    ]


def _mutate_degenerate(rng: np.random.Generator, seed: bytes) -> tuple[bytes, str]:
    tables = _degenerate_tables()
    name, ti, to, pd, values = tables[int(rng.integers(0, len(tables)))]
    members = _npz_members(seed)
    members.update({"theta_i.npy": _npy_bytes(ti), "theta_o.npy": _npy_bytes(to), "phi_d.npy": _npy_bytes(pd),
                    "values.npy": _npy_bytes(values)})
    return _npz_bytes(members), f"degenerate table: {name}"


#: ``hdr_limit`` sizes (height, width): 2:1 at the pixel limit (17 MB of run-length scanlines), square at
#: the limit (not 2:1), 16384 x 8192 (the largest real map), 13 M pixels (over the harness's plan),
#: and 512 x 1024 (decoded). Each built once per run.
HDR_LIMIT_SHAPES = ((11585, 23170), (16384, 16384), (8192, 16384), (2560, 5120), (512, 1024))


def _mutate_hdr_limit(rng: np.random.Generator, light: bool = False) -> tuple[bytes, str]:
    """``light``: one pixel value (each shape built once) and no decoded 512 x 1024 file (the CI subset)."""
    shapes = HDR_LIMIT_SHAPES[:-1] if light else HDR_LIMIT_SHAPES
    height, width = shapes[int(rng.integers(0, len(shapes)))]
    value = 128 if light else int(rng.integers(1, 256))
    key = ("hdr_limit", height, width, value)
    if key not in _BUILT:
        if len(_BUILT) > 8:  # a few files of 17 MB at most
            _BUILT.clear()
        runs, last = divmod(width, 127)
        component = bytes([255, value]) * runs + (bytes([128 + last, value]) if last else b"")
        exponent = bytes([255, 128]) * runs + (bytes([128 + last, 128]) if last else b"")
        line = bytes([2, 2, width >> 8, width & 255]) + component * 3 + exponent
        _BUILT[key] = (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {height} +X {width}\n".encode()
                       + line * height)
    data = _BUILT[key]
    if rng.random() < 0.2:
        cut = int(rng.integers(len(data) // 2, len(data)))
        return data[:cut], f"hdr_limit: {width} x {height} run-length, truncated to {cut:,} bytes"
    return data, f"hdr_limit: {width} x {height} run-length ({len(data):,} bytes)"


def mutate(reader: Reader, rng: np.random.Generator, seed: bytes, kind: str,
           light: bool = False) -> tuple[bytes | str, str]:
    """Return (mutated content or a special-file kind, description); ``light``: the cheaper variants of
    ``npz_inflate`` and ``hdr_limit`` (the CI subset)."""
    n = len(seed)
    if kind == "none":
        return seed, "unchanged seed"
    if kind == "exr_window":
        return _mutate_exr_window(rng, seed)
    if kind == "npz_inflate":
        return _mutate_npz_inflate(rng, seed, light)
    if kind == "degenerate":
        return _mutate_degenerate(rng, seed)
    if kind == "hdr_limit":
        return _mutate_hdr_limit(rng, light)
    if kind == "truncate":
        cut = int(rng.integers(0, min(n, 2048))) if rng.random() < 0.5 else int(rng.integers(0, max(n, 1)))
        return seed[:cut], f"truncate to {cut} of {n} bytes"
    if kind == "flip":
        data = bytearray(seed)
        k = int(rng.integers(1, 17))
        where = [_header_offset(rng, n) for _ in range(k)]
        for w in where:
            data[w] = int(rng.integers(0, 256))
        return bytes(data), f"flip {k} bytes at {where[:4]}..."
    if kind == "int32":
        data = bytearray(seed)
        w = int(rng.integers(0, max(1, min(n - 4, 512)) // 4)) * 4
        value = int(rng.choice(EXTREME_INTS))
        data[w:w + 4] = (value & 0xFFFFFFFF).to_bytes(4, "little")
        return bytes(data), f"int32 {value} at {w}"
    if kind == "nonfinite":
        data = bytearray(seed)
        pattern = NONFINITE_PATTERNS[int(rng.integers(0, len(NONFINITE_PATTERNS)))]
        w = int(rng.integers(0, max(1, n - len(pattern))))
        data[w:w + len(pattern)] = pattern
        return bytes(data), f"non-finite {pattern.hex()} at {w}"
    if kind == "append":
        extra = rng.integers(0, 256, int(rng.integers(1, 4096)), dtype=np.uint8).tobytes()
        return seed + extra, f"append {len(extra)} bytes"
    if kind == "zero":
        w = _header_offset(rng, n)
        k = int(rng.integers(1, 64))
        return seed[:w] + bytes(min(k, n - w)) + seed[w + k:], f"zero {k} bytes at {w}"
    if kind == "special":
        which = SPECIAL[int(rng.integers(0, len(SPECIAL)))]
        return which, f"special file: {which}"
    if kind == "text_number":
        import re

        numbers = [m.span() for m in re.finditer(rb"-?\d+(\.\d+)?(e-?\d+)?", seed[:4096])]
        if not numbers:
            return seed[: n // 2], "truncate (no numbers)"
        a, b = numbers[int(rng.integers(0, len(numbers)))]
        value = EXTREME_TEXT[int(rng.integers(0, len(EXTREME_TEXT)))]
        return seed[:a] + value + seed[b:], f"number at {a} -> {value[:20]!r}"
    if kind == "json_value":
        doc = json.loads(seed)
        choice = int(rng.integers(0, 6))
        if choice == 0:
            doc["model_spec"] = str(rng.choice(["microfacet:sigma=1e-4", "phong:s=1,ks=1e308", "nonsense",
                                                "lafortune:n=1e400", "", "phong:s=" + "9" * 5000]))
        elif choice == 1:
            doc["model_spec"] = [1, 2] if rng.random() < 0.5 else None
        elif choice == 2:
            doc = [doc]
        elif choice == 3:
            return b"[" * 100000 + b"]" * 100000, "deeply nested json"
        elif choice == 4:
            return seed.decode().encode("utf-16"), "utf-16 json"
        else:
            return b'{"model_spec": NaN}', "NaN literal"
        return json.dumps(doc).encode(), f"json value change {choice}"
    if kind in ("npy_header", "npy_data", "shrm_header"):
        members = _npz_members(seed)
        names = sorted(members)
        if kind == "shrm_header":
            header_payload = members["header.npy"]
            arr = np.load(io.BytesIO(header_payload), allow_pickle=False)
            head = json.loads(str(arr))
            key = str(rng.choice(sorted(head)))
            value = [None, -2, 1.5, "x", float("nan"), 1e308, [], {}, 0, -1, 10**9][int(rng.integers(0, 11))]
            if rng.random() < 0.15:
                del head[key]
                desc = f"shrm header: delete {key}"
            else:
                head[key] = value
                desc = f"shrm header: {key} = {value!r}"
            text = json.dumps(head) if rng.random() < 0.9 else json.dumps([head])
            buf = io.BytesIO()
            np.save(buf, np.array(text))
            members["header.npy"] = buf.getvalue()
            return _npz_bytes(members), desc
        name = names[int(rng.integers(0, len(names)))]
        payload = members[name]
        if kind == "npy_header":
            members[name] = _mutate_npy_header(rng, payload)
            return _npz_bytes(members), f"npy header of {name}"
        data = bytearray(payload)
        start = 128 if len(data) > 128 else len(data)
        if len(data) > start + 8:
            w = int(rng.integers(start, len(data) - 8))
            pattern = NONFINITE_PATTERNS[int(rng.integers(0, len(NONFINITE_PATTERNS)))]
            data[w:w + len(pattern)] = pattern
        members[name] = bytes(data)
        return _npz_bytes(members), f"npy data of {name}"
    if kind == "spec":
        raise AssertionError("spec mutations are strings: use mutate_spec")
    raise ValueError(f"unknown mutation {kind}")


def mutate_spec(rng: np.random.Generator, spec: str) -> tuple[str, str]:
    import re

    choice = int(rng.integers(0, 4))
    numbers = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", spec))
    if choice == 0 and numbers:
        m = numbers[int(rng.integers(0, len(numbers)))]
        value = EXTREME_TEXT[int(rng.integers(0, len(EXTREME_TEXT)))].decode()
        return spec[: m.start()] + value + spec[m.end():], f"number -> {value[:20]!r}"
    if choice == 1:
        cut = int(rng.integers(0, len(spec) + 1))
        return spec[:cut], f"truncate to {cut}"
    if choice == 2:
        chars = list(spec)
        for _ in range(int(rng.integers(1, 4))):
            chars.insert(int(rng.integers(0, len(chars) + 1)), str(rng.choice(list(",=:/;\x00 é\n1e.-"))))
        return "".join(chars), "insert characters"
    params = ["1e-4", "1e308", "0", "-0", "1e-300", "nan", "1e30"]
    name = spec.split(":")[0]
    key = {"microfacet": "sigma", "phong": "s", "lambert": "albedo", "lafortune": "n", "cook-torrance": "alpha"}[name]
    value = str(rng.choice(params))
    return f"{name}:{key}={value}", f"{key}={value}"


# --------------------------------------------------------------------------------------
# running one case (in a worker)
# --------------------------------------------------------------------------------------
def _finite(values: object) -> bool:
    array = np.asarray(values)
    return bool(array.size == 0 or np.all(np.isfinite(array.astype(np.float64, copy=False))))


def _probe_directions() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    L = rng.normal(size=(256, 3))
    V = rng.normal(size=(256, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]) + 1e-3, np.abs(V[:, 2]) + 1e-3
    L[0], V[0] = (0.0, 0.0, 1.0), (0.0, 0.0, 1.0)  # normal incidence: the peak of most lobes
    L[1], V[1] = (1.0, 0.0, 1e-6), (-1.0, 0.0, 1e-6)  # grazing mirror pair
    return L / np.linalg.norm(L, axis=1, keepdims=True), V / np.linalg.norm(V, axis=1, keepdims=True)


def load_and_check(reader: str, target: str, analyse: bool = False) -> tuple[bool, str]:
    """Load ``target`` with the reader's public loader; (all values finite, summary). ``analyse``: a
    BRDF is also given to ``choose_orders`` (ε 0.1, F ≤ 48, the default P cap, the RH02 rule), whose
    orders and ε must be finite with ε in [0, 1] (a table with one sample once took 477 s and 4.9 GB
    there)."""
    if reader in ("merl", "table", "cornell", "fit_json", "spec", "rgl", "curet", "gonio"):
        import warnings

        from shrmkit.brdf_io.specs import load_brdf

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            brdf = load_brdf(target)
        if reader in ("cornell", "curet", "gonio"):
            return _finite(brdf.rgb) and _finite(brdf.L) and _finite(brdf.V), f"{len(brdf.rgb)} samples"
        L, V = _probe_directions()
        values = brdf.eval(L, V)
        summary = f"{type(brdf).__name__}, max {np.max(values):.3g}"
        if analyse and _finite(values):
            from shrmkit.analysis.orders import choose_orders

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                # max_P at its default (20); at 24 the table with one measured sample of 216 took 7.4 s and
                # 1.1 GB before choose_orders capped P, like F, at the order the table's grid resolves
                choice = choose_orders(brdf, eps=0.1, max_F=48, criterion="rh02")
            ok = 0 <= choice.F <= 48 and 0 <= choice.P and np.isfinite(choice.eps) and 0 <= choice.eps <= 1
            return ok, f"{summary}; orders F {choice.F}, P {choice.P}, eps {choice.eps:.3g}"
        return _finite(values), summary
    if reader == "shrm":
        from shrmkit.analysis.shrm import load_shrm

        shrm = load_shrm(target)
        L, V = _probe_directions()
        values = shrm.radiance(L, V)
        return _finite(values) and _finite(shrm.coeffs), f"F={shrm.F}, P={shrm.P}"
    if reader in ("exr", "hdr", "pfm", "probe", "cube"):
        import warnings

        from shrmkit.brdf_io.envmap import load_env

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # resampling the OpenEXR cube seed (6 × 256² texels, ~2M equal-area sub-samples at the
            # default size) cost 2.5 s a case, most of the harness's time; 32 rows (16² sub-samples a
            # pixel, 0.5M) read and check the same file
            height = 32 if reader == "exr" else None
            env = load_env(target, probe=True) if reader == "probe" else load_env(target, height=height)
        return _finite(env.radiance), f"{env.radiance.shape}"
    if reader in ("ply", "obj"):
        import warnings

        from shrmkit.render.mesh import load_mesh

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mesh = load_mesh(target)
        faces = np.asarray(mesh.faces)
        ok = _finite(mesh.vertices) and faces.size > 0 and int(faces.max()) < len(mesh.vertices) and faces.min() >= 0
        return ok, f"{len(mesh.vertices)} vertices, {len(faces)} faces"
    if reader == "_selftest":  # misbehaviours the harness must classify (self_test)
        from shrmkit.brdf_io.errors import BadInputError

        if target == "sleep":
            time.sleep(3600)
        if target == "die":
            os.kill(os.getpid(), signal.SIGSEGV)
        if target == "huge":
            return _finite(np.ones(2**40, dtype=np.uint8)), "allocated 1 TiB"
        if target == "creep":
            block = np.ones(2**29, dtype=np.uint8)  # 512 MiB touched
            return _finite(block[:10]), "allocated 512 MiB"
        if target == "keyerror":
            raise KeyError("header")
        if target == "nan":
            return _finite(np.array([1.0, np.nan])), "a NaN"
        if target == "unnamed":
            raise BadInputError(None, "something is wrong")
        if target == "clean":
            raise BadInputError("the-file", "truncated")
        return True, "fine"
    raise ValueError(f"unknown reader {reader}")


def _peak_rss_reset() -> None:
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass


def _peak_rss_mib() -> float:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")


def run_case(reader: str, target: str, names: list[str], analyse: bool = False) -> dict:
    """Classify one case (see the module docstring); ``names``: strings a clean error may
    quote to name the file (its path, its name, a cube folder); ``analyse``: see :func:`load_and_check`."""
    from shrmkit.brdf_io.errors import BadInputError

    _peak_rss_reset()
    base = _peak_rss_mib()
    try:
        finite, summary = load_and_check(reader, target, analyse)
        outcome = "valid" if finite else "garbage"
        detail = summary if finite else f"non-finite values ({summary})"
    except BadInputError as err:
        text = str(err)
        memory_words = ("MemoryError", "bad_alloc", "Unable to allocate", "Cannot allocate memory")
        if any(w in text for w in memory_words):
            outcome, detail = "memory", text[:300]
        elif "\n" in text.strip():
            outcome, detail = "garbage", "multi-line message: " + text[:300]
        else:
            outcome = "clean" if any(name and name in text for name in names) else "garbage"
            detail = text[:300] if outcome == "clean" else "does not name the file: " + text[:300]
    except MemoryError:
        outcome, detail = "memory", "MemoryError"
    except RecursionError:
        outcome, detail = "crash", "RecursionError"
    except Exception as err:  # noqa: BLE001 — classifying every other failure is the point
        tb = traceback.extract_tb(err.__traceback__)
        where = f"{Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else "?"
        outcome, detail = "crash", f"{type(err).__name__} at {where}: {str(err)[:200]}"
    grown = _peak_rss_mib() - base
    return {"outcome": outcome, "detail": detail, "peak_mib": grown}


def _worker_main(memory_gib: float, budget_mib: float) -> None:
    """Worker loop: one JSON case per stdin line, one JSON result per stdout line."""
    import resource
    import warnings

    warnings.simplefilter("ignore")
    import shrmkit.analysis.shrm  # noqa: F401 — imports before the limit
    import shrmkit.brdf_io.envmap  # noqa: F401
    import shrmkit.brdf_io.specs  # noqa: F401
    import shrmkit.render.mesh  # noqa: F401

    limit = int(memory_gib * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    out = sys.stdout
    sys.stdout = sys.stderr  # stray prints must not break the protocol
    for line in sys.stdin:
        case = json.loads(line)
        result = run_case(case["reader"], case["target"], case["names"], bool(case.get("analyse")))
        if result["outcome"] in ("clean", "valid") and result["peak_mib"] > budget_mib:
            result = {**result, "outcome": "memory", "detail": f"peak +{result['peak_mib']:.0f} MiB; " +
                      result["detail"]}
        out.write(json.dumps(result) + "\n")
        out.flush()


# --------------------------------------------------------------------------------------
# the driver
# --------------------------------------------------------------------------------------
class Worker:
    """A worker process with a memory limit; replaced after a hang or a death."""

    def __init__(self, memory_gib: float, budget_mib: float) -> None:
        env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "MALLOC_ARENA_MAX": "2", "PYTHONWARNINGS": "ignore",
               # the memory plan at half the budget: a reader's estimate short by 2x shows as "memory"
               "SHRM_MAX_MEMORY_BYTES": str(int(budget_mib * 2**20 / 2))}
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--worker", str(memory_gib), str(budget_mib)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env, cwd=ROOT,
            start_new_session=True,
        )
        self.case: dict | None = None
        self.started = 0.0

    def send(self, case: dict) -> None:
        self.case, self.started = case, time.monotonic()
        assert self.proc.stdin is not None
        self.proc.stdin.write((json.dumps(case) + "\n").encode())
        self.proc.stdin.flush()

    def kill(self) -> None:
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        self.proc.wait()
        for stream in (self.proc.stdin, self.proc.stdout):
            if stream is not None:
                stream.close()


def _materialise(case: dict, content: bytes | str, seed_path: Path, work: Path) -> tuple[str, list[str]]:
    """Write the mutated file (or special file) for ``case``; return (target, names)."""
    reader = case["reader"]
    folder = work / f"{reader}_{case['index']}"
    folder.mkdir()
    if reader == "curet":  # abrdf.dat or table.txt of a copied folder is mutated
        data = folder / "curet"
        shutil.copytree(seed_path, data)
        path = data / ("abrdf.dat", "table.txt")[case["index"] % 2]
        path.unlink()
        target = f"{data / 'abrdf.dat'}#{1 + case['index'] % 61}"
        names = [str(data / "abrdf.dat"), str(path), str(data), path.name]
    elif reader == "cube":  # one face of a copied cube folder is mutated
        cube = folder / "cube"
        shutil.copytree(seed_path, cube)
        face = ("px", "nx", "py", "ny", "pz", "nz")[case["index"] % 6]
        path = cube / f"{face}.pfm"
        path.unlink()
        target, names = str(cube), [str(cube), str(path), cube.name]
    else:
        suffix = ".shrm.npz" if reader == "shrm" else seed_path.suffix
        name = "probe_case" if reader == "probe" else "case"
        path = folder / f"{name}{suffix}"
        target, names = str(path), [str(path), path.name]
        if reader == "gonio":
            target = f"{path}#532"
    if isinstance(content, str):  # a special file
        if content == "fifo":
            os.mkfifo(path)
        elif content == "devzero":
            os.symlink("/dev/zero", path)
        elif content == "folder":
            path.mkdir()
        else:
            path.write_bytes(b"")
    else:
        path.write_bytes(content)
    return target, names


def build_cases(readers: dict[str, Reader], seed: int, per_reader: int, only: set[str] | None,
                caps: dict[str, int] | None = None) -> list[dict]:
    """Cases ``per_reader`` per reader (at most ``caps[reader]`` where given); case i of a reader is the
    same for any count (its seed is (seed, reader index, i)), so a smaller count is a prefix."""
    cases = []
    for r_index, reader in enumerate(sorted(readers)):
        if (only and reader not in only) or not (readers[reader].seeds or readers[reader].text_seeds):
            continue
        for i in range(min(per_reader, (caps or {}).get(reader, per_reader))):
            cases.append({"reader": reader, "index": i, "seed": [seed, r_index, i]})
    return cases


def _prepare(case: dict, readers: dict[str, Reader], work: Path,
             seed_bytes: Callable[[Path], bytes] = Path.read_bytes, light: bool = False) -> dict:
    """Write the case's file (``seed_bytes(path)``: a seed file's content, read once per run by
    :func:`run_fuzz`; a MERL seed is 35 MB; ``light``: see :func:`mutate`)."""
    reader = readers[case["reader"]]
    rng = np.random.default_rng(case["seed"])
    if reader.text_seeds:
        spec = reader.text_seeds[int(rng.integers(0, len(reader.text_seeds)))]
        target, desc = mutate_spec(rng, spec) if case["index"] >= len(reader.text_seeds) else (spec, "seed")
        # a message may quote the spec (repr) or escape its control characters
        names = [target, target.strip(), repr(target), repr(target.strip()), target.encode("unicode_escape").decode(),
                 "empty" if not target.strip() else ""]
        return {**case, "target": target, "names": names, "mutation": desc, "is_seed": desc == "seed"}
    seed_path = reader.seeds[int(rng.integers(0, len(reader.seeds)))]
    kind = reader.mutations[int(rng.integers(0, len(reader.mutations)))]
    if case["index"] < len(reader.seeds):  # the first cases are the seeds themselves: they must load
        seed_path, kind = reader.seeds[case["index"]], "none"
    source = seed_path
    if reader.name == "cube":
        source = seed_path / ("px", "nx", "py", "ny", "pz", "nz")[case["index"] % 6]
        source = source.with_suffix(".pfm")
    elif reader.name == "curet":
        source = seed_path / ("abrdf.dat", "table.txt")[case["index"] % 2]
    content, desc = mutate(reader, rng, seed_bytes(source), kind, light)
    target, names = _materialise(case, content, seed_path, work)
    return {**case, "target": target, "names": names, "mutation": f"{seed_path.name}: {desc}",
            "is_seed": kind == "none", "analyse": kind == "degenerate"}


def drive(
    cases: list[dict],
    prepare: Callable[[dict], dict],
    finished: Callable[[dict], None],
    workers: int = 2,
    timeout: float = 20.0,
    memory_gib: float = 4.0,
    budget_mib: float = 1024.0,
) -> list[dict]:
    """Run prepared cases on a pool of limited workers; classify hangs and deaths here."""
    pending = list(reversed(cases))
    pool = [Worker(memory_gib, budget_mib) for _ in range(max(1, workers))]
    results: list[dict] = []
    try:
        while pending or any(w.case for w in pool):
            for w in pool:
                if w.case is None and pending:
                    w.send(prepare(pending.pop()))
            busy = {w.proc.stdout.fileno(): w for w in pool if w.case is not None}
            ready, _, _ = select.select(list(busy), [], [], 0.2)
            now = time.monotonic()
            for fd, w in list(busy.items()):
                case, started = w.case, w.started
                if fd in ready:
                    line = w.proc.stdout.readline()
                    if line:
                        result = {**case, **json.loads(line)}
                        w.case = None
                    else:  # died: a segfault, or killed at the memory limit
                        code = w.proc.wait()
                        w.kill()
                        result = {**case, "outcome": "memory" if code == -signal.SIGKILL else "crash",
                                  "detail": f"worker died (exit {code})", "peak_mib": float("nan")}
                        pool[pool.index(w)] = Worker(memory_gib, budget_mib)
                elif now - started > timeout:
                    w.kill()
                    result = {**case, "outcome": "hang", "detail": f"no answer in {timeout:g} s",
                              "peak_mib": float("nan")}
                    pool[pool.index(w)] = Worker(memory_gib, budget_mib)
                else:
                    continue
                result["seconds"] = round(now - started, 3)
                results.append(result)
                finished(result)
    finally:
        for w in pool:
            w.kill()
    return results


def run_fuzz(
    seed: int = 0,
    per_reader: int = 1000,
    readers_only: set[str] | None = None,
    workers: int = 2,
    timeout: float = 20.0,
    memory_gib: float = 4.0,
    budget_mib: float = 1024.0,
    progress: Callable[[int, int], None] | None = None,
    caps: dict[str, int] | None = None,
    light: bool = False,
) -> list[dict]:
    """Run the fuzz cases; return one result dict per case (reader, index, mutation,
    outcome, detail, seconds, peak_mib). ``caps``: fewer cases for the named readers (a MERL case
    writes and reads a 35 MB file); ``light``: the cheaper variants of the
    ``npz_inflate`` and ``hdr_limit`` mutations (no 50/400 MB table builds, no decoded picture: CI)."""
    work = Path(tempfile.mkdtemp(prefix="shrm_fuzz_"))
    try:
        (work / "seeds").mkdir()
        (work / "cases").mkdir()
        readers = _write_seeds(work / "seeds")
        cases = build_cases(readers, seed, per_reader, readers_only, caps)
        done = 0

        def finished(result: dict) -> None:
            nonlocal done
            done += 1
            folder = work / "cases" / f"{result['reader']}_{result['index']}"
            if folder.exists():
                _remove(folder)
            if progress:
                progress(done, len(cases))

        seeds: dict[Path, bytes] = {}

        def seed_bytes(path: Path) -> bytes:
            if path not in seeds:
                seeds[path] = path.read_bytes()
            return seeds[path]

        return drive(cases, lambda c: _prepare(c, readers, work / "cases", seed_bytes, light), finished, workers,
                     timeout,
                     memory_gib, budget_mib)
    finally:
        _remove(work)


def self_test(timeout: float = 5.0, memory_gib: float = 2.0, budget_mib: float = 256.0) -> dict[str, str]:
    """Classify the harness's own misbehaving loads (reader ``_selftest``): a hang, a
    death, a huge allocation, a creeping allocation, a wrong exception, a non-finite
    result, an unnamed error, a clean error and a valid load. Returns target -> outcome."""
    targets = ["sleep", "die", "huge", "creep", "keyerror", "nan", "unnamed", "clean", "fine"]
    cases = [{"reader": "_selftest", "index": i, "target": t, "names": ["the-file"], "mutation": t}
             for i, t in enumerate(targets)]
    results = drive(cases, lambda c: c, lambda r: None, 2, timeout, memory_gib, budget_mib)
    return {r["target"]: r["outcome"] for r in results}


def _remove(folder: Path) -> None:
    for path in sorted(folder.rglob("*"), key=lambda p: -len(p.parts)):
        if path.is_symlink() or path.is_file() or (path.exists() and not path.is_dir()) or not path.exists():
            try:
                path.unlink()
            except OSError:
                pass
        else:
            try:
                path.rmdir()
            except OSError:
                pass
    shutil.rmtree(folder, ignore_errors=True)


def _seed_refused(result: dict) -> bool:
    """An unchanged seed that does not load is a failure too (of the reader or of the harness)."""
    return bool(result.get("is_seed")) and result["outcome"] != "valid"


def outcome_table(results: list[dict]) -> str:
    """The table of outcomes per reader (plain text), with each reader's largest peak memory growth
    of one case (MiB, resident) and its slowest case (s)."""
    by_reader: dict[str, Counter] = {}
    peak: dict[str, float] = {}
    slowest: dict[str, float] = {}
    for r in results:
        name = r["reader"]
        by_reader.setdefault(name, Counter())[r["outcome"]] += 1
        grown = r.get("peak_mib", float("nan"))
        if grown == grown:  # not NaN (a case whose worker died has no measure)
            peak[name] = max(peak.get(name, 0.0), float(grown))
        slowest[name] = max(slowest.get(name, 0.0), float(r.get("seconds", 0.0)))
    width = max([len(n) for n in by_reader] + [6])
    head = (f"{'reader':<{width}} " + " ".join(f"{o:>7}" for o in OUTCOMES) + f" {'total':>7}"
            + f" {'peak MiB':>9} {'max s':>6}")
    lines = [head, "-" * len(head)]
    total = Counter()
    for name in sorted(by_reader):
        counts = by_reader[name]
        total.update(counts)
        lines.append(f"{name:<{width}} " + " ".join(f"{counts[o]:>7}" for o in OUTCOMES)
                     + f" {sum(counts.values()):>7} {peak.get(name, 0.0):>9.0f} {slowest[name]:>6.2f}")
    lines.append("-" * len(head))
    lines.append(f"{'all':<{width}} " + " ".join(f"{total[o]:>7}" for o in OUTCOMES) + f" {sum(total.values()):>7}"
                 + f" {max(peak.values(), default=0.0):>9.0f} {max(slowest.values(), default=0.0):>6.2f}")
    return "\n".join(lines)


def _show(spec: str, seed: int) -> int:
    """Rerun one case in this process, printing the mutation and the traceback."""
    reader_name, index = spec.split(":")
    work = Path(tempfile.mkdtemp(prefix="shrm_fuzz_show_"))
    try:
        readers = _write_seeds(work)
        case = next(c for c in build_cases(readers, seed, int(index) + 1, {reader_name}) if c["index"] == int(index))
        (work / "cases").mkdir()
        case = _prepare(case, readers, work / "cases")
        print(f"{reader_name}:{index}: {case['mutation']}\ntarget: {case['target'][:200]}")
        finite, summary = load_and_check(reader_name, case["target"], bool(case.get("analyse")))
        print(f"loaded: finite={finite}, {summary}")
    except Exception:  # noqa: BLE001
        traceback.print_exc()
    finally:
        _remove(work)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=900, help="cases per reader (default 900: > 10,000 in all)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--readers", default="", help="comma-separated subset (default: all)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds per case before it counts as a hang")
    parser.add_argument("--memory-gib", type=float, default=4.0, help="address-space limit of a worker")
    parser.add_argument("--memory-budget-mib", type=float, default=1024.0,
                        help="peak resident growth of one case above which it counts as a memory blow-up")
    parser.add_argument("--show", metavar="READER:INDEX", help="rerun one case here with its traceback")
    parser.add_argument("--failures", type=int, default=40, help="failures to list (default 40)")
    args = parser.parse_args(argv)
    if args.show:
        return _show(args.show, args.seed)
    only = {r for r in args.readers.split(",") if r} or None
    start = time.monotonic()

    def progress(done: int, total: int) -> None:
        if done % 200 == 0 or done == total:
            print(f"  {done}/{total} cases, {time.monotonic() - start:.0f} s", file=sys.stderr, flush=True)

    results = run_fuzz(args.seed, args.cases, only, args.workers, args.timeout, args.memory_gib,
                       args.memory_budget_mib, progress)
    failures = [r for r in results if r["outcome"] in FAILURES or _seed_refused(r)]
    slow = sorted(results, key=lambda r: -r.get("seconds", 0))[:5]
    print("slowest: " + ", ".join(f"{r['reader']}:{r['index']} {r.get('seconds', 0):.1f} s" for r in slow))
    for r in failures[: args.failures]:
        print(f"{r['outcome']:>7} {r['reader']}:{r['index']} [{r['mutation']}] {r['detail']}")
    if failures:
        print()
    print(outcome_table(results))
    print(f"{len(results)} cases in {time.monotonic() - start:.0f} s with {args.workers} workers "
          f"(seed {args.seed}, timeout {args.timeout:g} s, {args.memory_gib:g} GiB per worker); "
          f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "--worker":
        _worker_main(float(sys.argv[2]), float(sys.argv[3]))
    else:
        sys.exit(main())
