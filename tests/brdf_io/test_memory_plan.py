"""The memory plan (data_specs/limits.md): readers estimate their peak from the header and refuse,
naming the file, before they allocate or inflate (issues 28 and 30).

Each file here is crafted small: the header declares sizes within the pixel and element limits
whose reading would cost gigabytes. The reference is ``tracemalloc`` (numpy reports its
allocations there): the refusal must come before any large array exists.
"""

from __future__ import annotations

import io
import json
import struct
import tracemalloc
import zipfile
import zlib

import numpy as np
import pytest

from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.exr import read_exr, write_exr
from shrmkit.brdf_io.limits import check_memory, format_bytes
from shrmkit.brdf_io.merl import read_merl
from shrmkit.brdf_io.pfm import read_pfm, write_pfm
from shrmkit.brdf_io.rgbe import read_hdr
from shrmkit.brdf_io.table import MAX_RESOLVED_ORDER, TableBRDF, read_table, write_table

META = {"format": "shrmkit-brdf-table", "format_version": 1, "units": "1/sr", "name": "t"}


def _npy(array: np.ndarray) -> bytes:
    out = io.BytesIO()
    np.save(out, array)
    return out.getvalue()


def _inflating_table(path, shape: tuple[int, ...], pad: int = 2_200_000) -> None:
    """A table whose ``values`` member declares float64 ``shape`` (its .npy header is true) while the
    archive holds only ``pad`` zero bytes of it, deflated as stored blocks: the zip directory says
    header + 8·prod(shape) bytes from ~``pad`` compressed (ratio < 1100, as real deflate of zeros)."""
    n_ti, n_to, n_pd = shape[:3]
    grid = {"theta_i": np.linspace(0, 1.5, n_ti), "theta_o": np.linspace(0, 1.5, n_to),
            "phi_d": np.linspace(0, 3.1, n_pd)}
    header = np.lib.format.header_data_from_array_1_0(np.zeros(1))
    header["shape"] = shape
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    head = buf.getvalue()
    deflate = zlib.compressobj(0, zlib.DEFLATED, -15)  # level 0: stored deflate blocks
    stream = deflate.compress(head + bytes(pad)) + deflate.flush(zlib.Z_SYNC_FLUSH)
    declared = len(head) + 8 * int(np.prod(shape))
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as archive:
        for key, value in grid.items():
            archive.writestr(f"{key}.npy", _npy(value))
        archive.writestr("metadata.npy", _npy(np.array(json.dumps(META))))
        info = zipfile.ZipInfo("values.npy")
        info.compress_type = zipfile.ZIP_DEFLATED
        archive.writestr(info, b"")  # the last member, empty: its data and sizes are patched below
    data = bytearray(path.read_bytes())
    local = data.index(b"values.npy") - 30  # local file header (zip APPNOTE 4.3.7)
    central = data.rindex(b"values.npy") - 46  # its central directory entry (4.3.12)
    start = local + 30 + len(b"values.npy") + struct.unpack_from("<H", data, local + 28)[0]
    first_central = data.index(b"PK\x01\x02")
    shift = len(stream) - (first_central - start)
    data[start:first_central] = stream
    struct.pack_into("<II", data, local + 18, len(stream), declared)
    struct.pack_into("<II", data, central + shift + 20, len(stream), declared)
    end = data.rindex(b"PK\x05\x06")
    struct.pack_into("<I", data, end + 16, struct.unpack_from("<I", data, end + 16)[0] + shift)
    path.write_bytes(bytes(data))


def _peak_while(call) -> tuple[int, BaseException | None]:
    tracemalloc.start()
    error = None
    try:
        call()
    except BadInputError as err:
        error = err
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak, error


def test_table_member_that_inflates_a_thousand_fold_is_refused_from_its_header(tmp_path):
    """Issue 30: 2.2 MB of archive whose values member declares 2²⁸ float64 (within SHRM_MAX_ELEMENTS,
    a deflate ratio of 976, under the 1100 the directory check allows): refused from the .npy header
    by the memory plan (40 B a value: 10 GiB > 8 GiB), not allocated (2 GiB) and inflated."""
    path = tmp_path / "bomb.npz"
    _inflating_table(path, (1024, 1024, 256))
    assert path.stat().st_size < 2_400_000
    peak, error = _peak_while(lambda: read_table(path))
    assert error is not None and str(path) in str(error), error
    assert "SHRM_MAX_MEMORY_BYTES" in str(error) and "10.0 GiB" in str(error)
    assert peak < 64 * 2**20  # the member is never allocated (before: 2 GiB traced)


def test_table_within_the_plan_is_read_and_a_lower_plan_refuses_it(tmp_path, monkeypatch):
    """The plan's estimate against a real table: 4 × 64 × 64 × 3 values read under the default; with
    SHRM_MAX_MEMORY_BYTES below 40 B × 49,152 values it is refused, naming the file."""
    path = tmp_path / "t.npz"
    write_table(path, np.full((4, 64, 64, 3), 0.25), theta_i=np.linspace(0, 1.5, 4),
                theta_o=np.linspace(0, 1.5, 64), phi_d=np.linspace(0, 3.1, 64))
    assert read_table(path).values.shape == (4, 64, 64, 3)
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(40 * 49_152 - 1))
    with pytest.raises(BadInputError, match="t.npz: reading values .* needs an estimated 1.9 MiB"):
        read_table(path)


def _rle_hdr(path, height: int, width: int) -> None:
    """A valid run-length Radiance file of height × width grey pixels in the fewest bytes: per
    scanline, per component, runs of 127 equal bytes (Radiance color.c)."""
    runs, last = divmod(width, 127)
    component = bytes([255, 128]) * runs + (bytes([128 + last, 128]) if last else b"")
    line = bytes([2, 2, width >> 8, width & 255]) + component * 4
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {height} +X {width}\n".encode()
                     + line * height)


def test_rle_hdr_at_the_pixel_limit_is_refused_from_its_header(tmp_path):
    """Issue 30: a 17 MB run-length .hdr of 23,170 × 11,585 pixels (2:1, under SHRM_MAX_PIXELS)
    decoded into 4.3 GB (15 s). The plan (file + 40 B a pixel = 10 GiB) refuses it on the
    resolution line, as a picture and as an environment map (64 B a pixel), before decoding."""
    path = tmp_path / "limit.hdr"
    _rle_hdr(path, 11585, 23170)
    assert 16e6 < path.stat().st_size < 18e6
    for load in (read_hdr, load_env):
        peak, error = _peak_while(lambda load=load: load(path))
        assert error is not None and str(path) in str(error) and "SHRM_MAX_MEMORY_BYTES" in str(error), error
        assert "23170 x 11585" in str(error)
        assert peak < 3 * path.stat().st_size  # the file's bytes, no pixel array


def test_small_rle_hdr_decodes_and_lower_plan_refuses_it(tmp_path, monkeypatch):
    """The same writer at 16 × 32 gives a picture of value (128 / 256) · 2^(128 − 128) = 0.5 per
    channel (Ward's decoding, no ½ offset): the crafted files are real Radiance files."""
    path = tmp_path / "small.hdr"
    _rle_hdr(path, 16, 32)
    image = read_hdr(path)
    assert image.shape == (16, 32, 3) and np.all(image == 0.5)
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(path.stat().st_size + 40 * 16 * 32 - 1))
    with pytest.raises(BadInputError, match=r"small.hdr: decoding 32 x 16 pixels needs an estimated"):
        read_hdr(path)


def test_pfm_and_exr_are_planned_from_their_headers(tmp_path, monkeypatch):
    """PFM: file + 16 B a pixel; OpenEXR: file + 28 B a data-window pixel + 12 B a display pixel;
    environment maps: file + 64 B a pixel. Each read under the default, refused below its estimate."""
    image = np.full((8, 16, 3), 0.5, np.float32)
    write_pfm(tmp_path / "m.pfm", image)
    write_exr(tmp_path / "m.exr", image)
    assert np.all(read_pfm(tmp_path / "m.pfm") == 0.5) and np.all(read_exr(tmp_path / "m.exr") == 0.5)
    size = (tmp_path / "m.pfm").stat().st_size
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(size + 16 * 128 - 1))
    with pytest.raises(BadInputError, match=r"m.pfm: reading 16 x 8 pixels needs an estimated"):
        read_pfm(tmp_path / "m.pfm")
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(size + 16 * 128))
    read_pfm(tmp_path / "m.pfm")
    with pytest.raises(BadInputError, match=r"m.pfm: loading a 16 x 8 map needs an estimated"):
        load_env(tmp_path / "m.pfm")  # 64 B a pixel
    size = (tmp_path / "m.exr").stat().st_size
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(size + 40 * 128 - 1))
    with pytest.raises(BadInputError, match=r"m.exr: reading the data and display windows needs"):
        read_exr(tmp_path / "m.exr")
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(size + 64 * 128 + 64 * 2 * 4 * 4))
    assert load_env(tmp_path / "m.exr", height=4).radiance.shape == (4, 8, 3)
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(size + 64 * 128 + 64 * 2 * 4 * 4 - 1))
    with pytest.raises(BadInputError, match=r"m.exr: loading a 16 x 8 map into 8 x 4 needs"):
        load_env(tmp_path / "m.exr", height=4)


def test_check_memory_message_and_limit(monkeypatch):
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(2**30))
    assert check_memory("--size 10", 2**30, "a map") == 2**30
    with pytest.raises(BadInputError, match=r"^--size 99: a map needs an estimated 1.0 GiB of memory, over the "
                                            r"1.0 GiB limit \(SHRM_MAX_MEMORY_BYTES\)$"):
        check_memory("--size 99", 2**30 + 1, "a map")
    with pytest.raises(BadInputError, match="SHRM_MAX_MEMORY_BYTES"):
        check_memory("x", float("inf"), "a map")
    assert format_bytes(512 * 2**20) == "512 MiB" and format_bytes(3 * 2**40) == "3,072 GiB"
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", "lots")
    with pytest.raises(BadInputError, match="SHRM_MAX_MEMORY_BYTES='lots' is not a whole number"):
        check_memory("x", 1, "a map")


def test_tables_and_merl_files_without_a_measured_sample_are_refused(tmp_path):
    """All NaN (table) or all negative (MERL): evaluated as 0 everywhere, a black surface that was never
    measured (`shrm orders` said "zero everywhere"). All 0 or 1e-300 (the fuzz harness's degenerate
    tables: the analysis's error named the metadata's name, not the file). Refused on reading, naming
    the file."""
    grid = {"theta_i": np.radians([0.0, 30, 60]), "theta_o": np.radians([0.0, 30, 60]),
            "phi_d": np.radians([0.0, 90, 180])}
    write_table(tmp_path / "nan.npz", np.full((3, 3, 3, 3), np.nan), **grid)
    with pytest.raises(BadInputError, match=r"nan.npz: all 27 grid points are missing \(NaN\)"):
        read_table(tmp_path / "nan.npz")
    values = np.full((3, 3, 3, 3), np.nan)
    values[1, 2, 0] = 0.5  # one measured sample is data
    write_table(tmp_path / "one.npz", values, **grid)
    assert read_table(tmp_path / "one.npz").n_missing == 26
    # 12-byte header (90, 90, 180) then 3 planes of -1.0 (missing), as write_merl writes NaN
    (tmp_path / "nan.binary").write_bytes(np.array([90, 90, 180], "<i4").tobytes()
                                          + np.full(3 * 90 * 90 * 180, -1.0, "<f8").tobytes())
    with pytest.raises(BadInputError, match=r"nan.binary: every sample is missing"):
        read_merl(tmp_path / "nan.binary")
    for name, value in (("zero", 0.0), ("underflow", 1e-300)):  # analysed as "zero everywhere", named by
        write_table(tmp_path / f"{name}.npz", np.full((3, 3, 3, 3), value), **grid)  # the metadata's name
        with pytest.raises(BadInputError, match=rf"{name}.npz: the largest value is {value!r} 1/sr, at most 1e-30"):
            read_table(tmp_path / f"{name}.npz")


def test_resolved_order_of_subnormal_node_spacing_is_capped():
    """Found by the fuzz harness's degenerate tables: θ_i nodes 5·10⁻³²⁴ rad apart made 2π / Δ
    infinite and ``resolved_order`` raised OverflowError; it is capped (and 2π / 1 rad → 7)."""
    values = np.full((2, 2, 2), 0.2)
    tiny = TableBRDF(np.array([0.0, 5e-324]), np.array([0.0, 0.5]), np.array([0.0, 1.0]), values)
    assert tiny.resolved_order() == MAX_RESOLVED_ORDER
    plain = TableBRDF(np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.array([0.0, 1.0]), values)
    assert plain.resolved_order() == 7


@pytest.mark.parametrize("reader, name, per_byte", [
    ("cornell", "m.brdf", 8), ("gonio", "m.csv", 8), ("curet", "abrdf.dat", 8), ("rgl", "m.bsdf", 32),
])
def test_text_and_tensor_files_are_planned_from_their_size(tmp_path, monkeypatch, reader, name, per_byte):
    """Text readers (Cornell, gonioreflectometer CSV, CURET) plan 8 B per file byte (4.0 and 6.2 measured on
    27 and 9 MB files), RGL tensor files 32 (21 measured): refused before the file is read when the plan
    is over SHRM_MAX_MEMORY_BYTES, naming the file; at the limit, the plan passes (and the content, here
    meaningless, is what is refused)."""
    from shrmkit.brdf_io.cornell import read_cornell
    from shrmkit.brdf_io.curet import read_curet
    from shrmkit.brdf_io.gonio import read_gonio_csv
    from shrmkit.brdf_io.rgl import read_rgl

    load = {"cornell": read_cornell, "gonio": lambda p: read_gonio_csv(p, 532), "curet": lambda p: read_curet(p, 1),
            "rgl": read_rgl}[reader]
    path = tmp_path / name
    path.write_bytes(b"1 2 3\n" * 1000)
    (tmp_path / "table.txt").write_bytes(b"1 2 3\n" * 1000)  # CURET's second file, as large
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(6000 * per_byte - 1))
    with pytest.raises(BadInputError, match=r"needs an estimated .* over the .* limit") as err:
        load(path)
    assert str(tmp_path) in str(err.value) and "6,000-byte" in str(err.value)
    monkeypatch.setenv("SHRM_MAX_MEMORY_BYTES", str(6000 * per_byte))
    with pytest.raises(BadInputError) as err:
        load(path)
    assert "SHRM_MAX_MEMORY_BYTES" not in str(err.value)
