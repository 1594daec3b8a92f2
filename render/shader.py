"""Shading of the SHRM render modes (``distant``, ``perpixel``, ``kautz-mccool``, ``rsibr``).

RH02 = Ramamoorthi & Hanrahan, "Frequency Space Environment Map Rendering", SIGGRAPH 2002,
doi:10.1145/566654.566611. Per fragment, after the shared prelude of ``render.glsl``
(N, V, R in the z-up world frame):

- ``distant`` (RH02 eq. 12): radiance = M(R) with M = Σ B̃_pq Y^r_pq(Ṽ) one lat-long map per
  frame and object, Ṽ the direction from the object's bounding-sphere centre toward the eye,
  computed on the CPU (:func:`distant_update`) and uploaded as a float texture;
- ``perpixel`` (RH02 eq. 8): radiance = Σ B̃_pq(R) Y^r_pq(V), the (P+1)² coefficient maps
  tiled in one float texture (:func:`coefficient_atlas`: tile c at column (c mod cols)·W,
  row (c div cols)·H) and Y^r_pq(V) evaluated in the shader; ``kautz-mccool`` draws the
  azimuth-free (q = 0) SHRM the same way;
- ``rsibr`` (Cabral et al. 1999): the distant shader fed, per frame, the spherical-barycentric
  blend of the twelve maps of ``analysis.baselines.rsibr`` (:func:`rsibr_update`).

All maps are looked up with the bilinear lat-long rule of ``render.glsl`` (four ``texelFetch``es).
The SHRM modes clamp the radiance at 0 (``max(shrmRad, 0)`` in the fragment shader, and the
per-frame map of ``distant``), as :meth:`SHRM.radiance` does: the undershoot the prefilter's
window left (``SHRM.meta["negative_after"]``, ``data_specs/shrm_file.md``) never reaches an image.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..analysis.baselines.rsibr import RSIBRMaps, rsibr_from_shrm
from ..analysis.sh import real_sph_harm
from ..analysis.shrm import SHRM
from .glsl import (
    LATLONG_GLSL,
    Shading,
    check_texture_size,
    fragment_replacements,
    sh_glsl,
    vertex_replacements,
)
from .mesh import Mesh

__all__ = [
    "atlas_layout",
    "coefficient_atlas",
    "shrm_fragment_replacements",
    "distant_shading",
    "distant_update",
    "perpixel_shading",
    "rsibr_shading",
    "rsibr_update",
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


def shrm_fragment_replacements(lmax: int, height: int, width: int, *, per_pixel: bool) -> list[tuple[str, str]]:
    """Fragment shader replacements of one SHRM actor.

    ``per_pixel=False``: ``shrmTex`` is one H × W map looked up by R (distant, rsibr);
    ``per_pixel=True``: ``shrmTex`` is the coefficient atlas and Σ_c Y^r_c(V) tile_c(R) is summed.
    """
    n = (lmax + 1) ** 2
    cols, _ = atlas_layout(n)
    dec = [
        f"#define SHRM_H {int(height)}",
        f"#define SHRM_W {int(width)}",
        f"#define SHRM_COLS {cols}",
        f"#define SHRM_NC {n}",
        _LOOKUP,
    ]
    body = ["  ivec4 shrmIdx; vec2 shrmF;", "  shrm_setup(shrmR, shrmIdx, shrmF);"]
    if per_pixel:
        dec.append(sh_glsl(lmax))
        body += [
            "  float shrmY[SHRM_NC];",
            "  shrm_sh(shrmV, shrmY);",
            "  vec3 shrmRad = vec3(0.0);",
            "  for (int c = 0; c < SHRM_NC; ++c) {",
            "    ivec2 o = ivec2((c % SHRM_COLS) * SHRM_W, (c / SHRM_COLS) * SHRM_H);",
            "    shrmRad += shrmY[c] * shrm_fetch(o, shrmIdx, shrmF);",
            "  }",
        ]
    else:
        body.append("  vec3 shrmRad = shrm_fetch(ivec2(0, 0), shrmIdx, shrmF);")
    # the Gibbs undershoot the prefilter's window left (SHRM.meta "negative_after") ends here
    body.append("  shrmRad = max(shrmRad, vec3(0.0));")
    return fragment_replacements(dec, body)


def _view_map_shading(height: int, width: int, state: Any) -> Shading:
    """A per-frame H × W map looked up by R (filled by the mode's update before each frame)."""
    return Shading(
        np.zeros((height, width, 3), dtype=np.float32),
        vertex_replacements(),
        shrm_fragment_replacements(0, height, width, per_pixel=False),
        state=state,
    )


def distant_shading(shrm: SHRM, mesh: Mesh) -> Shading:
    """Distant viewer (RH02 eq. 12): the per-frame map Σ B̃_pq Y^r_pq(Ṽ); state = (P, flat coefficients)."""
    n, h, w, _ = shrm.coeffs.shape
    flat = np.ascontiguousarray(shrm.coeffs.reshape(n, -1), dtype=np.float32)
    return _view_map_shading(h, w, (shrm.P, flat))


def distant_update(state: tuple[int, np.ndarray], view: np.ndarray, out: np.ndarray) -> None:
    """Write Σ B̃_pq Y^r_pq(``view``) into the texture buffer ``out`` (no allocation of the map)."""
    P, flat = state
    basis = real_sph_harm(P, view).astype(np.float32)
    np.matmul(basis, flat, out=out.reshape(-1))
    np.maximum(out, 0.0, out=out)  # as SHRM.view_map: no negative radiance (the window's leftover undershoot)


def perpixel_shading(shrm: SHRM, mesh: Mesh) -> Shading:
    """Per-pixel view (RH02 eq. 8): the (P+1)² coefficient maps in one atlas, the SH of V in the shader."""
    n, h, w, _ = shrm.coeffs.shape
    cols, rows = atlas_layout(n)
    hint = "use mode='distant' or a coarser SHRM"
    check_texture_size((rows * h, cols * w), f"SHRM with P={shrm.P} on {h}x{w}", hint)
    return Shading(
        coefficient_atlas(shrm.coeffs),
        vertex_replacements(),
        shrm_fragment_replacements(shrm.P, h, w, per_pixel=True),
    )


def rsibr_shading(model: RSIBRMaps | SHRM, mesh: Mesh) -> Shading:
    """Cabral et al. 1999: the twelve maps (made from an SHRM by ``rsibr_from_shrm`` when given one)."""
    maps = model if isinstance(model, RSIBRMaps) else rsibr_from_shrm(model)
    _, h, w, _ = maps.maps.shape
    return _view_map_shading(h, w, maps)


def rsibr_update(maps: RSIBRMaps, view: np.ndarray, out: np.ndarray) -> None:
    """Write the blend of the three maps of the face containing ``view`` into ``out``."""
    blended = maps.view_map(view)
    out.reshape(blended.shape)[...] = blended
