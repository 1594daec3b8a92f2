"""The view page's payloads, encoded as the viewer decodes them: base64 of half floats scaled
by a power of two, the mesh (decimated to its budget), the background, the lights and a measured
BRDF's table, and each SHRM's coefficient atlas with the maps the page stores.
"""

from __future__ import annotations

import base64
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..analysis.lights import LightSet
from ..analysis.shrm import SHRM
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from ._page_fit import CoefficientFit, ViewBudget, _area_resample, fit_coefficients
from .brdf_glsl import TABLE_SHADER, BrdfTable, brdf_shader_for, choose_table, light_shading, lights_glsl_parts
from .mesh import Mesh, make_mesh
from .preview import unit_mesh
from .shader import atlas_layout, coefficient_atlas

#: Half floats: coefficients are multiplied by a power of two that brings their largest
#: magnitude to at most this (the largest half float is 65504).
HALF_TARGET = 32768.0



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
    centre, _ = mesh.bounding_sphere()
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
        limit = shrm.info.max_view_deg  # the order rule's view limit (None: an SHRM without it)
        table, error = choose_table(brdf, shrm.lights, max_view_deg=float(80.0 if limit is None else limit),
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
