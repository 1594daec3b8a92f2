"""A self-contained HTML page that renders an SHRM [RH02] live in WebGL2: ``shrm view``.

:func:`build_view` gathers the page's data (:class:`ViewPage`): the viewer ``render/webgl/view.js``
and its GLSL ES 3.00 shaders ([WebGL2], [GLSLES3]; package data inlined: no network, it works from
``file://``), the SHRM's coefficient maps as a half-float atlas, the background, the mesh and a
still PNG for browsers without WebGL2; :func:`page_html` writes a whole page, :func:`view_fragment`
one to embed. The shaders draw ``distant`` ([RH02] eq. 12) and ``perpixel`` ([RH02] eq. 8) as
``shrm render`` does (``render.shader``); maps that do not fit the page's budget (:class:`ViewBudget`)
are reduced by :func:`fit_coefficients`, with a note. The page: ``data_specs/view_html.md``.
"""

from __future__ import annotations

import base64
import html
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from scipy import sparse

from .._version import __version__
from ..analysis.lights import LightSet
from ..analysis.shrm import SHRM
from ..brdf_io.atomic import atomic_path
from ..brdf_io.env_rotation import env_rotation_matrix
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_corners, bilinear_lookup, row_edges_cos
from .brdf_glsl import TABLE_SHADER, BrdfTable, brdf_shader_for, choose_table, light_shading, lights_glsl_parts
from .camera import Camera, orthonormal_frame
from .cpu_reference import shade, sphere_geometry
from .defaults import DEFAULT_PAGE_BYTES, DEFAULT_VIEW, STILL_RENDERERS, VIEW_MODES  # numpy-free home (CLI parsers)
from .defaults import DEFAULT_VIEW_MESH as DEFAULT_MESH
from .mesh import Mesh, load_mesh, make_mesh
from .offscreen import probe_offscreen
from .output import TONE_MAPS, composite, environment_background, to_8bit
from .pipeline import render_frames
from .preview import png_bytes, preview_exposure, unit_mesh
from .shader import atlas_layout, coefficient_atlas

__all__ = [
    "VIEW_MODES",
    "DEFAULT_MESH",
    "DEFAULT_VIEW",
    "CAMERA_DISTANCE",
    "CAMERA_MARGIN",
    "STILL_RENDERERS",
    "ViewBudget",
    "CoefficientFit",
    "ViewPage",
    "PageEnvironment",
    "page_camera",
    "fit_coefficients",
    "build_view",
    "view_fragment",
    "page_html",
    "view_html",
    "write_view",
    "webgl_sources",
    "stored_lights",
]

#: The camera: eye at this distance from the origin (the mesh is in the unit sphere) ...
CAMERA_DISTANCE = 3.0
#: ... and at zoom 1 the vertical field of view is tangent to a sphere of this radius.
CAMERA_MARGIN = 1.15
#: Elevations are clamped to ±this (the image up is +z).
MAX_ELEVATION = 89.0
#: Half floats: coefficients are multiplied by a power of two that brings their largest
#: magnitude to at most this (the largest half float is 65504).
HALF_TARGET = 32768.0

_WEBGL_DIR = "webgl"
_SHADER_SUFFIXES = (".glsl", ".vert", ".frag")


@dataclass(frozen=True)
class ViewBudget:
    """Size limits of a page (``data_specs/view_html.md``, Size budget).

    Attributes
    ----------
    page_bytes
        The whole HTML page, UTF-8 (default 8 MiB). The coefficient maps get what the rest
        leaves.
    mesh_bytes
        Raw vertex and index data of the mesh (float32 positions and normals, uint16/uint32
        indices; default 1 MiB, about 45 000 triangles); larger meshes are decimated.
    env_rows
        Rows of the background environment (halved until at most this; default 256).
    still_size
        Width and height of the still image in pixels (default 384).
    max_edge
        Largest edge of the coefficient atlas in texels (default 2048, the WebGL2 minimum of
        MAX_TEXTURE_SIZE, so that every WebGL2 implementation can hold it).
    min_rows
        The coefficient maps are never halved below this many rows (default 8).
    brdf_bytes
        The table of a measured BRDF that shades the lights (base64 of half floats; default
        1.5 MiB, at most a quarter of ``page_bytes``): the finest grid within it whose error meets
        the target, or the coarsest (``render.brdf_glsl.choose_table``).
    """

    page_bytes: int = DEFAULT_PAGE_BYTES
    mesh_bytes: int = 1 << 20
    env_rows: int = 256
    still_size: int = 384
    max_edge: int = 2048
    min_rows: int = 8
    brdf_bytes: int = 3 << 19

    def __post_init__(self) -> None:
        for name, lo in (("page_bytes", 64 << 10), ("mesh_bytes", 4096), ("env_rows", 2), ("still_size", 16),
                         ("max_edge", 64), ("min_rows", 2), ("brdf_bytes", 4096)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < lo:
                raise BadInputError(None, f"ViewBudget.{name} must be an integer >= {lo}, got {value!r}")


@dataclass(frozen=True, eq=False)
class CoefficientFit:
    """What :func:`fit_coefficients` kept.

    Attributes
    ----------
    coeffs
        float32 ((P+1)², h, w, 3): the coefficient maps the page stores (before half rounding).
    P
        The view order kept.
    source_shape
        (P, H, W) of the SHRM given.
    added_rel_rms
        Estimated relative RMS error the reduction adds over all (R, V) pairs (0 when nothing
        was reduced): sqrt(error energy / energy) of the maps, the error energy being the
        squared difference between the bilinear lookups of the kept maps and of the given ones,
        integrated over R (equal-area samples), plus the whole energy of the view bands dropped
        (the real SH are orthonormal in V, so these add up over V).
    """

    coeffs: np.ndarray
    P: int
    source_shape: tuple[int, int, int]
    added_rel_rms: float = 0.0

    @property
    def reduced(self) -> bool:
        return (self.P, self.coeffs.shape[1], self.coeffs.shape[2]) != self.source_shape


@dataclass(frozen=True, eq=False)
class PageEnvironment:
    """One environment of a page as the page holds it (for CPU references of its image).

    Attributes
    ----------
    name
        The environment's name.
    coeffs
        float32 ((P+1)², h, w, 3): its coefficient maps as stored (half rounding and scale undone).
    env_radiance
        float32 (h, w, 3): its background as stored, or None.
    fit
        The :class:`CoefficientFit` of the budget rule for it.
    """

    name: str
    coeffs: np.ndarray
    env_radiance: np.ndarray | None
    fit: CoefficientFit


@dataclass(frozen=True, eq=False)
class ViewPage:
    """A page's content: the JSON document the viewer reads and the still image.

    Attributes
    ----------
    data
        The JSON document (``data_specs/view_html.md``), base64 payloads included.
    still_png
        PNG of the initial view shown where WebGL2 is missing (empty when ``still="none"``).
    still_renderer
        Which renderer made it (``cpu-reference``, ``opengl (...)``, ``given``, ``none``).
    notes
        Visible notes: reductions to fit the budget, mesh decimation, still-image limits.
    coeffs
        float32 ((P+1)², h, w, 3): the coefficient maps exactly as the page holds them
        (half-float rounding and scale undone), for comparisons.
    env_radiance
        float32 (h, w, 3): the background exactly as the page holds it, or None.
    mesh
        The mesh the page draws (after decimation).
    fit
        The :class:`CoefficientFit` of the budget rule.
    title
        Page title.
    environments
        Every environment the page switches between (the first is ``coeffs``, ``env_radiance`` and
        ``fit`` above), as :class:`PageEnvironment`; one entry for a page of one environment.
    """

    data: dict[str, Any]
    still_png: bytes
    still_renderer: str
    notes: tuple[str, ...]
    coeffs: np.ndarray
    env_radiance: np.ndarray | None
    mesh: Mesh
    fit: CoefficientFit
    title: str
    sources: dict[str, str] = field(default_factory=dict, repr=False)
    environments: tuple[PageEnvironment, ...] = ()

    @property
    def P(self) -> int:
        return self.fit.P

    def stored_shrm(self, source: SHRM, index: int = 0) -> SHRM:
        """An SHRM of the coefficients as stored (for the CPU reference of the page's image), with
        ``source``'s lights (the page holds their samples exactly, float32); ``index``: which of the
        page's :attr:`environments` (``source`` is the SHRM it was made from)."""
        stored = self.environments[index] if self.environments else PageEnvironment(
            "", self.coeffs, self.env_radiance, self.fit)
        return SHRM(F=source.F, P=stored.fit.P, coeffs=stored.coeffs, tolerance=source.tolerance,
                    eps=dict(source.eps), meta=dict(source.meta), lights=source.lights if source.has_lights else None,
                    brdf=source.lights_brdf() if source.has_lights else None)


# ------------------------------------------------------------------------------------------
# camera
# ------------------------------------------------------------------------------------------


def page_camera(
    azimuth: float, elevation: float, zoom: float = 1.0, width: int = 1, height: int = 1
) -> Camera:
    """The perspective camera of the page for a view (``view.js`` ``pageCamera``).

    The eye is at :data:`CAMERA_DISTANCE` along v = (cos e cos a, cos e sin a, sin e) (a =
    ``azimuth``, e = ``elevation`` in degrees, e clamped to ±89°), looking at the origin, image
    up from +z; tan(fov_y / 2) = tan(asin(:data:`CAMERA_MARGIN` / distance)) / ``zoom``, and ×
    height/width for a portrait canvas (so the sphere fits the narrower side).
    """
    if not (math.isfinite(azimuth) and math.isfinite(elevation) and math.isfinite(zoom) and zoom > 0):
        raise BadInputError(None, f"view must be finite with zoom > 0, got {azimuth}, {elevation}, {zoom}")
    a = math.radians(azimuth)
    e = math.radians(min(max(elevation, -MAX_ELEVATION), MAX_ELEVATION))
    view = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    forward, right, up = orthonormal_frame(view, np.array([0.0, 0.0, 1.0]))
    t = math.tan(math.asin(CAMERA_MARGIN / CAMERA_DISTANCE)) / zoom
    if width < height:
        t *= height / width
    return Camera(CAMERA_DISTANCE * view, forward, right, up, "perspective", fov_y=2.0 * math.atan(t))


# ------------------------------------------------------------------------------------------
# the budget rule for the coefficient maps
# ------------------------------------------------------------------------------------------


def _overlap(src: np.ndarray, dst: np.ndarray) -> sparse.csr_matrix:
    """(len(dst)−1, len(src)−1) matrix of the fraction of each destination interval covered by
    each source interval; ``src`` and ``dst`` are increasing edges of the same range."""
    lo = np.maximum(dst[:-1, None], src[None, :-1])
    hi = np.minimum(dst[1:, None], src[None, 1:])
    m = np.maximum(hi - lo, 0.0) / (dst[1:] - dst[:-1])[:, None]
    return sparse.csr_matrix(m)


def _area_resample(maps: np.ndarray, h: int, w: int, chunk: int = 16) -> np.ndarray:
    """(n, H, W, 3) lat-long maps → (n, h, w, 3): each new pixel the solid-angle-weighted mean of
    the old pixels it overlaps (rows weighted in 1 − cos θ, columns in φ)."""
    n, H, W, _ = maps.shape
    # in float32, the maps' type (means of a few texels): half the memory traffic of float64
    rows = _overlap(1.0 - row_edges_cos(H), 1.0 - row_edges_cos(h)).astype(np.float32)  # (h, H)
    cols = _overlap(np.linspace(0.0, 1.0, W + 1), np.linspace(0.0, 1.0, w + 1)).astype(np.float32)  # (w, W)
    out = np.empty((n, h, w, 3), np.float32)
    for s in range(0, n, chunk):
        block = np.asarray(maps[s:s + chunk], np.float32)
        k = block.shape[0]
        by_row = rows @ np.moveaxis(block, 1, 0).reshape(H, -1)  # (h, k·W·3)
        by_row = np.moveaxis(by_row.reshape(h, k, W, 3), 2, 0).reshape(W, -1)  # (W, h·k·3)
        both = (cols @ by_row).reshape(w, h, k, 3)
        out[s:s + k] = np.transpose(both, (2, 1, 0, 3))
    return out


def _sphere_samples(n: int) -> np.ndarray:
    """n unit vectors of a Fibonacci lattice: equal-area samples of the sphere, (n, 3)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k
    r = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def _lookup_matrix(dirs: np.ndarray, height: int, width: int) -> sparse.csr_matrix:
    """(N, H·W) sparse matrix of the bilinear lookup (``brdf_io.latlong.bilinear_lookup``) of an
    H × W lat-long map at unit vectors (N, 3): four weights per row, summing to 1."""
    y0, y1, x0, x1, fy, fx = bilinear_corners(dirs, height, width)
    cols = np.stack([y0 * width + x0, y0 * width + x1, y1 * width + x0, y1 * width + x1], axis=1)
    weights = np.stack([(1 - fy) * (1 - fx), (1 - fy) * fx, fy * (1 - fx), fy * fx], axis=1)
    rows = np.repeat(np.arange(len(dirs)), 4)
    return sparse.csr_matrix((weights.ravel(), (rows, cols.ravel())), shape=(len(dirs), height * width))


def _lookup(maps: np.ndarray, dirs: np.ndarray, chunk: int = 16) -> np.ndarray:
    """Bilinear lookups (N, n, 3) float32 of (n, h, w, 3) maps at unit vectors (N, 3): one sparse
    product per chunk of maps laid out (h·w, k·3)."""
    n, h, w, _ = maps.shape
    matrix = _lookup_matrix(dirs, h, w)
    out = np.empty((len(dirs), n, 3), np.float32)
    for s in range(0, n, chunk):
        block = np.ascontiguousarray(np.moveaxis(maps[s:s + chunk], 0, 2)).reshape(h * w, -1)
        out[:, s:s + chunk] = (matrix @ block).reshape(len(dirs), -1, 3)
    return out


def _squared_difference(maps: np.ndarray, dirs: np.ndarray, given: np.ndarray, chunk: int = 2048) -> float:
    """Σ over directions, maps and channels of (lookup of ``maps`` at ``dirs`` − ``given``)², a chunk of
    directions at a time: the (N, n, 3) lookups of the whole set and their difference are not held
    (2 × 18 MB for a P = 18 SHRM at 4096 directions)."""
    total = 0.0
    for s in range(0, len(dirs), chunk):
        diff = _lookup(maps, dirs[s:s + chunk]) - given[s:s + chunk]
        total += float(np.einsum("snc,snc->", diff, diff, dtype=np.float64))
    return total


def _atlas_fits(P: int, h: int, w: int, max_bytes: int, max_edge: int) -> bool:
    cols, rows = atlas_layout((P + 1) ** 2)
    return rows * h * cols * w * 6 <= max_bytes and max(rows * h, cols * w) <= max_edge


def fit_coefficients(
    coeffs: np.ndarray, P: int, max_bytes: int, *, max_edge: int = 2048, min_rows: int = 8, samples: int = 4096
) -> CoefficientFit:
    """The SHRM's coefficient maps at the (rows, P) of least estimated error within ``max_bytes``:
    the page's budget rule (the maps get what the rest of :attr:`ViewBudget.page_bytes` leaves;
    the page states a reduction in a visible note).

    The maps ((P+1)², H, W, 3) are stored as a half-float RGB atlas (6 bytes a texel, tiles as
    (:func:`~shrmkit.render.shader.coefficient_atlas`) whose edges must not exceed ``max_edge``. Candidates:
    for each P' ≤ P, the largest number of rows h ≤ H (at least ``min_rows``, width in the
    same proportion) whose atlas fits, the maps resampled to it by solid-angle-weighted area
    means. Each candidate's error energy (:class:`CoefficientFit`) is estimated on ``samples``
    equal-area directions R (a Fibonacci lattice): the squared difference of the bilinear
    lookups of the resampled and the given maps, plus the energy of the dropped maps (the real
    SH are orthonormal in V); the least wins, ties to the larger P'. Candidates are tried from
    P' = P down and the search stops at the first whose dropped energy alone is no less than the
    best error found (it and every smaller P' lose). Nothing is computed beyond a size check
    when the maps fit as they are.

    Raises
    ------
    BadInputError
        When not even one map of ``min_rows`` rows fits.
    """
    n, H, W, _ = coeffs.shape
    if n != (P + 1) ** 2:
        raise ValueError(f"coeffs must have (P+1)^2 = {(P + 1) ** 2} maps, got {n}")
    source = (P, H, W)

    def width(h: int) -> int:
        return max(1, round(h * W / H))

    def rows_for(p: int) -> int:
        cols, rows = atlas_layout((p + 1) ** 2)
        h = min(H, int(math.sqrt(max_bytes / (6.0 * cols * rows * W / H))) + 1, max_edge // rows)
        while h > 0 and not _atlas_fits(p, h, width(h), max_bytes, max_edge):
            h -= 1
        return h

    if _atlas_fits(P, H, W, max_bytes, max_edge):
        return CoefficientFit(np.asarray(coeffs, np.float32), P, source)
    dirs = _sphere_samples(samples)
    given = _lookup(coeffs, dirs)
    weight = 4.0 * np.pi / samples
    energy = weight * np.einsum("snc,snc->n", given, given, dtype=np.float64)
    total = float(energy.sum())
    best: tuple[float, int, np.ndarray] | None = None
    for p in range(P, -1, -1):
        h = rows_for(p)
        if h < min_rows:
            continue
        m = (p + 1) ** 2
        dropped = float(energy[m:].sum())  # a lower bound of this candidate's error, growing as p falls
        if best is not None and dropped >= best[0]:
            break  # neither this P' nor any smaller one can win (ties go to the larger P')
        if h >= H:
            maps, err = np.asarray(coeffs[:m], np.float32), dropped
        else:
            maps = _area_resample(coeffs[:m], h, width(h))
            err = weight * _squared_difference(maps, dirs, given[:, :m]) + dropped
        if best is None or err < best[0]:
            best = (err, p, maps)
        if h >= H:
            break  # a smaller P' at full resolution only drops more
    if best is None:
        raise BadInputError(None, f"the SHRM does not fit the page budget: even one {min_rows}-row map "
                            f"needs more than {max_bytes} bytes")
    err, p, maps = best
    rel = math.sqrt(err / total) if total > 0 else 0.0
    return CoefficientFit(np.ascontiguousarray(maps), p, source, rel)


# ------------------------------------------------------------------------------------------
# payloads
# ------------------------------------------------------------------------------------------


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def _b64_len(n_bytes: int) -> int:
    return 4 * ((n_bytes + 2) // 3)


def _half(values: np.ndarray) -> tuple[np.ndarray, float]:
    """(little-endian float16 values × scale, scale): scale a power of two bringing the largest
    magnitude to at most :data:`HALF_TARGET` (and at most 2^64)."""
    peak = float(np.max(np.abs(values))) if values.size else 0.0
    scale = 2.0 ** math.floor(math.log2(HALF_TARGET / peak)) if peak > 0 and math.isfinite(peak) else 1.0
    # at most 2^64: maps that are all but zero (a map whose light took everything, filled with
    # float32's tiny) stay finite in float32 and round to zero
    scale = min(scale, 2.0**64)
    scaled = (np.asarray(values, np.float64) * scale).astype("<f2")
    return scaled, scale


def _page_mesh(mesh: Mesh, max_bytes: int) -> tuple[Mesh, str | None]:
    """``mesh`` in the unit sphere, decimated (VTK quadric decimation) until its arrays fit."""
    mesh = unit_mesh(mesh)
    if _mesh_bytes(len(mesh.vertices), mesh.n_triangles) <= max_bytes:
        return mesh, None
    import pyvista as pv  # optional heavy dependency (VTK): only for meshes over the budget

    source = mesh.n_triangles
    current = mesh
    for _ in range(6):
        # vertices ≈ triangles / 2 on a closed mesh: 12 + 6 (or 12) bytes per triangle
        target = max(16, int(max_bytes / 26))
        if current.n_triangles <= target:
            target = int(current.n_triangles * 0.8)
        cells = np.hstack([np.full((current.n_triangles, 1), 3), current.faces]).ravel()
        poly = pv.PolyData(current.vertices, cells)
        out = poly.decimate(1.0 - target / current.n_triangles)
        faces = np.asarray(out.regular_faces, dtype=np.int64)
        # quadric placement may move vertices a little out of the unit sphere: normalize again
        current = make_mesh(np.asarray(out.points, np.float64), faces, name=mesh.name, normalize=True)
        if _mesh_bytes(len(current.vertices), current.n_triangles) <= max_bytes:
            break
    if _mesh_bytes(len(current.vertices), current.n_triangles) > max_bytes:
        raise BadInputError(mesh.name, f"the mesh could not be decimated to {max_bytes} bytes "
                            f"({current.n_triangles} triangles left)")
    note = (f"mesh {mesh.name}: decimated from {source} to {current.n_triangles} triangles "
            f"(quadric decimation) to fit {max_bytes / 2**20:.2f} MiB of mesh data")
    return current, note


def _mesh_bytes(n_vertices: int, n_triangles: int) -> int:
    index = 2 if n_vertices <= 65535 else 4
    return n_vertices * 24 + n_triangles * 3 * index


def _mesh_payload(mesh: Mesh) -> dict[str, Any]:
    nv = len(mesh.vertices)
    index_type = "uint16" if nv <= 65535 else "uint32"
    centre = 0.5 * (mesh.vertices.min(axis=0) + mesh.vertices.max(axis=0))
    return {
        "name": mesh.name,
        "vertices": nv,
        "triangles": mesh.n_triangles,
        "center": [float(x) for x in centre],
        "positions": _b64(mesh.vertices.astype("<f4")),
        "normals": _b64(mesh.normals.astype("<f4")),
        "index_type": index_type,
        "indices": _b64(mesh.faces.astype("<u2" if index_type == "uint16" else "<u4")),
    }


def _env_payload(env: EnvironmentMap, max_rows: int) -> tuple[dict[str, Any], np.ndarray]:
    radiance = np.asarray(env.radiance, np.float32)
    H, W, _ = radiance.shape
    if H > max_rows:
        radiance = _area_resample(radiance[None], max_rows, max(1, round(max_rows * W / H)))[0]
    half, scale = _half(radiance)
    h, w, _ = radiance.shape
    stored = (half.astype(np.float32) / np.float32(scale)).astype(np.float32)
    return {"name": env.name, "height": h, "width": w, "scale": scale, "texels": _b64(half)}, stored


def stored_lights(data: dict[str, Any]) -> LightSet | None:
    """The light samples a page's document holds (``data["lights"]``; None without), as a
    :class:`~shrmkit.analysis.lights.LightSet` (float32 values, one light per sample), for CPU
    references of the page's image."""
    doc = data.get("lights")
    if not doc:
        return None
    u = doc["uniforms"]
    directions = np.reshape(np.asarray(u["shrmLightDir"]["value"], np.float64), (-1, 3))
    power = np.reshape(np.asarray(u["shrmLightPower"]["value"], np.float64), (-1, 3))
    return LightSet(directions, power, np.arange(len(directions)))


def _lights_payload(shrm: SHRM, budget: ViewBudget) -> tuple[dict[str, Any] | None, str | None]:
    """The page's ``lights`` entry (``data_specs/view_html.md``) and a note, or (None, None).

    The samples and the BRDF's parameters as the uniforms of ``render/webgl/lights.glsl`` and the
    BRDF's GLSL (``render.brdf_glsl``: the same files as the desktop shaders); a measured BRDF's
    table as half floats within ``budget.brdf_bytes``, its error measured on what the page holds.
    """
    if not shrm.has_lights:
        return None, None
    brdf = shrm.lights_brdf()
    shader = brdf_shader_for(brdf)
    table_doc, note = None, None
    if shader is TABLE_SHADER:
        share = min(budget.brdf_bytes, budget.page_bytes // 4)
        max_texels = max(8, share // 8)  # 6 bytes of half floats a texel, × 4/3 in base64

        def halves(table: BrdfTable) -> BrdfTable:
            half, scale = _half(table.values)
            return table.with_values((half.astype(np.float32) / np.float32(scale)).astype(np.float32), scale)

        assert shrm.lights is not None  # has_lights
        table, error = choose_table(brdf, shrm.lights, max_view_deg=float(shrm.meta.get("max_view_deg", 80.0)),
                                    max_texels=max_texels, store=halves)
        lights = light_shading(shrm, table=table, measure=False)
        half = (table.atlas()).astype("<f2")  # values × scale, exact in half floats (rounded above)
        nh, nd, npd = table.shape
        table_doc = {"shape": [nh, nd, npd], "cols": table.cols, "rows": half.shape[0] // nd,
                     "periodic": bool(table.periodic), "scale": table.scale, "texels": _b64(half),
                     "rel_rms": error["rel_rms"], "worst_band_rel_rms": error["worst_band_rel_rms"],
                     "max_view_deg": error["max_view_deg"], "target": error["target"]}
        note = (f"lights shaded with a {nh}x{nd}x{npd} table of the measured BRDF (theta_h, theta_d, phi_d): its "
                f"error on the lights' reflection {100 * error['rel_rms']:.2g} % relative RMS, worst view band "
                f"{100 * error['worst_band_rel_rms']:.2g} % (to {error['max_view_deg']:g} degrees)")
    else:
        lights = light_shading(shrm)
    assert shrm.lights is not None and lights is not None  # has_lights: light_shading has lights to shade
    doc = {
        "count": len(shrm.lights), "lights": len(shrm.lights.lights) or len(set(shrm.lights.light.tolist())),
        "model": shader.name, "glsl": list(lights_glsl_parts(shader)), "defines": dict(lights.defines),
        "uniforms": {name: {"type": kind, "value": [float(np.float32(v)) for v in values]}
                     for name, (kind, values) in lights.uniforms.items()},
        "table": table_doc,
    }
    return doc, note


# ------------------------------------------------------------------------------------------
# the still image
# ------------------------------------------------------------------------------------------


def _chunked(radiance, chunk: int = 8192):
    def evaluate(R: np.ndarray, V: np.ndarray) -> np.ndarray:
        out = np.empty((len(R), 3))
        for s in range(0, len(R), chunk):
            out[s:s + chunk] = radiance(R[s:s + chunk], V[s:s + chunk])
        return out

    return evaluate


def _cpu_radiance(shrm: SHRM, mode: str, camera: Camera, env_rotation: np.ndarray | None = None):
    """B(R, V) of the page's ``mode`` for ``shade`` (which turns R and V by Qᵀ itself): per pixel, or
    the distant view map made for Qᵀ Ṽ, as the shaders."""
    if mode == "perpixel":
        return _chunked(shrm.radiance)
    view_map = shrm.view_map(camera.view_direction(np.zeros(3)), env_rotation=env_rotation)
    if shrm.has_lights:  # the map holds the SHRM part; the lights at each pixel's own V, as the shaders
        return _chunked(lambda R, V: bilinear_lookup(view_map, R) + shrm.light_radiance(R, V))
    return lambda R, V: bilinear_lookup(view_map, R)


def _still(
    shrm: SHRM, env: EnvironmentMap | None, mesh: Mesh, is_sphere: bool, view: dict[str, Any], size: int, how: str
) -> tuple[bytes, str, str | None, str]:
    """PNG of the initial view (the lighting turned by the view's ``env_*`` angles), its renderer, a
    note when it shows less than the page, its mode."""
    mode = view["mode"]
    rotation = env_rotation_matrix(view["env_azimuth"], view["env_elevation"], view["env_roll"])
    q = None if np.array_equal(rotation, np.eye(3)) else rotation
    if how == "none":
        return b"", "none", None, mode
    camera = page_camera(view["azimuth"], view["elevation"], view["zoom"], size, size)
    note = None
    use_gl = how == "gl" or (how == "auto" and not is_sphere)
    if use_gl:
        ok, message = probe_offscreen(timeout=60.0)
        if not ok and how == "gl":
            raise BadInputError(None, f"still image with OpenGL: no offscreen context ({message})")
        if not ok:
            use_gl = False
            note = f"the still image shows the sphere: no offscreen OpenGL to render the mesh ({message})"
    elif not is_sphere:
        note = "the still image shows the sphere (CPU reference renderer), not the mesh"
    if use_gl:
        background = "env" if env is not None and view["background"] else "black"
        try:
            frames, timings = render_frames(
                mesh, shrm, [camera], size=size, mode=mode,
                env_radiance=None if env is None else env.radiance, background=background, fps_frames=0,
                env_rotation=q,
            )
        except ValueError as err:  # a perpixel atlas over the GPU's texture limit (render.shader)
            mode = "distant"
            note = f"the still image is drawn in mode distant ({err})"
            frames, timings = render_frames(
                mesh, shrm, [camera], size=size, mode=mode,
                env_radiance=None if env is None else env.radiance, background=background, fps_frames=0,
                env_rotation=q,
            )
        linear, renderer = frames[0].linear, f"opengl ({timings.backend})"
    else:
        geometry = sphere_geometry(camera, size, size)
        radiance = shade(geometry, _cpu_radiance(shrm, mode, camera, q), env_rotation=q).astype(np.float32)
        if env is not None and view["background"]:
            bg = environment_background(env.radiance, camera, size, size, env_rotation=q)
        else:
            bg = np.zeros((size, size, 3), np.float32)
        linear = composite(radiance, geometry.hit.astype(np.float32), bg)
        renderer = "cpu-reference"
    image = to_8bit(linear, exposure=view["exposure"], curve=view["tone"])
    return png_bytes(image), renderer, note, mode


# ------------------------------------------------------------------------------------------
# the page
# ------------------------------------------------------------------------------------------


def webgl_sources() -> dict[str, str]:
    """The package data of ``render/webgl``: file name → text (the viewer, shaders, style, template)."""
    folder = resources.files(__package__).joinpath(_WEBGL_DIR)
    return {entry.name: entry.read_text(encoding="utf-8") for entry in folder.iterdir()
            if entry.is_file() and entry.name.endswith((".js", ".css", ".html", *_SHADER_SUFFIXES))}


def _check_view(mode: str, tone: str, azimuth: float, elevation: float, zoom: float, exposure: float | None) -> None:
    if mode not in VIEW_MODES:
        raise BadInputError(None, f"view mode must be one of {', '.join(VIEW_MODES)}, got {mode!r}")
    if tone not in TONE_MAPS:
        raise BadInputError(None, f"tone map must be one of {', '.join(TONE_MAPS)}, got {tone!r}")
    for name, value in (("azimuth", azimuth), ("elevation", elevation), ("zoom", zoom)):
        if not isinstance(value, int | float) or not math.isfinite(value):
            raise BadInputError(None, f"{name} must be a finite number, got {value!r}")
    if not 0.25 <= zoom <= 10.0:
        raise BadInputError(None, f"zoom must be in [0.25, 10], got {zoom}")
    if not -MAX_ELEVATION <= elevation <= MAX_ELEVATION:
        raise BadInputError(None, f"elevation must be in [-{MAX_ELEVATION:g}, {MAX_ELEVATION:g}] degrees, "
                            f"got {elevation}")
    if exposure is not None and (not isinstance(exposure, int | float) or not -30.0 <= exposure <= 30.0):
        raise BadInputError(None, f"exposure must be a number of stops in [-30, 30], got {exposure!r}")


def build_view(
    shrm: SHRM,
    env: EnvironmentMap | None = None,
    *,
    mesh: Mesh | str | Path | None = None,
    mode: str = "distant",
    exposure: float | None = None,
    tone: str = "filmic",
    azimuth: float = DEFAULT_VIEW["azimuth"],
    elevation: float = DEFAULT_VIEW["elevation"],
    zoom: float = DEFAULT_VIEW["zoom"],
    background: bool = True,
    budget: ViewBudget | None = None,
    still: str = "auto",
    still_png: bytes | None = None,
    title: str | None = None,
    env_rotation: tuple[float, ...] = (0.0, 0.0, 0.0),
    more: Sequence[tuple[SHRM, EnvironmentMap | None]] = (),
) -> ViewPage:
    """Everything a view page holds, within the size budget.

    Parameters
    ----------
    shrm
        The global SHRM (``analysis.shrm.prefilter``).
    env
        The environment it was prefiltered from, for the background (None: black, no toggle).
    mesh
        A :class:`Mesh`, a path or a built-in spec (default :data:`DEFAULT_MESH`); moved into
        the unit sphere, decimated to ``budget.mesh_bytes``.
    mode, tone, exposure, azimuth, elevation, zoom, background
        The initial view (the URL hash of the page overrides it): render mode (``distant`` or
        ``perpixel``), tone map (``filmic`` or ``srgb``), exposure in stops (None: the
        preview rule, ``render.preview.preview_exposure`` — 0 without ``env``), camera
        (:func:`page_camera`) and whether the environment is drawn behind the object.
    env_rotation
        The lighting's initial rotation, degrees (AZ, EL[, ROLL]) as
        :func:`~shrmkit.brdf_io.env_rotation.env_rotation_matrix` (the page's ``env_azimuth``,
        ``env_elevation``, ``env_roll``; EL in [−90, 90]); the still image shows it too.
    more
        Further (SHRM, environment) pairs the page switches between without reloading (an
        ``environment`` menu and ``env_index`` in the URL); prefiltered from the same BRDF.
        The coefficient budget is shared equally, the backgrounds get at most a quarter of the
        page together (rows halved until they fit). The still image shows the first.
    budget
        Size limits (:class:`ViewBudget`).
    still, still_png
        The still image for browsers without WebGL2: ``still_png`` when given (e.g. a report's
        preview), else rendered by ``still`` — ``"cpu"`` (the CPU reference renderer on the
        analytic sphere), ``"gl"`` (VTK offscreen, the page's mesh), ``"auto"`` (cpu for the
        default sphere, gl for a mesh when an offscreen context exists, else the sphere with a
        note) or ``"none"``.
    title
        Page title (default: "BRDF under ENV" from the SHRM's meta).

    Raises
    ------
    BadInputError
        Bad view values or rotation, a mesh that cannot be loaded or decimated, a budget that
        cannot hold even one small map per environment, an entry of ``more`` that is not an SHRM.
    """
    pairs = _check_pairs(shrm, env, more)
    budget = ViewBudget() if budget is None else budget
    if still not in STILL_RENDERERS:
        raise BadInputError(None, f"still must be one of {', '.join(STILL_RENDERERS)}, got {still!r}")
    view = _initial_view(env, mode, tone, exposure, azimuth, elevation, zoom, background, env_rotation, len(pairs))
    is_sphere = mesh is None
    source_mesh = load_mesh(DEFAULT_MESH if mesh is None else mesh) if not isinstance(mesh, Mesh) else mesh
    notes: list[str] = []
    page_mesh, mesh_note = _page_mesh(source_mesh, budget.mesh_bytes)
    if mesh_note:
        notes.append(mesh_note)
    png, renderer, still_note, still_mode = (
        (bytes(still_png), "given", None, mode) if still_png is not None
        else _still(shrm, env, unit_mesh(source_mesh), is_sphere, view, budget.still_size, still))
    if still_note:
        notes.append(still_note)
    brdf_name = str(shrm.meta.get("brdf", "BRDF"))
    names = [str(s_k.meta.get("environment", e_k.name if e_k is not None else "environment")) for s_k, e_k in pairs]
    title = title or f"{brdf_name} under {names[0]}"
    env_rows = _background_rows(budget, len(pairs))
    entries, stored_envs = _environment_entries(pairs, names, env_rows, budget, notes)
    data = _page_data(title, brdf_name, view, entries, _mesh_payload(page_mesh), renderer, still_mode, notes, budget,
                      env_rows)
    sources = webgl_sources()
    max_bytes = _coefficient_bytes(data, entries, pairs, png, sources, budget)
    stored_pages: list[PageEnvironment] = []
    for entry, (s_k, _), name, env_stored in zip(entries, pairs, names, stored_envs, strict=True):
        entry["shrm"], page = _shrm_payload(s_k, name, env_stored, max_bytes, budget)
        if page.fit.reduced:
            notes.append(("" if len(pairs) == 1 else f"{name}: ") + _reduction_note(s_k, page.fit, budget))
        stored_pages.append(page)
    data["shrm"] = entries[0]["shrm"]
    data["notes"] = notes
    first = stored_pages[0]
    return ViewPage(data, png, renderer, tuple(notes), first.coeffs, first.env_radiance, page_mesh, first.fit, title,
                    sources, tuple(stored_pages))


def _initial_view(env: EnvironmentMap | None, mode: str, tone: str, exposure: float | None, azimuth: float,
                  elevation: float, zoom: float, background: bool, env_rotation: tuple[float, ...], n_envs: int
                  ) -> dict[str, Any]:
    """The page's initial view (checked): camera, exposure in stops (None: the preview rule, 0
    without an environment), mode, tone map, background and the lighting's rotation in degrees."""
    _check_view(mode, tone, azimuth, elevation, zoom, exposure)
    rotation = _check_env_angles(env_rotation)
    if exposure is None:
        exposure = preview_exposure(env) if env is not None else 0.0
    view = {"azimuth": float(azimuth), "elevation": float(elevation), "zoom": float(zoom),
            "exposure": round(float(exposure), 3), "mode": mode, "background": bool(background and env is not None),
            "tone": tone, "env_azimuth": rotation[0], "env_elevation": rotation[1], "env_roll": rotation[2]}
    if n_envs > 1:
        view["env_index"] = 0
    return view


def _page_data(title: str, brdf_name: str, view: dict[str, Any], entries: list[dict[str, Any]],
               mesh: dict[str, Any], renderer: str, still_mode: str, notes: list[str], budget: ViewBudget,
               env_rows: int) -> dict[str, Any]:
    """The page's data document (shrmkit-view version 1, ``data_specs/view_html.md``) before the coefficients:
    the first environment's payloads at the top, every environment's under ``environments``."""
    data: dict[str, Any] = {
        "format": "shrmkit-view",
        "version": 1,
        "title": title,
        "brdf": brdf_name,
        "environment": entries[0]["name"],
        "camera": {"distance": CAMERA_DISTANCE, "margin": CAMERA_MARGIN},
        "view": view,
        "shrm": None,
        "env": entries[0]["env"],
        "mesh": mesh,
        "lights": entries[0]["lights"],
        "still": {"renderer": renderer, "width": budget.still_size, "height": budget.still_size,
                  "view": {**view, "mode": still_mode}},
        "notes": notes,
        "budget": {"page_bytes": budget.page_bytes, "mesh_bytes": budget.mesh_bytes, "env_rows": env_rows},
    }
    if len(entries) > 1:
        data["environments"] = entries  # entries[0]'s payloads are data's own (the first environment)
    return data


def _check_pairs(shrm: SHRM, env: EnvironmentMap | None, more: Sequence[tuple[SHRM, EnvironmentMap | None]]
                 ) -> list[tuple[SHRM, EnvironmentMap | None]]:
    """The page's (SHRM, environment) pairs, the first one first; each must hold an SHRM."""
    pairs = [(shrm, env), *[(s_k, e_k) for s_k, e_k in more]]
    for k, (s_k, _) in enumerate(pairs):
        if not isinstance(s_k, SHRM):
            raise BadInputError(None, f"build_view needs an SHRM (environment {k}), got {type(s_k).__name__}")
    return pairs


def _background_rows(budget: ViewBudget, n_envs: int) -> int:
    """Rows of each background map: ``budget.env_rows``, halved (down to 8) while several
    backgrounds together pass a quarter of the page."""
    env_rows = budget.env_rows
    if n_envs > 1:
        while env_rows > 8 and n_envs * _b64_len(env_rows * 2 * env_rows * 6) > budget.page_bytes // 4:
            env_rows //= 2
    return env_rows


def _environment_entries(pairs: Sequence[tuple[SHRM, EnvironmentMap | None]], names: Sequence[str], env_rows: int,
                         budget: ViewBudget, notes: list[str]) -> tuple[list[dict[str, Any]], list[np.ndarray | None]]:
    """Each environment's page entry (name, background, lights; the SHRM comes later) and the
    background radiance the page stores (None without one); lights' notes go to ``notes``."""
    entries: list[dict[str, Any]] = []
    stored_envs: list[np.ndarray | None] = []
    for (s_k, e_k), name in zip(pairs, names, strict=True):
        env_data, env_stored = (None, None) if e_k is None else _env_payload(e_k, env_rows)
        lights_data, lights_note = _lights_payload(s_k, budget)
        if lights_note:
            notes.append(lights_note if len(pairs) == 1 else f"{name}: {lights_note}")
        entries.append({"name": name, "shrm": None, "env": env_data, "lights": lights_data})
        stored_envs.append(env_stored)
    return entries, stored_envs


def _shrm_placeholder(s_k: SHRM) -> dict[str, Any]:
    """An SHRM entry without texels: what the page holds besides the coefficients is measured with it."""
    return {"F": s_k.F, "P": s_k.P, "source": {"P": s_k.P, "height": s_k.height, "width": s_k.width},
            "height": s_k.height, "width": s_k.width, "cols": 0, "rows": 0, "scale": 1.0,
            "added_rel_rms": 0.0, "texels": ""}


def _coefficient_bytes(data: dict[str, Any], entries: list[dict[str, Any]],
                       pairs: Sequence[tuple[SHRM, EnvironmentMap | None]], png: bytes, sources: dict[str, str],
                       budget: ViewBudget) -> int:
    """Raw bytes each environment's coefficients may take: what the page costs without them is
    measured, the budget rule gets the rest, shared equally (the reduction notes and the numbers of
    the shrm entries are covered by the margin; base64 makes 4 bytes of 3)."""
    for entry, (s_k, _) in zip(entries, pairs, strict=True):
        entry["shrm"] = _shrm_placeholder(s_k)
    data["shrm"] = entries[0]["shrm"]
    fixed = len(_render_page(data["title"], data, png, sources).encode("utf-8"))
    margin = 2048 * len(pairs)
    room = (budget.page_bytes - fixed - margin) // len(pairs)
    max_bytes = (room // 4) * 3
    if max_bytes <= 0:
        raise BadInputError(None, f"the page budget of {budget.page_bytes} bytes is used up before the SHRM "
                            f"({fixed} bytes for the viewer, mesh, background and still image)")
    return max_bytes


def _shrm_payload(s_k: SHRM, name: str, env_stored: np.ndarray | None, max_bytes: int, budget: ViewBudget
                  ) -> tuple[dict[str, Any], PageEnvironment]:
    """One SHRM fitted to ``max_bytes``: its page entry (half-float atlas in base64) and the maps
    the page stores, (n_maps, h, w, 3) float32 as the viewer decodes them."""
    fit = fit_coefficients(s_k.coeffs, s_k.P, max_bytes, max_edge=budget.max_edge, min_rows=budget.min_rows)
    atlas = coefficient_atlas(fit.coeffs)
    half, scale = _half(atlas)
    cols, rows = atlas_layout((fit.P + 1) ** 2)
    h, w = fit.coeffs.shape[1:3]
    stored = (half.astype(np.float32) / np.float32(scale)).astype(np.float32)
    stored_maps = np.stack([stored[(c // cols) * h:(c // cols + 1) * h, (c % cols) * w:(c % cols + 1) * w]
                            for c in range((fit.P + 1) ** 2)])
    entry = {"F": s_k.F, "P": fit.P, "source": {"P": s_k.P, "height": s_k.height, "width": s_k.width},
             "height": h, "width": w, "cols": cols, "rows": rows, "scale": scale,
             "added_rel_rms": fit.added_rel_rms, "texels": _b64(half)}
    return entry, PageEnvironment(name, stored_maps, env_stored, fit)


def _reduction_note(s_k: SHRM, fit: CoefficientFit, budget: ViewBudget) -> str:
    """What the budget cut from an SHRM (texels, view order P) and the estimated added error."""
    H, W = fit.source_shape[1], fit.source_shape[2]
    h, w = fit.coeffs.shape[1:3]
    parts = []
    if (h, w) != (H, W):
        parts.append(f"coefficient maps {H}x{W} -> {h}x{w} texels")
    if fit.P != s_k.P:
        parts.append(f"view order P {s_k.P} -> {fit.P} ({(fit.P + 1) ** 2} of {(s_k.P + 1) ** 2} maps)")
    return (f"reduced to fit the {budget.page_bytes / 2**20:.3g} MiB page budget: " + ", ".join(parts)
            + f"; estimated added error {100 * fit.added_rel_rms:.2g} % relative RMS over all (R, V)")


def _check_env_angles(angles: Any) -> tuple[float, float, float]:
    """The page's lighting rotation (AZ, EL[, ROLL]) in degrees: finite, EL in [−90, 90]."""
    try:
        values = [float(a) for a in angles]
    except (TypeError, ValueError):
        values = []
    if len(values) not in (2, 3) or not all(math.isfinite(v) for v in values):
        raise BadInputError(None, f"env_rotation must be two or three finite angles AZ, EL[, ROLL] in degrees, "
                            f"got {angles!r}")
    if not -90.0 <= values[1] <= 90.0:
        raise BadInputError(None, f"env_rotation: the elevation must be in [-90, 90] degrees, got {values[1]:g}")
    return values[0], values[1], values[2] if len(values) == 3 else 0.0


def _page_document(data: dict[str, Any]) -> dict[str, Any]:
    """The JSON document as the page holds it: with several environments, the first one's payloads
    are not repeated in ``environments[0]`` (the viewer reads them from the document's own keys)."""
    if "environments" not in data:
        return data
    return {**data, "environments": [{"name": data["environments"][0]["name"]}, *data["environments"][1:]]}


def _json_script(doc: Any) -> str:
    """JSON that is safe inside a <script> element."""
    text = json.dumps(doc, separators=(",", ":"), allow_nan=False)
    return text.replace("</", "<\\/").replace("<!--", "<\\!--")


_ID = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,63}$")


def _fragment(title: str, data: dict[str, Any], png: bytes, sources: dict[str, str], element_id: str,
              use_hash: bool) -> str:
    if not _ID.match(element_id):
        raise BadInputError(None, f"element_id must be a letter then letters, digits, '-' or '_', got {element_id!r}")
    shaders = {name: text for name, text in sorted(sources.items()) if name.endswith(_SHADER_SUFFIXES)}
    s = data["shrm"]
    lights = data.get("lights")
    info = (f"F = {s['F']}, P = {s['P']}, maps {s['height']}x{s['width']}, mesh {data['mesh']['triangles']} "
            f"triangles" + (f", {lights['count']} light samples shaded per pixel" if lights else ""))
    notes = "".join(f'<div class="shrm-view-note">{html.escape(n)}</div>' for n in data["notes"])
    still = (f'<img class="shrm-view-fallback" alt="still image of {html.escape(title)}" '
             f'src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">') if png else ""
    return "\n".join([
        f'<style>{sources["view.css"]}</style>',
        f'<div class="shrm-view" id="{element_id}" data-state="loading">',
        f'<canvas class="shrm-view-canvas" aria-label="live view of {html.escape(title)}"></canvas>',
        '<div class="shrm-view-still"><div class="shrm-view-fallback-note"></div>' + still + "</div>",
        f'<div class="shrm-view-info"><span class="shrm-view-title">{html.escape(title)}</span>'
        f'<span class="shrm-view-numbers"> — {html.escape(info)}</span>'
        ' <span class="shrm-view-help">· drag: orbit · Shift+drag: lighting · wheel: zoom · double-click: reset · '
        'click here: fold</span>'
        + notes + "</div>",
        '<div class="shrm-view-ui"></div>',
        "</div>",
        f"<script>window.ShrmViewShaders = window.ShrmViewShaders || {_json_script(shaders)};</script>",
        f"<script>{sources['view.js']}</script>",
        f'<script type="application/json" id="{element_id}-data">{_json_script(_page_document(data))}</script>',
        "<script>(function () { var root = document.getElementById(" + json.dumps(element_id) + ");"
        " var data = JSON.parse(document.getElementById(" + json.dumps(element_id + "-data") + ").textContent);"
        f" window.ShrmView.mount(root, data, {{hash: {'true' if use_hash else 'false'}}}); }})();</script>",
    ])


#: The page template's placeholders, filled in one pass (:func:`_render_page`).
_PLACEHOLDER = re.compile(r"\{\{(VERSION|TITLE|FRAGMENT)\}\}")


def _render_page(title: str, data: dict[str, Any], png: bytes, sources: dict[str, str]) -> str:
    """The page: the template's placeholders replaced in a single pass over the template, so text
    that came from a user (a file named ``{{FRAGMENT}}.hdr``, a title) is never read again as a
    placeholder (successive ``str.replace`` calls pasted the fragment into itself; issue 28)."""
    fragment = _fragment(title, data, png, sources, "shrm-view", True)
    values = {"VERSION": html.escape(__version__), "TITLE": html.escape(title), "FRAGMENT": fragment}
    return _PLACEHOLDER.sub(lambda match: values[match.group(1)], sources["page.html"])


def view_fragment(page: ViewPage, *, element_id: str = "shrm-view", use_hash: bool = False) -> str:
    """The viewer as an HTML fragment to embed in another page (a report): a ``<div
    class="shrm-view" id=element_id>`` (size it with CSS, e.g. ``#id {width: 480px; height:
    480px}``), its style and scripts. Several fragments may share a page (distinct ids);
    ``use_hash`` lets the page's URL hash set this viewer's view (one per page)."""
    return _fragment(page.title, page.data, page.still_png, page.sources or webgl_sources(), element_id, use_hash)


def page_html(page: ViewPage) -> str:
    """The whole self-contained HTML page (the view follows the URL hash).

    Raises ValueError if it exceeds the page budget it was built for (never, by construction).
    """
    text = _render_page(page.title, page.data, page.still_png, page.sources or webgl_sources())
    limit = page.data.get("budget", {}).get("page_bytes")
    size = len(text.encode("utf-8"))
    if limit is not None and size > limit:
        raise ValueError(f"the view page has {size} bytes, over its budget of {limit}")
    return text


def view_html(shrm: SHRM, env: EnvironmentMap | None = None, **kwargs: Any) -> str:
    """``page_html(build_view(shrm, env, **kwargs))``: the page as a string."""
    return page_html(build_view(shrm, env, **kwargs))


def write_view(path: str | Path, text: str) -> Path:
    """Write a page atomically (UTF-8); returns the path."""
    target = Path(path)
    with atomic_path(target) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return target
