"""Shading of the SHRM render modes (``distant``, ``perpixel``, ``kautz-mccool``, ``rsibr``).

Per fragment, after the shared prelude of ``render.glsl``
(N, V, R in the z-up world frame):

- ``distant`` ([RH02] eq. 12): radiance = M(R) with M = Σ B̃_pq Y^r_pq(Ṽ) one lat-long map per
  frame and object, Ṽ the direction from the object's bounding-sphere centre toward the eye,
  computed on the CPU (:func:`distant_update`) and uploaded as a float texture;
- ``perpixel`` ([RH02] eq. 8): radiance = Σ B̃_pq(R) Y^r_pq(V), the 3·(P+1)² scalar maps
  (coefficient c, channel k) packed four to an RGBA texel in one float texture
  (:func:`packed_coefficient_atlas`: scalar map j = 3c + k is component j mod 4 of tile
  t = j div 4, tile t at column (t mod cols)·W, row (t div cols)·H) and Y^r_pq(V) evaluated
  in the shader; ``kautz-mccool`` [KM00] draws the azimuth-free (q = 0) SHRM the same way. Packing
  four channels a texel takes ⌈3(P+1)²/4⌉ fetches per bilinear corner instead of (P+1)² RGB
  ones (48 instead of 64 at P = 3): texel fetches are most of the per-pixel cost of this mode
  on a CPU rasterizer (``benchmarks/render_speed.py``);
- ``rsibr`` [Cabral99]: the distant shader fed, per frame, the spherical-barycentric
  blend of the twelve maps of ``analysis.baselines.rsibr`` (:func:`rsibr_update`).

All maps are looked up with the bilinear lat-long rule of ``render.glsl`` (four ``texelFetch``es).
The SHRM modes clamp the radiance at 0 (``max(shrmRad, 0)`` in the fragment shader, and the
per-frame map of ``distant``), as :meth:`SHRM.radiance` does: the undershoot the prefilter's
window left (``SHRM.meta["negative_after"]``, ``data_specs/shrm_file.md``) never reaches an image.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..analysis.baselines.rsibr import RSIBRMaps, rsibr_from_shrm
from ..analysis.sh import real_sph_harm
from ..analysis.shrm import SHRM
from ._brdf_table import table_covers, theta_d_ranges
from .brdf_glsl import LightShading, light_shading
from .glsl import (
    LATLONG_GLSL,
    Shading,
    check_texture_size,
    fragment_replacements,
    screen_fragment_replacements,
    sh_glsl,
    vertex_replacements,
)
from .mesh import Mesh

_LIGHT_SHADINGS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def cached_light_shading(shrm: SHRM, views: Sequence[tuple[np.ndarray, float]] | None = None
                         ) -> LightShading | None:
    """:func:`~shrmkit.render.brdf_glsl.light_shading` of ``shrm`` for ``views``, made once per SHRM
    object and views (a measured BRDF's table and its error are computed once for the build's
    description and the shaders); the same images as a fresh call.

    ``views`` (``light_shading(views=)``; None: any view, the whole table): a shading made before
    is reused when its table holds every θ_d row these views read (a whole table, or one made for
    views whose rows include theirs, ``_brdf_table.table_covers``); else one is made for them, or,
    when a partial table was made before, the whole table, which then replaces it (at most one
    table per SHRM is kept).
    """
    if not shrm.has_lights:
        return None
    assert shrm.lights is not None  # has_lights
    earlier: LightShading | None = _LIGHT_SHADINGS.get(shrm)
    if earlier is not None:
        theta_d = None if views is None else theta_d_ranges(shrm.lights.directions, views)
        if earlier.table is None or table_covers(earlier.table, theta_d):
            return earlier
        # views its partial table lacks: the whole table from now on, read by any view (an SHRM rendered
        # frame by frame from a moving camera would otherwise keep a new partial table per frame)
        views = None
    shading = light_shading(shrm, views=views)
    assert shading is not None  # has_lights
    _LIGHT_SHADINGS[shrm] = shading
    return shading

__all__ = [
    "atlas_layout",
    "coefficient_atlas",
    "packed_tiles",
    "packed_coefficient_atlas",
    "shrm_fragment_replacements",
    "distant_shading",
    "distant_update",
    "perpixel_shading",
    "rsibr_shading",
    "rsibr_update",
    "cached_light_shading",
]

_LOOKUP = LATLONG_GLSL + """
void shrm_setup(vec3 d, out ivec4 idx, out vec2 f) {
  latlong_setup(d, SHRM_H, SHRM_W, idx, f);
}
"""


def atlas_layout(n_tiles: int) -> tuple[int, int]:
    """(columns, rows) of the tile grid holding ``n_tiles`` coefficient maps."""
    cols = max(1, math.ceil(math.sqrt(n_tiles)))
    rows = math.ceil(n_tiles / cols)
    return cols, rows


def coefficient_atlas(coeffs: np.ndarray) -> np.ndarray:
    """Tile the (n, H, W, 3) coefficient maps into one float32 (rows·H, cols·W, 3) image.

    Tile c sits at rows [r·H, (r+1)·H), columns [k·W, (k+1)·W) with k = c mod cols,
    r = c div cols (:func:`atlas_layout`); texture row 0 is the first array row.
    """
    n, h, w, _ = coeffs.shape
    cols, rows = atlas_layout(n)
    out = np.zeros((rows * h, cols * w, 3), dtype=np.float32)
    for c in range(n):
        r, k = divmod(c, cols)
        out[r * h:(r + 1) * h, k * w:(k + 1) * w] = coeffs[c]
    return out


def packed_tiles(n_coeffs: int) -> int:
    """Number of RGBA tiles holding the 3·``n_coeffs`` scalar maps of :func:`packed_coefficient_atlas`."""
    return -(-3 * int(n_coeffs) // 4)


def packed_coefficient_atlas(coeffs: np.ndarray) -> np.ndarray:
    """Pack the (n, H, W, 3) coefficient maps four scalar maps to a texel: float32 (rows·H, cols·W, 4).

    Scalar map j = 3c + k (coefficient c, colour channel k) is component j mod 4 of tile
    t = j div 4; tile t sits at rows [r·H, (r+1)·H), columns [q·W, (q+1)·W) with q = t mod cols,
    r = t div cols (:func:`atlas_layout` of :func:`packed_tiles` (n) tiles). Components past
    3n are 0. Values are copied exactly (no arithmetic).
    """
    n, h, w, _ = coeffs.shape
    n_tiles = packed_tiles(n)
    cols, rows = atlas_layout(n_tiles)
    out = np.zeros((rows * h, cols * w, 4), dtype=np.float32)
    # scalar map j = 3c + k straight into its tile's component (no (3n, H, W) copy of the maps: a
    # P = 18 SHRM of 120 × 240 maps is 125 MB in float32)
    for j in range(3 * n):
        (r, q), (c, k) = divmod(j // 4, cols), divmod(j, 3)
        out[r * h:(r + 1) * h, q * w:(q + 1) * w, j % 4] = coeffs[c, :, :, k]
    return out


_FETCH4 = """
// bilinear fetch of the four channels of shrmTex at tile offset o (texel units)
vec4 shrm_fetch4(ivec2 o, ivec4 idx, vec2 f) {
  vec4 t00 = texelFetch(shrmTex, o + ivec2(idx.x, idx.z), 0);
  vec4 t01 = texelFetch(shrmTex, o + ivec2(idx.y, idx.z), 0);
  vec4 t10 = texelFetch(shrmTex, o + ivec2(idx.x, idx.w), 0);
  vec4 t11 = texelFetch(shrmTex, o + ivec2(idx.y, idx.w), 0);
  vec4 top = t00 * (1.0 - f.x) + t01 * f.x;
  vec4 bottom = t10 * (1.0 - f.x) + t11 * f.x;
  return top * (1.0 - f.y) + bottom * f.y;
}
"""


def _packed_sum_glsl(n: int, height: int, width: int) -> list[str]:
    """Straight-line GLSL summing Σ_c Y^r_c(V) map_c(R) over the tiles of the packed atlas."""
    cols, _ = atlas_layout(packed_tiles(n))
    lines = ["  vec3 shrmRad = vec3(0.0);"]
    for t in range(packed_tiles(n)):
        r, q = divmod(t, cols)
        lines.append(f"  vec4 shrmT{t} = shrm_fetch4(ivec2({q * int(width)}, {r * int(height)}), shrmIdx, shrmF);")
        for i in range(4):
            c, k = divmod(4 * t + i, 3)
            if c < n:  # components past 3n are padding
                lines.append(f"  shrmRad[{k}] += shrmY[{c}] * shrmT{t}[{i}];")
    return lines


def shrm_fragment_replacements(
    lmax: int, height: int, width: int, *, per_pixel: bool, screen: bool = False, lights: LightShading | None = None
) -> list[tuple[str, str]]:
    """Fragment shader replacements of one SHRM actor.

    ``per_pixel=False``: ``shrmTex`` is one H × W map looked up by R (distant, rsibr);
    ``per_pixel=True``: ``shrmTex`` is the packed coefficient atlas (:func:`packed_coefficient_atlas`)
    and Σ_c Y^r_c(V) map_c(R) is summed, channel by channel, in the same order as a sum over
    RGB tiles (bilinear per scalar map, then the SH weight). ``screen=True``: the same body
    in the deferred screen pass (``glsl.screen_fragment_replacements``: R read back from the
    geometry pass), once per covered pixel. ``lights`` (:func:`~shrmkit.render.brdf_glsl.light_shading`):
    the explicit lights' exact reflection Σ_k ρ̂(ω_k; V, N) E_k, N = normalize(R + V), added per
    pixel after the clamp (DESIGN §5a; ``render/webgl/lights.glsl`` and the BRDF's GLSL); None
    (no lights) leaves no light code in the shader.
    """
    n = (lmax + 1) ** 2
    dec = [
        f"#define SHRM_H {int(height)}",
        f"#define SHRM_W {int(width)}",
        f"#define SHRM_NC {n}",
        _LOOKUP,
    ]
    body = ["  ivec4 shrmIdx; vec2 shrmF;", "  shrm_setup(shrmR, shrmIdx, shrmF);"]
    if per_pixel:
        dec += [_FETCH4, sh_glsl(lmax)]
        body += ["  float shrmY[SHRM_NC];", "  shrm_sh(shrmV, shrmY);", *_packed_sum_glsl(n, height, width)]
    else:
        body.append("  vec3 shrmRad = shrm_fetch(ivec2(0, 0), shrmIdx, shrmF);")
    # the Gibbs undershoot the prefilter's window left (SHRM.meta "negative_after") ends here
    body.append("  shrmRad = max(shrmRad, vec3(0.0));")
    if lights is not None:  # the lights, exactly, per pixel (V of the pixel, also in mode distant)
        dec.append(lights.glsl())
        body.append("  shrmRad += shrm_lights(shrmR, shrmV);")
    return screen_fragment_replacements(dec, body) if screen else fragment_replacements(dec, body)


def _light_parts(lights: LightShading | None) -> dict[str, Any]:
    """The Shading fields of the lights: uniforms and the BRDF table texture."""
    if lights is None:
        return {}
    textures = {} if lights.table is None else {"shrmBrdfTex": lights.table.atlas()}
    if textures:
        check_texture_size(textures["shrmBrdfTex"].shape, "the BRDF table of the lights")
    return {"uniforms": dict(lights.uniforms), "textures": textures}


def _view_map_shading(height: int, width: int, state: Any, lights: LightShading | None = None) -> Shading:
    """A per-frame H × W map looked up by R (filled by the mode's update before each frame). With
    lights it has a deferred screen pass too (the map is the same texture, rewritten per frame):
    their per-pixel sum is what costs, and deferred it runs once per covered pixel."""
    return Shading(
        np.zeros((height, width, 3), dtype=np.float32),
        vertex_replacements(),
        shrm_fragment_replacements(0, height, width, per_pixel=False, lights=lights),
        state=state,
        deferred=None if lights is None else shrm_fragment_replacements(0, height, width, per_pixel=False,
                                                                         screen=True, lights=lights),
        **_light_parts(lights),
    )


def distant_shading(shrm: SHRM, mesh: Mesh, *, views: Sequence[tuple[np.ndarray, float]] | None = None) -> Shading:
    """Distant viewer (RH02 eq. 12): the per-frame map Σ B̃_pq Y^r_pq(Ṽ); state = (P, flat coefficients).
    The SHRM's explicit lights are added per fragment with the pixel's own V (the map holds the
    SHRM part only, ``SHRM.view_map``: a light's highlight is sharper than it resolves); a measured
    BRDF's table only for ``views`` when given (:func:`cached_light_shading`: then draw no other)."""
    n, h, w, _ = shrm.coeffs.shape
    flat = np.ascontiguousarray(shrm.coeffs.reshape(n, -1), dtype=np.float32)
    return _view_map_shading(h, w, (shrm.P, flat), cached_light_shading(shrm, views))


def distant_update(state: tuple[int, np.ndarray], view: np.ndarray, out: np.ndarray) -> None:
    """Write Σ B̃_pq Y^r_pq(``view``) into the texture buffer ``out`` (no allocation of the map)."""
    P, flat = state
    basis = real_sph_harm(P, view).astype(np.float32)
    # einsum's single-threaded loop, not a BLAS call: a threaded BLAS GEMV of this size waits
    # for a second core that the rasterizer's threads (llvmpipe) or other work hold, costing a
    # scheduler time slice (milliseconds) instead of ~0.2 ms
    np.einsum("k,kn->n", basis, flat, out=out.reshape(-1))
    np.maximum(out, 0.0, out=out)  # as SHRM.view_map: no negative radiance (the window's leftover undershoot)


def perpixel_shading(shrm: SHRM, mesh: Mesh, *, views: Sequence[tuple[np.ndarray, float]] | None = None) -> Shading:
    """Per-pixel view (RH02 eq. 8): the (P+1)² coefficient maps in one packed RGBA atlas
    (:func:`packed_coefficient_atlas`), the SH of V in the shader; with its deferred screen
    pass (``Shading.deferred``: the sum once per covered pixel, ``vtk_renderer``). ``views`` as
    :func:`distant_shading`'s."""
    n, h, w, _ = shrm.coeffs.shape
    cols, rows = atlas_layout(packed_tiles(n))
    hint = "use mode='distant' or a coarser SHRM"
    check_texture_size((rows * h, cols * w), f"SHRM with P={shrm.P} on {h}x{w}", hint)
    lights = cached_light_shading(shrm, views)
    return Shading(
        packed_coefficient_atlas(shrm.coeffs),
        vertex_replacements(),
        shrm_fragment_replacements(shrm.P, h, w, per_pixel=True, lights=lights),
        deferred=shrm_fragment_replacements(shrm.P, h, w, per_pixel=True, screen=True, lights=lights),
        **_light_parts(lights),
    )


def rsibr_shading(model: RSIBRMaps | SHRM, mesh: Mesh) -> Shading:
    """Cabral et al. 1999: the twelve maps (made from an SHRM by ``rsibr_from_shrm`` when given one)."""
    maps = model if isinstance(model, RSIBRMaps) else rsibr_from_shrm(model)
    _, h, w, _ = maps.maps.shape
    # an SHRM's explicit lights are in the maps rsibr_from_shrm makes (Cabral's maps hold everything)
    return _view_map_shading(h, w, maps)


def rsibr_update(maps: RSIBRMaps, view: np.ndarray, out: np.ndarray) -> None:
    """Write the blend of the three maps of the face containing ``view`` into ``out``."""
    blended = maps.view_map(view)
    out.reshape(blended.shape)[...] = blended
