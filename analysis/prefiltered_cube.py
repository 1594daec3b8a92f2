"""The engines' GGX-prefiltered environment as a cube mip chain (split sum, one roughness per level).

Real-time engines keep the first factor of the split sum (``analysis/baselines/split_sum.py``,
[Karis13]) as a cube map whose mip levels hold the environment prefiltered for increasing GGX
roughness; a material looks its roughness up between two levels. The level → roughness rule
here is the glTF one ([glTF-IBL], glTF-Sample-Viewer: ``lod = roughness ·
(levels − 1)``): level m of N holds the perceptual roughness r_m = m/(N − 1), GGX width
α_m = r_m² (level 0: r = 0, the environment itself). Each level with α > 0 is Karis's
prefilter L̄_α(R) = ∫ L(ω) D_α(h) max(R·ω, 0) dω / ∫ D_α(h) max(R·ω, 0) dω summed over every
pixel of the lat-long map (:func:`~shrmkit.analysis.baselines.split_sum.ggx_prefiltered`, exact
pixel weights, no sampling noise) on a grid fine enough for the level's texels, then looked up
bilinearly at the texel centres; level 0 is the map averaged over 4 × 4 bilinear sub-samples
per texel. A map of fewer than 64 rows is replicated (each pixel k × k times) to 64 rows or more
before the prefilter, so that the lobe is summed over a grid that tells its directions apart
(:data:`MIN_PREFILTER_ROWS`). A black map (zero everywhere) is refused.

Cube frame: the faces (px, nx, py, ny, pz, nz) and texel directions of
``brdf_io/cubemap.py`` in the y-up frame of cube-map files (:data:`~shrmkit.brdf_io.cubemap.CUBE_TO_PROJECT`:
project X = z_c, Y = −x_c, Z = y_c), which is what a y-up engine samples: face py is the zenith.

Public objects: :class:`CubeChain`, :func:`ggx_cube_chain`, :func:`chain_roughness`,
:func:`material_lod`.

References: [Karis13] (split sum, ``PrefilterEnvMap``); [glTF-IBL] (``lod = roughness · (mipCount − 1)``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..brdf_io.cubemap import CUBE_TO_PROJECT, cube_map_directions
from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_lookup
from .baselines.split_sum import ggx_prefiltered
from .defaults import MAX_CUBE_FACE_SIZE as MAX_FACE_SIZE  # numpy-free home, for the CLI's parsers

__all__ = ["CubeChain", "ggx_cube_chain", "chain_roughness", "material_lod", "MAX_FACE_SIZE"]


@dataclass(frozen=True, eq=False)
class CubeChain:
    """A GGX-prefiltered cube mip chain.

    Attributes
    ----------
    levels
        One float32 array (6, S_m, S_m, 3) per level, S_m = max(1, S >> m), faces in
        ``CUBE_FACES`` order (px, nx, py, ny, pz, nz), rows top to bottom (cube-map file frame).
    roughness
        Perceptual roughness r_m = m/(N − 1) of each level.
    alpha
        GGX width α_m = r_m² of each level.
    rows
        Rows of the lat-long grid each level was prefiltered on (the map's own rows for level 0).
    seconds
        Time to build the chain.
    """

    levels: tuple[np.ndarray, ...]
    roughness: tuple[float, ...]
    alpha: tuple[float, ...]
    rows: tuple[int, ...]
    seconds: float

    @property
    def face_size(self) -> int:
        return int(self.levels[0].shape[1])


def chain_roughness(n_levels: int) -> np.ndarray:
    """Perceptual roughness of each of ``n_levels`` levels, m/(N − 1) (0 for a single level)."""
    return np.arange(n_levels) / max(n_levels - 1, 1)


def material_lod(alpha: float, n_levels: int) -> float:
    """The (fractional) level a GGX material of width α reads: √α · (N − 1)."""
    return float(np.sqrt(alpha) * (n_levels - 1))


#: Rows below which a map is replicated (each pixel k × k times) before it is prefiltered: the
#: prefilter's grid is a divisor of the map's rows, and a lobe must be summed over a grid fine
#: enough to tell its directions apart (a 1 × 2 map's roughness-1 level is the cosine-weighted
#: average of both halves, not the pixel a texel falls in). Replication keeps every pixel's
#: radiance over its own solid angle (the map is piecewise constant, DESIGN §2).
MIN_PREFILTER_ROWS = 64


def _replicated(radiance: np.ndarray) -> np.ndarray:
    """The map with each pixel repeated k × k times, k = ⌈64 / H⌉ (the map itself when H ≥ 64)."""
    k = -(-MIN_PREFILTER_ROWS // radiance.shape[0])
    return radiance if k == 1 else np.repeat(np.repeat(radiance, k, axis=0), k, axis=1)


def _rows_for(height: int, alpha: float, face: int) -> int:
    """Smallest divisor of the map's rows H that is at least min(4π/α, 4·S_m) and 64: a pixel
    pitch of α/4 for the lobe (``default_level_rows``), never finer than needed for the level's
    texels, never coarser than 2.8° (benchmarks/export_accuracy.py measures the lookup's error)."""
    target = max(64.0, min(4.0 * np.pi / alpha, 4.0 * face))
    return next((d for d in range(1, height + 1) if height % d == 0 and d >= target), height)


def _texel_directions(size: int, sub: int = 1) -> np.ndarray:
    """Project-frame directions of the texels (6, S, S, 3), or of sub × sub sub-samples per
    texel (6, S, S, sub², 3)."""
    if sub == 1:
        return cube_map_directions(size) @ CUBE_TO_PROJECT.T
    # the texel grid of a face sub times finer, regrouped: (6, S, sub, S, sub) -> (6, S, S, sub²)
    d = cube_map_directions(size * sub).reshape(6, size, sub, size, sub, 3)
    return d.transpose(0, 1, 3, 2, 4, 5).reshape(6, size, size, sub * sub, 3) @ CUBE_TO_PROJECT.T


def ggx_cube_chain(env: object, *, face_size: int = 128, n_levels: int | None = None) -> CubeChain:
    """Build the GGX-prefiltered cube mip chain of a lat-long environment (module docstring).

    Parameters
    ----------
    env
        An EnvironmentMap or an (H, W, 3) lat-long array (W = 2H, project frame, DESIGN §2).
    face_size
        S, texels along a face of level 0: a power of two, 1..2048.
    n_levels
        Levels N (default log2(S) + 1, down to 1 × 1); level m has max(1, S >> m) texels.

    Returns
    -------
    CubeChain

    Raises
    ------
    BadInputError
        A face size that is not a power of two, a level count outside 1..log2(S) + 1, a map
        that is not 2:1, a black map (zero everywhere, as ``shrm prefilter`` refuses it).
    """
    t0 = time.perf_counter()
    radiance = np.asarray(getattr(env, "radiance", env), dtype=np.float64)
    if radiance.ndim != 3 or radiance.shape[1] != 2 * radiance.shape[0] or radiance.shape[2] != 3:
        raise BadInputError(getattr(env, "name", None), f"need an (H, 2H, 3) lat-long map, got {radiance.shape}")
    if not (1 <= face_size <= MAX_FACE_SIZE) or face_size & (face_size - 1):
        raise BadInputError(None, f"cube face size {face_size}: must be a power of two in 1..{MAX_FACE_SIZE}")
    if not np.any(radiance != 0):
        raise BadInputError(getattr(env, "name", None),
                            "the environment map is black (zero everywhere): nothing to prefilter")
    full = int(np.log2(face_size)) + 1
    n_levels = full if n_levels is None else int(n_levels)
    if not 1 <= n_levels <= full:
        raise BadInputError(None, f"{n_levels} mip levels: a {face_size}-texel face has 1..{full}")
    rough = chain_roughness(n_levels)
    fine = _replicated(radiance) if np.any(rough > 0) else radiance
    height = radiance.shape[0]
    levels, rows = [], []
    for m, r in enumerate(rough):
        size = max(1, face_size >> m)
        alpha = float(r * r)
        if alpha == 0.0:
            d = _texel_directions(size, sub=4)
            level = bilinear_lookup(radiance, d).mean(axis=-2)
            rows.append(height)
        else:
            n = _rows_for(fine.shape[0], alpha, size)
            pre = ggx_prefiltered(fine, alpha, n)
            level = bilinear_lookup(pre, _texel_directions(size))
            rows.append(n)
        levels.append(np.ascontiguousarray(level, dtype=np.float32))
    return CubeChain(levels=tuple(levels), roughness=tuple(float(r) for r in rough),
                     alpha=tuple(float(r * r) for r in rough), rows=tuple(rows),
                     seconds=time.perf_counter() - t0)
