"""The BRDF in GLSL for the lights beside the SHRM [RH02] (DESIGN §5a): one shader file per model.

A scene's explicit lights (``analysis.lights``) are shaded exactly per pixel, as
:meth:`SHRM.radiance` does on the CPU: B_lights(R, V) = Σ_k ρ̂(ω_k; V, N) E_k, N = normalize(R + V).
:data:`BRDF_GLSL` gives each analytic model its GLSL file; every other BRDF is tabulated on
half/difference angles [Rus98] at MERL's spacing [MERL03] (:func:`tabulate_brdf`), on the
coarsest grid whose measured error is within 1 % (:func:`choose_table`); :func:`light_shading`
gathers what a renderer binds. Files and uniforms: ``data_specs/render_outputs.md``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

import numpy as np

from ..analysis.defaults import DEFAULT_MAX_VIEW_DEG
from ..analysis.lights import LightSet
from ..brdf_io.brdf import BRDF
from ..brdf_io.errors import BadInputError
from ..brdf_io.models import CookTorrance, Lafortune, Lambert, PhongLobe, SimplifiedMicrofacet

# the `NAME as NAME` imports: public here before the split, importable from here still (patch them where read)
from ._brdf_table import TABLE_COS_FLOOR as TABLE_COS_FLOOR
from ._brdf_table import (
    TABLE_FACTORS,
    TABLE_GRID,
    TABLE_TARGET_REL_RMS,
    BrdfTable,
    choose_table,
    scaled_grid,
    table_error,
    table_grid_for,
    table_light_radiance,
    table_lookup,
    tabulate_brdf,
    theta_d_ranges,
)
from ._brdf_table import atlas_texels as atlas_texels
from ._brdf_table import table_angles as table_angles

__all__ = [
    "BrdfShader",
    "BRDF_GLSL",
    "TABLE_SHADER",
    "TABLE_GRID",
    "BrdfTable",
    "LightShading",
    "brdf_shader_for",
    "tabulate_brdf",
    "table_grid_for",
    "choose_table",
    "scaled_grid",
    "TABLE_TARGET_REL_RMS",
    "TABLE_FACTORS",
    "table_lookup",
    "table_light_radiance",
    "table_error",
    "light_shading",
    "lights_glsl_parts",
    "glsl_source",
    "MAX_LIGHT_SAMPLES",
]

#: Uniform arrays are sized to the scene's samples, at most this many (``analysis.lights``:
#: MAX_LIGHTS × MAX_SAMPLES_PER_LIGHT).
MAX_LIGHT_SAMPLES = 128

#: A uniform value: (GLSL type, flat float values); types "float", "vec3", "vec3[]", "int".
Uniform = tuple[str, list[float]]

_WEBGL_DIR = "webgl"


def glsl_source(name: str) -> str:
    """The text of ``render/webgl/<name>`` (package data).

    Each GLSL file is used verbatim by the desktop VTK shaders (``render.shader``) and by the
    WebGL2 page (``render.webgl_page``, ``view.js``), as ``latlong.glsl`` is.
    """
    return resources.files(__package__).joinpath(_WEBGL_DIR).joinpath(name).read_text(encoding="utf-8")


def _rgb(a: Any) -> list[float]:
    return [float(x) for x in np.broadcast_to(np.asarray(a, dtype=np.float64), (3,))]


@dataclass(frozen=True)
class BrdfShader:
    """One row of the BRDF shader table.

    Attributes
    ----------
    name
        Short name (the JSON of the view page: ``lights.brdf.model``).
    model
        The BRDF class it shades (an exact type match).
    source
        File name in ``render/webgl/`` defining ``vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V)``
        for unit vectors in one frame (the z-up world frame); the models are isotropic, so only
        dot products of N, L, V enter and no tangent frame is built.
    uniforms
        brdf → {uniform name: (GLSL type, flat values)}.
    defines
        brdf → {macro: value}: what sizes arrays or selects a branch at compile time.
    """

    name: str
    model: type | None
    source: str
    uniforms: Callable[[Any], dict[str, Uniform]]
    defines: Callable[[Any], dict[str, int]] = field(default=lambda brdf: {})


def _lafortune_uniforms(b: Lafortune) -> dict[str, Uniform]:
    out: dict[str, Uniform] = {"shrmLafKd": ("vec3", _rgb(b.kd))}
    lobes = b.lobes or ()
    for key, attr in (("shrmLafCxy", "cxy"), ("shrmLafCz", "cz"), ("shrmLafN", "n"), ("shrmLafKs", "ks")):
        # no lobes: one lobe of zero scale (arrays need a size >= 1)
        values = [v for lobe in lobes for v in _rgb(getattr(lobe, attr))] if lobes else \
            ([0.0, 0.0, 0.0] if attr == "ks" else [1.0, 1.0, 1.0])
        out[key] = ("vec3[]", values)
    return out


#: The BRDF shader table: one :class:`BrdfShader` per analytic model class; :func:`brdf_shader_for`
#: picks the entry of a BRDF. Each model has **one** GLSL file in ``render/webgl/``:
#:
#: ==========================  ========================  =====================================
#: model (``brdf_io.models``)  GLSL file                 parameters (uniforms / #defines)
#: ==========================  ========================  =====================================
#: ``PhongLobe``               ``brdf_phong.glsl``       ``shrmPhongS``, ``shrmPhongKs``
#: ``SimplifiedMicrofacet``    ``brdf_microfacet.glsl``  ``shrmMicrofacetSigma``, ``…Ks``
#: ``Lambert``                 ``brdf_lambert.glsl``     ``shrmLambertAlbedo``
#: ``Lafortune``               ``brdf_lafortune.glsl``   ``shrmLafKd``, per lobe ``shrmLafCxy[k]``,
#:                                                       ``…Cz[k]``, ``…N[k]``, ``…Ks[k]``;
#:                                                       ``SHRM_LAF_LOBES``
#: ``CookTorrance``            ``brdf_cook_torrance…``   ``shrmCtKd``, ``…Ks``, ``…F0``,
#:                                                       ``shrmCtAlpha``; ``SHRM_CT_GGX``
#: measured (kind ≠ analytic)  ``brdf_table.glsl``       the table texture ``shrmBrdfTex``,
#:                                                       ``shrmBrdfScale``; ``SHRM_TAB_*``
#: ==========================  ========================  =====================================
BRDF_GLSL: dict[type, BrdfShader] = {
    s.model: s
    for s in (
        BrdfShader("phong", PhongLobe, "brdf_phong.glsl",
                   lambda b: {"shrmPhongS": ("float", [float(b.s)]), "shrmPhongKs": ("vec3", _rgb(b.ks))}),
        BrdfShader("microfacet", SimplifiedMicrofacet, "brdf_microfacet.glsl",
                   lambda b: {"shrmMicrofacetSigma": ("float", [float(b.sigma)]),
                              "shrmMicrofacetKs": ("vec3", _rgb(b.ks))}),
        BrdfShader("lambert", Lambert, "brdf_lambert.glsl",
                   lambda b: {"shrmLambertAlbedo": ("vec3", _rgb(b.albedo))}),
        BrdfShader("lafortune", Lafortune, "brdf_lafortune.glsl", _lafortune_uniforms,
                   lambda b: {"SHRM_LAF_LOBES": max(1, len(b.lobes))}),
        BrdfShader("cook-torrance", CookTorrance, "brdf_cook_torrance.glsl",
                   lambda b: {"shrmCtKd": ("vec3", _rgb(b.kd)), "shrmCtKs": ("vec3", _rgb(b.ks)),
                              "shrmCtF0": ("vec3", _rgb(b.f0)), "shrmCtAlpha": ("float", [float(b.alpha)])},
                   lambda b: {"SHRM_CT_GGX": 1 if b.distribution == "ggx" else 0}),
    )
    if s.model is not None  # every entry here names its class (None is TABLE_SHADER's)
}

#: Every other BRDF: a table texture (``brdf_table.glsl``; :func:`tabulate_brdf`) — measured BRDFs
#: (MERL ``.binary``, RGL ``.bsdf``, table ``.npz``, scattered data: every BRDF whose ``kind`` is
#: not ``"analytic"``) and analytic models without an entry in :data:`BRDF_GLSL`.
TABLE_SHADER = BrdfShader("table", None, "brdf_table.glsl", lambda t: {"shrmBrdfScale": ("float", [float(t.scale)])},
                          lambda t: {"SHRM_TAB_NH": t.shape[0], "SHRM_TAB_ND": t.shape[1], "SHRM_TAB_NP": t.shape[2],
                                     "SHRM_TAB_COLS": t.cols, "SHRM_TAB_PERIODIC": int(t.periodic)})


def brdf_shader_for(brdf: BRDF) -> BrdfShader:
    """The entry of :data:`BRDF_GLSL` for ``brdf``'s class, or :data:`TABLE_SHADER` for a BRDF
    without one (measured data, and analytic models the table does not list)."""
    return BRDF_GLSL.get(type(brdf), TABLE_SHADER)


# ------------------------------------------------------------------------------------------
# what a renderer needs: GLSL, uniforms, defines, the table texture
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class LightShading:
    """The lights of one object on the GPU.

    Attributes
    ----------
    shader
        The BRDF's table entry.
    count
        Light samples (the uniform arrays' size, ``SHRM_NLIGHTS``).
    uniforms
        {name: (GLSL type, flat values)}: the samples (``shrmLightCount``, ``shrmLightDir``,
        ``shrmLightPower``) and the BRDF's parameters.
    defines
        {macro: value} of the BRDF and ``SHRM_NLIGHTS``.
    table
        The BRDF table (measured BRDFs), bound as ``shrmBrdfTex``; else None. Made for some views
        (``light_shading(views=)``), it holds only the θ_d rows they read (``BrdfTable.rows``).
    table_error
        :func:`table_error` of the table (None without one).
    """

    shader: BrdfShader
    count: int
    uniforms: dict[str, Uniform]
    defines: dict[str, int]
    table: BrdfTable | None = None
    table_error: dict[str, float] | None = None

    def glsl(self, *, vtk: bool = True) -> str:
        """The #defines and the GLSL of the BRDF and the light sum, for the VTK shaders
        (``SHRM_VTK``: VTK declares the samplers of the textures it binds)."""
        return "\n".join([*(["#define SHRM_VTK 1"] if vtk else []),
                          *(f"#define {k} {int(v)}" for k, v in self.defines.items()),
                          *(glsl_source(name) for name in lights_glsl_parts(self.shader))])

    def describe(self) -> str:
        """One line: samples, BRDF shader, the table and its measured error."""
        text = f"{self.count} light sample(s) shaded per pixel by {self.shader.source}"
        if self.table is not None:
            nh, nd, npd = self.table.shape
            text += f" (BRDF table {nh}x{nd}x{npd} in theta_h, theta_d, phi_d"
            if self.table.rows is not None:  # tabulated for the frames' views only
                runs = ", ".join(f"{a}-{b}" for a, b in self.table.rows)
                text += (f"; tabulated in theta_d rows {runs or 'none'}, the views', "
                         f"{100 * self.table.tabulated / (nh * nd * npd):.2g} % of its texels")
            if self.table_error is not None:
                text += (f"; its error on the lights' reflection {100 * self.table_error['rel_rms']:.2g} % relative "
                         f"RMS, worst view band {100 * self.table_error['worst_band_rel_rms']:.2g} %")
            text += ")"
        return text


def lights_glsl_parts(shader: BrdfShader) -> tuple[str, ...]:
    """The GLSL files of the lights, in order: helpers (``brdf_common.glsl``), the BRDF, the sum
    (``lights.glsl``: ``shrm_lights(R, V)`` over the samples, uniforms ``shrmLightCount``,
    ``shrmLightDir[]``, ``shrmLightPower[]``, array size ``SHRM_NLIGHTS``)."""
    return ("brdf_common.glsl", shader.source, "lights.glsl")


def light_uniforms(lights: LightSet) -> dict[str, Uniform]:
    """The samples as uniforms: count, unit directions (z-up frame), RGB powers."""
    return {"shrmLightCount": ("int", [float(len(lights))]),
            "shrmLightDir": ("vec3[]", [float(x) for x in lights.directions.reshape(-1)]),
            "shrmLightPower": ("vec3[]", [float(x) for x in lights.power.reshape(-1)])}


def light_shading(shrm: Any, *, table_shape: tuple[int, int, int] | None = None,
                  table: BrdfTable | None = None, measure: bool = True,
                  views: Sequence[tuple[np.ndarray, float]] | None = None) -> LightShading | None:
    """The :class:`LightShading` of an SHRM's lights, or None when it has none (then the shaders
    hold no light code at all: no cost).

    A BRDF without a GLSL model (:func:`brdf_shader_for`) is tabulated at the resolution its error
    needs (:func:`choose_table`; on ``table_shape`` if given), or ``table`` is used (its error
    measured with ``measure``).

    ``views``: None (default), the whole table; else every direction V toward the eye the frames
    will shade, as cones (unit axis (3,), half-angle in radians; ``Camera.view_cone``) in the
    lights' frame (the unrotated environment's: ``brdf_io.env_rotation.to_map_frame``): the table
    is tabulated only in the θ_d rows they can read (:func:`theta_d_ranges`; ``BrdfTable.rows``),
    and draws those frames as the whole table does, bit for bit; its error is the whole table's.
    """
    if not getattr(shrm, "has_lights", False):
        return None
    lights: LightSet = shrm.lights
    if len(lights) > MAX_LIGHT_SAMPLES:
        raise BadInputError(None, f"{len(lights)} light samples: the shaders take at most {MAX_LIGHT_SAMPLES}")
    brdf = shrm.lights_brdf()
    shader = brdf_shader_for(brdf)
    uniforms = light_uniforms(lights)
    error = None
    if shader is TABLE_SHADER:
        stated = shrm.info.max_view_deg
        max_view = DEFAULT_MAX_VIEW_DEG if stated is None else float(stated)
        if table is None:
            theta_d = None if views is None else theta_d_ranges(lights.directions, views)
            table, error = choose_table(brdf, lights, max_view_deg=max_view, shape=table_shape, theta_d=theta_d)
        elif measure:
            error = table_error(table, brdf, lights, max_view_deg=max_view)
        uniforms.update(shader.uniforms(table))
        defines = shader.defines(table)
    else:
        table = None
        uniforms.update(shader.uniforms(brdf))
        defines = shader.defines(brdf)
    return LightShading(shader, len(lights), uniforms, {**defines, "SHRM_NLIGHTS": len(lights)}, table, error)
