"""GLSL shared by every render mode: the shader prelude, lat-long lookup, real SH, and :class:`Shading`.

Each render mode (``render.modes``) turns its model into a :class:`Shading`: one float32
texture (sampler ``shrmTex``), VTK shader replacements, optional per-vertex ``vec4``
attributes, and the state its per-frame update reads. The replacements are made here, once:
the vertex shader's (:func:`vertex_replacements`), the fragment shader's prelude that computes
N, V and R in the z-up world frame (= VTK world frame) before the mode's body sets ``vec3 shrmRad``
(:func:`fragment_replacements`), and the two passes of deferred shading
(:func:`gbuffer_fragment_replacements`, :func:`screen_fragment_replacements`; the per-pixel modes,
:class:`~shrmkit.render.vtk_renderer.SHRMRenderer`). Uniforms set per frame by the renderer:
``shrmEye``, ``shrmOrtho``, ``shrmViewDir`` and :data:`TO_MAP_UNIFORM` (the environment's rotation
at view time). Also the bilinear lat-long lookup (:data:`LATLONG_GLSL`) and the real SH as
straight-line GLSL (:func:`sh_glsl`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

import numpy as np

__all__ = [
    "Shading",
    "MAX_TEXTURE_SIZE",
    "check_texture_size",
    "vertex_replacements",
    "fragment_replacements",
    "gbuffer_fragment_replacements",
    "screen_fragment_replacements",
    "varying",
    "glsl_float",
    "sh_glsl",
    "LATLONG_GLSL",
    "TO_MAP_UNIFORM",
]

#: Largest texture edge we rely on (llvmpipe and current GPUs allow at least 16384).
MAX_TEXTURE_SIZE = 16384

Replacements = list[tuple[str, str]]


@dataclass(frozen=True, eq=False)
class Shading:
    """What one object needs on the GPU.

    Attributes
    ----------
    texture
        float32 (h, w, 3) or (h, w, 4) image bound as sampler ``shrmTex`` (GL_RGB32F or
        GL_RGBA32F); texel (x, y) is ``texture[y, x]``.
        A mode with a per-frame update rewrites it in place every frame.
    vertex, fragment
        (tag, replacement) pairs for VTK's vertex and fragment shaders.
    attributes
        Per-vertex ``vec4`` attributes: GLSL name -> float32 (n_vertices, 4).
    state
        What the mode's per-frame update reads (``RenderMode.update``), or None.
    deferred
        Fragment replacements of the same shading as a screen pass
        (:func:`screen_fragment_replacements`: R read from the geometry pass, V per pixel), or
        None when the mode cannot be deferred (it needs N, vertex attributes or a per-frame map).
    uniforms
        Constant uniforms of the fragment shader (both passes): name -> (GLSL type, flat
        values), types ``float``, ``int``, ``vec3`` and ``vec3[]`` (an array of vec3) — the
        lights and the BRDF's parameters (``render.brdf_glsl``).
    textures
        Further float32 (h, w, 3) textures by sampler name (a measured BRDF's table,
        ``shrmBrdfTex``), bound beside ``shrmTex`` in both passes.
    """

    texture: np.ndarray
    vertex: Replacements
    fragment: Replacements
    attributes: dict[str, np.ndarray] = field(default_factory=dict)
    state: Any = None
    deferred: Replacements | None = None
    uniforms: dict[str, tuple[str, list[float]]] = field(default_factory=dict)
    textures: dict[str, np.ndarray] = field(default_factory=dict)


def check_texture_size(shape: tuple[int, ...], what: str, hint: str = "") -> None:
    """Raise ValueError when a texture of ``shape`` (height, width, ...) has an edge over
    :data:`MAX_TEXTURE_SIZE` texels; the message starts with ``what`` and ends with ``hint``."""
    h, w = int(shape[0]), int(shape[1])
    if max(h, w) > MAX_TEXTURE_SIZE:
        raise ValueError(f"{what} needs a {h}x{w} texture (limit {MAX_TEXTURE_SIZE}){'; ' + hint if hint else ''}")


def glsl_float(x: float) -> str:
    """A GLSL float literal with 9 significant digits (exact for float32)."""
    return f"{float(x):.9e}"


def varying(attribute: str) -> str:
    """Name of the varying that carries the vertex attribute ``attribute`` to the fragment shader."""
    return f"{attribute}_f"


def vertex_replacements(attributes: Sequence[str] = ()) -> Replacements:
    """(tag, replacement) pairs for the vertex shader: world position, normal and ``attributes`` passed on.

    The world position ``shrmPosWC`` and normal ``shrmNormWC`` are passed on as they are (the actor's
    model matrix is the identity and VBO shift/scale is disabled, so ``vertexMC`` and ``normalMC`` are
    world-space), plus each attribute ``a`` as the varying :func:`varying` (``a_f``).
    """
    dec = ["//VTK::Normal::Dec", "out vec3 shrmPosWC;", "out vec3 shrmNormWC;"]
    impl = ["//VTK::Normal::Impl", "  shrmPosWC = vertexMC.xyz;", "  shrmNormWC = normalMC;"]
    for name in attributes:
        dec += [f"in vec4 {name};", f"out vec4 {varying(name)};"]
        impl.append(f"  {varying(name)} = {name};")
    return [("//VTK::Normal::Dec", "\n".join(dec) + "\n"), ("//VTK::Normal::Impl", "\n".join(impl) + "\n")]


#: V: toward the eye (perspective) or the constant direction toward the camera (ortho)
_VIEW_LINE = "  vec3 shrmV = (shrmOrtho != 0) ? normalize(shrmViewDir) : normalize(shrmEye - shrmPosWC);"

#: The mat3 uniform Qᵀ taking world directions into the unrotated environment's frame (column-major
#: as OpenGL stores it); a shader that reads it declares nothing: the renderer sets it. The environment
#: is rotated by Q at view time (``brdf_io.env_rotation``): the prelude of every shading body turns
#: N, V and R into the unrotated map's frame (Qᵀ N, Qᵀ V, Qᵀ R), so every mode's lookup, its lights
#: and its per-frame map read B_Q(R, V) = B(Qᵀ R, Qᵀ V); the identity when nothing rotates.
TO_MAP_UNIFORM = "shrmToMap"
_TO_MAP_LINES = [f"  shrmN = {TO_MAP_UNIFORM} * shrmN;", f"  shrmV = {TO_MAP_UNIFORM} * shrmV;",
                 f"  shrmR = {TO_MAP_UNIFORM} * shrmR;"]


def fragment_replacements(
    declarations: Sequence[str], body: Sequence[str], attributes: Sequence[str] = (), *, to_map: bool = True
) -> Replacements:
    """(tag, replacement) pairs for the fragment shader: the prelude, the mode's ``declarations``
    and ``body`` (which sets ``vec3 shrmRad`` from ``shrmN``, ``shrmV``, ``shrmR``), the output.
    ``to_map`` (default): N, V, R are turned into the unrotated environment's frame by the uniform
    :data:`TO_MAP_UNIFORM` before the body; False leaves them in the world frame (the geometry pass).

    The prelude computes, in the z-up world frame (= VTK world frame), N = normalize(interpolated
    normal) flipped on back faces, V = normalize(eye − P) (perspective) or the constant direction
    toward the camera (ortho), R = 2 (N·V) N − V; the mode's body then sets ``vec3 shrmRad``, written
    out as the colour. Uniforms (set per frame by the renderer): ``shrmEye`` (vec3), ``shrmOrtho``
    (int), ``shrmViewDir`` (vec3, toward the camera, used when ortho), and :data:`TO_MAP_UNIFORM`.
    """
    dec = [
        "//VTK::Edges::Dec",
        "in vec3 shrmPosWC;",
        "in vec3 shrmNormWC;",
        *(f"in vec4 {varying(name)};" for name in attributes),
        *declarations,
    ]
    impl = [
        "  vec3 shrmN = normalize(shrmNormWC);",
        "  if (!gl_FrontFacing) shrmN = -shrmN;",
        _VIEW_LINE,
        "  vec3 shrmR = normalize(2.0 * dot(shrmN, shrmV) * shrmN - shrmV);",
        *(_TO_MAP_LINES if to_map else []),
        *body,
        "  gl_FragData[0] = vec4(shrmRad, 1.0);",
    ]
    # declarations go at the last declaration tag before main(), after VTK has declared the
    # texture samplers (//VTK::TMap::Dec); the tag is kept so VTK's own code still lands there
    return [("//VTK::Edges::Dec", "\n".join(dec) + "\n"), ("//VTK::Light::Impl", "\n".join(impl) + "\n")]


def gbuffer_fragment_replacements() -> Replacements:
    """(tag, replacement) pairs of the deferred geometry pass: the prelude's R (unit, z-up
    world frame) times the object's tag, the uniform ``shrmGScale`` (2^(k+1), exact), as the
    colour; alpha 1. The screen pass (:func:`screen_fragment_replacements`) divides it out.

    Deferred shading (the per-pixel modes; :class:`~shrmkit.render.vtk_renderer.SHRMRenderer`): this
    geometry pass writes R scaled by the object's tag ``shrmGScale`` (2^(k+1) for object k: an exact
    scaling) to the float colour buffer; the screen pass draws a quad filling the view, reads R back
    at its pixel (``texelFetch(shrmGbuf, ivec2(gl_FragCoord.xy))``), keeps the pixels of its own tag,
    computes V as the prelude does (the quad's point lies on the same pixel ray as the surface point,
    so eye − P has the same direction) and runs the same body. This pass writes the world R
    (unrotated); the screen pass rotates what it reads back.
    """
    return fragment_replacements([], ["  vec3 shrmRad = shrmR * shrmGScale;"], to_map=False)


def screen_fragment_replacements(declarations: Sequence[str], body: Sequence[str]) -> Replacements:
    """(tag, replacement) pairs of the deferred screen pass of one object, for a quad filling the view.

    Reads the geometry pass at the fragment's pixel (sampler ``shrmGbuf``, texel = pixel), keeps
    the pixels whose |texel / shrmGScale| is 1 (the object's tag; discards the others), with
    R = texel / shrmGScale (exact: a power of two), and V as :func:`fragment_replacements` does from the quad's
    world position (on the pixel's ray, like the surface point), turns R and V into the unrotated
    environment's frame (:data:`TO_MAP_UNIFORM`), then runs ``body`` (which must not read ``shrmN``)
    and writes ``vec4(shrmRad, 1)``.
    """
    dec = ["//VTK::Edges::Dec", "in vec3 shrmPosWC;", "in vec3 shrmNormWC;", *declarations]
    impl = [
        "  vec4 shrmG = texelFetch(shrmGbuf, ivec2(gl_FragCoord.xy), 0);",
        # divide first (exact: a power of two), then measure: |R·2^64|² would overflow float32
        "  vec3 shrmR = shrmG.xyz / shrmGScale;",
        "  if (abs(length(shrmR) - 1.0) > 0.25) discard;",
        _VIEW_LINE,
        *_TO_MAP_LINES[1:],
        *body,
        "  gl_FragData[0] = vec4(shrmRad, 1.0);",
    ]
    return [("//VTK::Edges::Dec", "\n".join(dec) + "\n"), ("//VTK::Light::Impl", "\n".join(impl) + "\n")]


def sh_glsl(lmax: int) -> str:
    """GLSL function ``void shrm_sh(vec3 v, out float Y[n])`` for the real SH up to ``lmax``.

    The real SH of the DESIGN §2 basis, index l² + l + m, as straight-line GLSL:
    Y^r_lm = K_lm h_lm(z) Re (x + iy)^m (m ≥ 0) or Im (x + iy)^|m| (m < 0), with
    K_m = √2 (−1)^m f_mm / sin^m θ and h_lm the normalized-Legendre three-term recurrence of
    :func:`shrmkit.analysis.sh.legendre_f` divided by f_mm (no trigonometric functions).
    """
    n = (lmax + 1) ** 2
    lines = [f"void shrm_sh(vec3 v, out float Y[{n}]) {{", "  float x = v.x, y = v.y, z = v.z;"]
    lines.append("  float c0 = 1.0, s0 = 0.0;")
    fmm = 1.0 / math.sqrt(4.0 * math.pi)  # f_00; f_mm = this * prod(-sqrt((2k+1)/(2k))) * sin^m
    for m in range(lmax + 1):
        if m > 0:
            fmm *= -math.sqrt((2.0 * m + 1.0) / (2.0 * m))
            # (x + iy)^m = (x + iy)^(m-1) (x + iy)
            lines.append(f"  float c{m} = c{m - 1} * x - s{m - 1} * y, s{m} = c{m - 1} * y + s{m - 1} * x;")
        k = fmm if m == 0 else math.sqrt(2.0) * (-1.0) ** m * fmm
        for l in range(m, lmax + 1):
            if l == m:
                expr = "1.0"
            elif l == m + 1:
                expr = f"{glsl_float(math.sqrt(2.0 * m + 3.0))} * z"
            else:
                a_l = math.sqrt((4.0 * l * l - 1.0) / (l * l - m * m))
                a_lm1 = math.sqrt((4.0 * (l - 1) ** 2 - 1.0) / ((l - 1) ** 2 - m * m))
                expr = f"{glsl_float(a_l)} * (z * h{l - 1}_{m} - {glsl_float(1.0 / a_lm1)} * h{l - 2}_{m})"
            lines.append(f"  float h{l}_{m} = {expr};")
            if m == 0:
                lines.append(f"  Y[{l * l + l}] = {glsl_float(k)} * h{l}_0;")
            else:
                lines.append(f"  Y[{l * l + l + m}] = {glsl_float(k)} * h{l}_{m} * c{m};")
                lines.append(f"  Y[{l * l + l - m}] = {glsl_float(k)} * h{l}_{m} * s{m};")
    lines.append("}")
    return "\n".join(lines) + "\n"


#: The bilinear lat-long lookup of ``brdf_io.latlong.bilinear_lookup`` in GLSL: ``latlong_setup``
#: and ``latlong_fetch`` of the WebGL viewer's ``render/webgl/latlong.glsl`` (one source for both
#: renderers), and ``shrm_fetch``, the fetch from the sampler ``shrmTex``. Done with ``texelFetch``
#: (four exact float texels, weights in float32): φ wraps around with no seam, θ is clamped to the
#: first and last row centres; θ = atan2(|R_xy|, R_z) stays accurate at the poles. No hardware
#: filtering or mipmapping is involved, so there is no seam from derivative jumps and no 8-bit
#: weight quantization.
LATLONG_GLSL = resources.files(__package__).joinpath("webgl").joinpath("latlong.glsl").read_text(
    encoding="utf-8") + """
// bilinear fetch from shrmTex at tile offset o (texel units)
vec3 shrm_fetch(ivec2 o, ivec4 idx, vec2 f) {
  return latlong_fetch(shrmTex, o, idx, f);
}
"""
