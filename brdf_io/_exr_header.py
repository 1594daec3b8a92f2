"""The headers of an OpenEXR file: read and size-checked before any pixel, the part and layer chosen.

:func:`_read_headers` reads every part's header (the OpenEXR C library's own messages captured by
:func:`_library_output`, only their first line kept: :func:`_first_line`); :func:`_check_sizes`
refuses deep parts and declared sizes beyond the limits or beyond what the file's bytes can hold;
:func:`_choose_part` and :func:`_choose_layer` pick the colour to read, naming the candidates
when the choice is ambiguous. :mod:`.exr` reads the pixels; the rules are in
``data_specs/environment_maps.md`` §2.1.

Reference: [OpenEXR] file layout (chunk offset table, lines per chunk by compression).
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import OpenEXR

from .errors import BadInputError
from .limits import check_elements, check_memory, check_pixels

# scan lines per chunk by compression (OpenEXR file layout); unknown methods count as 256,
# which only weakens the lower bound on the file size
_LINES_PER_CHUNK = {
    "NO_COMPRESSION": 1, "RLE_COMPRESSION": 1, "ZIPS_COMPRESSION": 1, "ZIP_COMPRESSION": 16,
    "PIZ_COMPRESSION": 32, "PXR24_COMPRESSION": 16, "B44_COMPRESSION": 32, "B44A_COMPRESSION": 32,
    "DWAA_COMPRESSION": 32, "DWAB_COMPRESSION": 256,
}
# every chunk costs at least its 8-byte offset-table entry plus an 8-byte leader (y and size)
_MIN_BYTES_PER_CHUNK = 16
_MAX_CAPTURED_BYTES = 1 << 16


# --------------------------------------------------------------------------------------
# library messages
# --------------------------------------------------------------------------------------
class _Captured:
    text = ""


@contextlib.contextmanager
def _library_output() -> Iterator[_Captured]:
    """Capture what the OpenEXR C library writes to file descriptor 2 and what the bindings
    print on Python's stdout, for the duration of the block; the text lands in ``.text``.

    fd 2 is process-wide: output of other threads during the block is captured too."""
    captured = _Captured()
    buffer = io.StringIO()
    with contextlib.suppress(AttributeError, ValueError, OSError):
        sys.stderr.flush()
    saved = tmp = None
    try:
        tmp = tempfile.TemporaryFile()
        saved = os.dup(2)
        os.dup2(tmp.fileno(), 2)
    except OSError:  # no fd 2 to redirect: let the library write where it writes
        if saved is not None:
            os.close(saved)
        if tmp is not None:
            tmp.close()
        saved = tmp = None
    try:
        with contextlib.redirect_stdout(buffer):
            yield captured
    finally:
        text = ""
        if saved is not None:
            os.dup2(saved, 2)
            os.close(saved)
        if tmp is not None:
            tmp.seek(0)
            text = tmp.read(_MAX_CAPTURED_BYTES).decode("utf-8", "replace")
            tmp.close()
        captured.text = text + buffer.getvalue()


def _first_line(path: Path, *texts: str) -> str:
    """First non-empty line of the first text that has one, without a leading "<path>: "."""
    for text in texts:
        for line in text.splitlines():
            line = line.strip()
            for prefix in (f"{path}: ", f"{path.name}: "):
                if line.startswith(prefix):
                    line = line[len(prefix) :]
            if line:
                return line if len(line) <= 300 else line[:297] + "..."
    return "unknown error"


# --------------------------------------------------------------------------------------
# header checks
# --------------------------------------------------------------------------------------
def _box(value: Any) -> tuple[int, int, int, int]:
    lo, hi = value
    return int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])


def _box_size(box: tuple[int, int, int, int]) -> tuple[int, int]:
    """(height, width) of an inclusive box (≤ 0 when empty)."""
    return box[3] - box[1] + 1, box[2] - box[0] + 1


def _enum_name(value: Any) -> str:
    return str(getattr(value, "name", value))


def _part_label(index: int, name: str) -> str:
    return f"part {index}" + (f" {name!r}" if name else "")


@dataclass(frozen=True)
class _Part:
    index: int
    name: str
    header: dict
    channels: dict[str, tuple[int, int]]  # name -> (xSampling, ySampling)

    @property
    def storage(self) -> str:
        return _enum_name(self.header.get("type", "scanlineimage"))

    @property
    def data_window(self) -> tuple[int, int, int, int]:
        return _box(self.header["dataWindow"])

    @property
    def label(self) -> str:
        return _part_label(self.index, self.name)


def _read_headers(path: Path) -> list[_Part]:
    try:
        with _library_output() as out, OpenEXR.File(str(path), header_only=True) as exr:
            parts = []
            for i, part in enumerate(exr.parts):
                header = dict(exr.header(i))
                channels = {
                    str(ch.name): (int(ch.xSampling), int(ch.ySampling)) for ch in header.get("channels", [])
                }
                name = str(header.get("name", "") or part.name() or "")
                parts.append(_Part(i, name, header, channels))
    except Exception as err:  # the bindings raise RuntimeError/ValueError/... for bad files
        raise BadInputError(path, f"not a readable OpenEXR file ({_first_line(path, out.text, str(err))})") from None
    if not parts:
        raise BadInputError(path, f"not a readable OpenEXR file ({_first_line(path, out.text, 'no parts')})")
    return parts


def _check_sizes(path: Path, parts: list[_Part], size: int) -> None:
    """Refuse, from the headers alone, deep parts and declared sizes beyond the limits or
    beyond what ``size`` bytes can hold (one offset entry + chunk leader per chunk)."""
    deep = [p for p in parts if p.storage.startswith("deep")]
    if deep:
        raise BadInputError(
            path, "deep OpenEXR images are not environment maps ("
            + ", ".join(f"{p.label} is {p.storage}" for p in deep) + ")",
        )
    elements = 0
    chunks = 0
    for p in parts:
        source = path if len(parts) == 1 else f"{path} ({p.label})"
        if "dataWindow" not in p.header:
            raise BadInputError(source, "OpenEXR header has no dataWindow")
        h, w = _box_size(p.data_window)
        check_pixels(source, h, w)
        for name, (xs, ys) in p.channels.items():
            if xs < 1 or ys < 1:
                raise BadInputError(source, f"channel {name!r} has sampling {xs} x {ys}")
            elements += -(-w // xs) * -(-h // ys)
        tiles = p.header.get("tiles")
        if p.storage == "tiledimage" and tiles is not None:
            tx, ty = max(int(tiles.xSize), 1), max(int(tiles.ySize), 1)
            chunks += -(-w // tx) * -(-h // ty)
        else:
            chunks += -(-h // _LINES_PER_CHUNK.get(_enum_name(p.header.get("compression")), 256))
    check_elements(path, (elements,), "OpenEXR pixel data (all parts and channels)")
    # the memory plan (data_specs/limits.md): the file, every channel decoded (float32 at most)
    check_memory(path, size + 4 * elements, f"decoding {elements:,} OpenEXR channel samples")
    if chunks * _MIN_BYTES_PER_CHUNK > size:
        raise BadInputError(
            path, f"file of {size:,} bytes is too small for the {chunks:,} chunks its header declares "
            f"(at least {chunks * _MIN_BYTES_PER_CHUNK:,} bytes): truncated or corrupt",
        )


# --------------------------------------------------------------------------------------
# part and layer choice
# --------------------------------------------------------------------------------------
def _layers(channels: dict[str, tuple[int, int]]) -> dict[str, dict[str, str]]:
    """layer prefix -> {upper-case suffix: full channel name}; ``""`` for unprefixed names."""
    layers: dict[str, dict[str, str]] = {}
    for name in sorted(channels):
        prefix, _, suffix = name.rpartition(".")
        layers.setdefault(prefix, {}).setdefault(suffix.upper(), name)
    return layers


def _colour_kind(suffixes: dict[str, str]) -> str | None:
    if all(c in suffixes for c in ("R", "G", "B")):
        return "rgb"
    if all(c in suffixes for c in ("Y", "RY", "BY")):
        return "yca"
    if "Y" in suffixes:
        return "y"
    return None


def _colour_layers(part: _Part) -> list[str]:
    return [name for name, suffixes in _layers(part.channels).items() if _colour_kind(suffixes)]


def _describe_layers(names: list[str]) -> str:
    return ", ".join(repr(n) if n else "'' (unprefixed)" for n in names)


def _choose_part(path: Path, parts: list[_Part], part: int | str | None) -> _Part:
    def listing() -> str:
        return "; ".join(
            f"{p.label}: " + (f"colour layers {_describe_layers(_colour_layers(p))}" if _colour_layers(p)
                              else f"channels {sorted(p.channels)}")
            for p in parts
        )

    if part is not None:
        if isinstance(part, bool) or not isinstance(part, (int, str, np.integer)):
            raise BadInputError(path, f"part={part!r}: give a part name or index")
        if isinstance(part, str):
            named = [p for p in parts if p.name == part]
            if named:
                return named[0]
            if not part.strip().lstrip("-").isdigit():
                raise BadInputError(path, f"no part named {part!r}; parts: {listing()}")
            part = int(part.strip())
        index = int(part)
        if not 0 <= index < len(parts):
            raise BadInputError(path, f"part index {index} out of range (file has {len(parts)} part(s)): {listing()}")
        return parts[index]
    colour = [p for p in parts if _colour_layers(p)]
    if len(colour) == 1:
        return colour[0]
    if not colour:
        raise BadInputError(path, f"OpenEXR file has no R, G, B (or Y) channels; {listing()}")
    raise BadInputError(
        path, f"OpenEXR file has {len(colour)} parts with colour channels; choose one with "
        f"part=NAME|INDEX: {listing()}",
    )


def _choose_layer(path: Path, part: _Part, layer: str | None, multipart: bool) -> tuple[str, str, dict[str, str]]:
    """(layer, colour kind, {suffix: channel name}) of the chosen layer."""
    layers = _layers(part.channels)
    colour = [name for name, suffixes in layers.items() if _colour_kind(suffixes)]
    where = f" in {part.label}" if multipart else ""
    if layer is not None:
        if not isinstance(layer, str):
            raise BadInputError(path, f"layer={layer!r}: give a layer name")
        wanted = layer[:-1] if layer.endswith(".") else layer
        if wanted not in layers:
            folded = [name for name in layers if name.lower() == wanted.lower()]
            if len(folded) != 1:
                raise BadInputError(
                    path, f"no layer {layer!r}{where}; layers with colour: {_describe_layers(colour) or 'none'}"
                )
            wanted = folded[0]
        kind = _colour_kind(layers[wanted])
        if kind is None:
            raise BadInputError(
                path, f"layer {layer!r}{where} has no R, G, B (or Y) channels: {sorted(layers[wanted].values())}"
            )
        return wanted, kind, layers[wanted]
    if "" in layers and _colour_kind(layers[""]):
        return "", _colour_kind(layers[""]) or "", layers[""]
    if len(colour) == 1:
        return colour[0], _colour_kind(layers[colour[0]]) or "", layers[colour[0]]
    if not colour:
        raise BadInputError(
            path, f"OpenEXR file has no R, G, B (or Y) channels{where}; channels: {sorted(part.channels)}"
        )
    raise BadInputError(
        path, f"OpenEXR file has no plain R, G, B channels{where} and {len(colour)} layers with colour: "
        f"{_describe_layers(colour)}; choose one with layer=NAME",
    )
