"""Radiance picture scanlines (new-style run-length, pre-1991 run-length, flat) decoded to RGBE bytes.

:class:`_Decoder` turns the bytes after a Radiance header into file-order RGBE pixels, deciding
per scanline between the encodings as the Radiance library does; :func:`_smallest_encoding`
bounds the bytes a declared size needs (checked before anything is allocated). :mod:`.rgbe`
parses the header, converts the pixels and writes files; the rules are in
``data_specs/image_files.md``.

Reference: [Radiance] ``src/common/color.c`` (``freadcolrs``, ``oldreadcolrs``). Citation keys:
``data_specs/bibliography.md``.
"""

from __future__ import annotations

import array
from pathlib import Path

import numpy as np

from .errors import BadInputError

_RLE_MIN_WIDTH, _RLE_MAX_WIDTH = 8, 32767  # color.c MINELEN, MAXELEN
_BLOCK_BYTES = 1 << 22  # output bytes decoded / converted per block (bounds temporaries)
_OLD_WINDOW = 1 << 20  # 4-byte groups examined per step of the old-style decoder


class _Decoder:
    """Decode the scanlines of a Radiance picture into file-order RGBE bytes.

    Radiance (color.c ``freadcolrs``) decides per scanline: a scanline whose length is in
    8..32767 and whose first bytes are 2, 2, h, l with h < 128 is new-style run-length
    encoded (and h·256 + l must be the length); every other scanline is read by
    ``oldreadcolrs``: 4-byte pixels, where a pixel (1, 1, 1, n) repeats the previous pixel
    n << s times, s growing by 8 for each consecutive repeat pixel and restarting at 0 on
    every other pixel and every scanline. Repeats stop at the end of the scanline (the
    current Radiance), and a repeat at the start of a scanline copies the last pixel
    decoded before it.

    Python only walks the new-style chunk headers (one step per chunk) and the old-style
    repeat pixels that meet a scanline end; bytes are moved by numpy, in blocks of
    scanlines, so memory stays close to the output's 4 bytes per pixel.
    """

    def __init__(self, path: Path, data: bytes, pos: int, scanlines: int, length: int) -> None:
        self.path, self.data, self.pos = path, data, pos
        self.scanlines, self.length = scanlines, length
        self.src = np.frombuffer(data, dtype=np.uint8)
        self.out = np.empty((scanlines * length, 4), dtype=np.uint8)  # pages touched as decoded
        self.done = 0  # pixels decoded so far, file order
        self.rle_ok = _RLE_MIN_WIDTH <= length <= _RLE_MAX_WIDTH

    def run(self) -> np.ndarray:
        data, total = self.data, self.scanlines * self.length
        while self.done < total:
            p = self.pos
            if self.rle_ok and len(data) >= p + 4 and data[p] == 2 and data[p + 1] == 2 and data[p + 2] < 128:
                self._new_style()
            else:
                self._old_style()
        return self.out.reshape(self.scanlines, self.length, 4)

    def _truncated(self, kind: str) -> BadInputError:
        row = self.done // self.length
        return BadInputError(
            self.path,
            f"truncated {kind} RGBE data at scanline {row} of {self.scanlines} "
            f"({len(self.data) - self.pos} bytes left)",
        )

    # ----- new-style run-length scanlines
    def _new_style(self) -> None:
        """Decode new-style scanlines until the image is complete or an old-style one begins."""
        data, n, width = self.data, len(self.data), self.length
        heads = array.array("I" if n < 2**32 else "Q")  # file offset of every chunk header
        record = heads.append
        first = row = self.done // width
        starts = [self.pos]  # file offset of each scanline
        chunks = [0]  # chunks before each scanline
        pos = self.pos
        try:
            while row < self.scanlines:
                if pos + 4 > n:
                    raise IndexError
                if data[pos] != 2 or data[pos + 1] != 2 or data[pos + 2] & 128:
                    break  # an old-style scanline follows
                if data[pos + 2] << 8 | data[pos + 3] != width:
                    declared = data[pos + 2] << 8 | data[pos + 3]
                    raise BadInputError(
                        self.path, f"corrupt RLE data: scanline {row} declares length {declared}, expected {width}"
                    )
                pos += 4
                for _component in range(4):
                    filled = 0
                    while filled < width:
                        c = data[pos]
                        record(pos)
                        if c > 128:
                            filled += c - 128
                            pos += 2
                        elif c:
                            filled += c
                            pos += c + 1
                        else:
                            raise BadInputError(self.path, f"corrupt RLE data: zero-length chunk at scanline {row}")
                    if filled != width:
                        raise BadInputError(self.path, f"corrupt RLE data: chunk overruns scanline {row}")
                if pos > n:
                    raise IndexError
                row += 1
                starts.append(pos)
                chunks.append(len(heads))
        except IndexError:
            self.pos, self.done = starts[-1], row * width
            raise self._truncated("run-length encoded") from None
        self._gather(first, starts, chunks, np.frombuffer(heads, dtype=np.uint32 if heads.itemsize == 4 else np.uint64))
        self.pos, self.done = pos, row * width

    def _gather(self, first: int, starts: list[int], chunks: list[int], heads: np.ndarray) -> None:
        """Expand the walked scanlines first, first + 1, ... into self.out, a block at a time.

        Within a block the source offset of every output byte is a cumulative sum: +1 inside
        a literal chunk, +0 inside a run, and a jump to the chunk's first value byte at the
        start of each chunk.
        """
        src, width, count = self.src, self.length, len(starts) - 1
        step = max(1, _BLOCK_BYTES // (4 * width))
        for b0 in range(0, count, step):
            b1 = min(count, b0 + step)
            a = starts[b0]
            head = heads[chunks[b0] : chunks[b1]].astype(np.int64) - a
            code = src[head + a].astype(np.int32)
            literal = code <= 128
            length = np.where(literal, code, code - 128)
            begin = head + 1  # first value byte, relative to a
            last = begin + (length - 1) * literal  # source of each chunk's last output byte
            step_in = np.repeat(literal.astype(np.int32), length)
            out_start = np.cumsum(length) - length
            step_in[out_start] = begin - np.concatenate(([0], last[:-1]))
            source = np.cumsum(step_in, dtype=np.int64 if starts[b1] - a >= 2**31 else np.int32)
            planes = src[a : starts[b1]][source]
            target = self.out[(first + b0) * width : (first + b1) * width].reshape(b1 - b0, width, 4)
            target[...] = planes.reshape(b1 - b0, 4, width).transpose(0, 2, 1)

    # ----- flat and pre-1991 run-length scanlines
    def _old_style(self) -> None:
        """Decode old-style scanlines until the image is complete or a new-style one begins.

        Windows of 4-byte groups are expanded at once (:meth:`_old_window`) up to the first
        group whose meaning depends on where a scanline ends (a repeat crossing a scanline
        end, a repeat after a repeat that completed a scanline, the first pixel, a new-style
        start); such groups go one by one through :meth:`_old_groups`, a transcription of
        ``oldreadcolrs``. The window shrinks where such groups are frequent.
        """
        total = self.scanlines * self.length
        done, pos, shift, window, one_by_one = self.done, self.pos, 0, min(256, _OLD_WINDOW), 64
        while done < total:
            groups = min((len(self.data) - pos) // 4, window)
            if groups == 0:
                self.done, self.pos = done, pos
                raise self._truncated("flat/old-style")
            g = self.src[pos : pos + 4 * groups].reshape(groups, 4)
            used, done, shift, more = self._old_window(g, done, shift)
            if more and used < groups:
                if used < 16:  # special groups are dense here: walk longer stretches one by one
                    one_by_one = min(2 * one_by_one, 1 << 14)
                    g = self.src[pos : pos + 4 * min((len(self.data) - pos) // 4, used + one_by_one)].reshape(-1, 4)
                else:
                    one_by_one = 64
                taken, done, shift, more = self._old_groups(g, used, min(len(g), used + one_by_one), done, shift)
                window = min(max(64, 2 * used), _OLD_WINDOW)
                used = taken
            elif used == groups:
                window = min(2 * window, _OLD_WINDOW)
            pos += 4 * used
            if not more:
                break
        self.done, self.pos = done, pos

    def _old_window(self, g: np.ndarray, done: int, shift: int) -> tuple[int, int, int, bool]:
        """Expand the longest prefix of groups g that needs no scanline bookkeeping.

        Returns (groups used, pixels done, repeat shift, whether old-style groups may follow).
        """
        width, total, groups = self.length, self.scanlines * self.length, len(g)
        repeat = (g[:, 0] == 1) & (g[:, 1] == 1) & (g[:, 2] == 1)
        if not repeat.any():  # flat pixels: only new-style starts can interrupt them
            first, more = min(groups, total - done), True
            if self.rle_ok:
                starts = np.arange((-done) % width, first, width)
                looks = (g[starts, 0] == 2) & (g[starts, 1] == 2) & (g[starts, 2] < 128)
                if looks.any():
                    first, more = int(starts[np.argmax(looks)]), False
            self.out[done : done + first] = g[:first]
            done += first
            return first, done, 0 if first else shift, more and done < total
        index = np.arange(groups)
        last_plain = np.maximum.accumulate(np.where(repeat, -1, index))
        run = index - last_plain - 1 + np.where(last_plain < 0, shift // 8, 0)  # k-th repeat in a row
        exponent = g[:, 3].astype(np.int64)
        shifted = np.where(run >= 4, np.where(exponent > 0, total + 1, 0), exponent << (8 * np.clip(run, 0, 3)))
        count = np.where(repeat, shifted, 1)
        end = done + np.cumsum(count)
        start = end - count
        filling = repeat & (count > 0)
        completes = filling & (end % width == 0)
        special = filling & ((start // width != (end - 1) // width) | (end > total) | (start == 0))
        special[1:] |= repeat[1:] & completes[:-1]  # Radiance restarts the shift on the next scanline
        special |= start >= total
        if self.rle_ok:
            special |= (
                ~repeat & (start % width == 0) & (g[:, 0] == 2) & (g[:, 1] == 2) & (g[:, 2] < 128)
            )
        first = int(np.argmax(special)) if special.any() else groups
        if first:
            out32 = self.out.view(np.uint32).reshape(-1)
            values = np.ascontiguousarray(g[:first]).view(np.uint32).reshape(-1)
            copies = repeat[:first] & (count[:first] > 0)
            if copies.any():
                source = last_plain[:first]
                previous = out32[done - 1] if done else np.uint32(0)  # a leading repeat: the pixel before
                values = np.where(copies, np.where(source >= 0, values[np.maximum(source, 0)], previous), values)
            produced = int(end[first - 1]) - done
            out32[done : done + produced] = np.repeat(values, count[:first])
            done += produced
            last = first - 1
            shift = 8 * (int(run[last]) + 1) if repeat[last] and not completes[last] else 0
        more = done < total and not (
            first < groups and self.rle_ok and not repeat[first] and done % width == 0 and g[first, 0] == 2
            and g[first, 1] == 2 and g[first, 2] < 128
        )
        return first, done, shift, more

    def _old_groups(self, g: np.ndarray, i0: int, i1: int, done: int, shift: int) -> tuple[int, int, int, bool]:
        """Groups g[i0:i1] one at a time, as color.c ``oldreadcolrs``; same return as _old_window."""
        out32 = self.out.view(np.uint32).reshape(-1)
        values = np.ascontiguousarray(g[i0:i1]).view(np.uint32).reshape(-1).tolist()
        width, total = self.length, self.scanlines * self.length
        for i, (r, gr, b, e) in enumerate(g[i0:i1].tolist(), start=i0):
            if done == total:
                return i, done, shift, False
            if r == 1 and gr == 1 and b == 1:
                count = e << min(shift, 64)  # any non-zero count << 64 exceeds a scanline
                if count:
                    if done == 0:
                        raise BadInputError(self.path, "corrupt RGBE data: run-length repeat before the first pixel")
                    take = min(count, width - done % width)
                    out32[done : done + take] = out32[done - 1]
                    done += take
                    if done % width == 0:  # scanline complete: the next one starts afresh
                        shift = 0
                        continue
                shift += 8
            else:
                if self.rle_ok and done % width == 0 and r == 2 and gr == 2 and b < 128:
                    return i, done, shift, False  # a new-style scanline starts here
                out32[done] = values[i - i0]
                done += 1
                shift = 0
        return i1, done, shift, done < total


def _smallest_encoding(length: int) -> int:
    """Fewest bytes any scanline of ``length`` pixels can take: old-style, a pixel or repeat
    groups (k groups repeat up to 256**k - 1 pixels); new-style, 4 + 4·2·ceil(length/127)."""
    groups = 1
    while 256**groups - 1 < length:
        groups += 1
    smallest = 4 * groups
    if _RLE_MIN_WIDTH <= length <= _RLE_MAX_WIDTH:
        smallest = min(smallest, 4 + 8 * -(-length // 127))
    return smallest
