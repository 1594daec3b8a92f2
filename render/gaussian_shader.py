"""GLSL for the Gaussian-lobe shading of [Green07] (render mode ``gaussian-lobes``).

The fragment shader evaluates exactly what :meth:`shrmkit.analysis.baselines.gaussian_lobes.
GaussianLobeModel.radiance` computes on the CPU (:func:`gaussian_fragment_replacements`), reading
the SG mip stack from one float32 atlas (:func:`sg_atlas`; no 8-bit data anywhere), with optional
self-shadowing by per-vertex SH visibility ([Green07] eq. 7, :func:`gaussian_shading`).
"""

from __future__ import annotations

import numpy as np

from ..analysis.baselines.gaussian_lobes import GaussianLobeModel, GaussianLobes
from ..analysis.baselines.selfshadow import hemisphere_step_sh
from .glsl import (
    LATLONG_GLSL,
    TO_MAP_UNIFORM,
    Shading,
    check_texture_size,
    fragment_replacements,
    glsl_float,
    sh_glsl,
    varying,
    vertex_replacements,
)
from .mesh import Mesh

__all__ = ["sg_atlas", "gaussian_fragment_replacements", "gaussian_shading", "N_VIS_ATTRIBUTES", "VIS_ATTRIBUTES"]

#: vec4 vertex attributes carrying the 25 SH-4 visibility coefficients (28 slots, 3 unused).
N_VIS_ATTRIBUTES = 7
VIS_ATTRIBUTES = tuple(f"glVis{i}" for i in range(N_VIS_ATTRIBUTES))


def sg_atlas(levels: tuple[np.ndarray, ...]) -> tuple[np.ndarray, list[int], list[int]]:
    """Stack the mip levels (H_j, 2H_j, 3) into one float32 image; returns (atlas, row offsets, heights).

    The atlas is (Σ H_j, max 2H_j, 3); texel (x, y) of the texture is ``atlas[y, x]``. Level j
    (H_j × 2H_j) occupies rows [row_j, row_j + H_j) and columns [0, 2H_j), levels stacked top to
    bottom; the shader reads each level with the bilinear lat-long rule of
    ``brdf_io.latlong.bilinear_lookup`` by four ``texelFetch``es (φ wraps, θ clamped to the
    first/last row centres), as in ``render.glsl``.
    """
    heights = [int(level.shape[0]) for level in levels]
    rows = [int(r) for r in np.concatenate([[0], np.cumsum(heights)[:-1]])]
    width = max(int(level.shape[1]) for level in levels)
    out = np.zeros((sum(heights), width, 3), dtype=np.float32)
    for level, r in zip(levels, rows, strict=True):
        if level.shape[1] != 2 * level.shape[0]:
            raise ValueError(f"mip level must be H x 2H, got {level.shape[:2]}")
        out[r:r + level.shape[0], :level.shape[1]] = level
    return out, rows, heights


def _const_array(glsl_type: str, name: str, items: list[str]) -> str:
    return f"const {glsl_type} {name}[{len(items)}] = {glsl_type}[](" + ", ".join(items) + ");"


def _lobe_tables(lobes: GaussianLobes, sigmas: np.ndarray) -> list[str]:
    N, K = lobes.mu.shape
    J = len(sigmas)
    mu = lobes.mu.reshape(-1)
    sig = lobes.sigma.reshape(-1)
    w = lobes.weight.reshape(-1, 3)
    # level pair and weight exactly as SGMipStack.lookup
    t = np.clip(np.log2(np.maximum(sig, 1e-300) / sigmas[0]), 0.0, J - 1.0)
    j0 = np.minimum(np.floor(t).astype(np.int64), max(J - 2, 0))
    f = t - j0
    nodes = np.asarray(lobes.theta_v, dtype=np.float64)
    g = glsl_float
    return [
        f"#define GLOBE_N {N}",
        f"#define GLOBE_K {K}",
        _const_array("float", "glNodes", [g(x) for x in nodes]),
        _const_array("vec2", "glCS", [f"vec2({g(np.cos(m))}, {g(np.sin(m))})" for m in mu]),
        _const_array("vec3", "glW", [f"vec3({g(a)}, {g(b)}, {g(c)})" for a, b, c in w]),
        _const_array("int", "glLev", [str(int(j)) for j in j0]),
        _const_array("float", "glLevF", [g(x) for x in f]),
    ]


_LEVEL = LATLONG_GLSL + """
vec3 sg_level(int j, vec3 d) {
  ivec4 idx;
  vec2 f;
  latlong_setup(d, sgH[j], 2 * sgH[j], idx, f);
  return shrm_fetch(ivec2(0, sgRow[j]), idx, f);
}
vec3 sg_lookup(int idx, vec3 d) {
  int j0 = glLev[idx];
  float f = glLevF[idx];
  vec3 v = sg_level(j0, d) * (1.0 - f);
  if (f > 0.0) v += sg_level(j0 + 1, d) * f;
  return v;
}
"""

_VIS_COEFFS = ", ".join(f"{varying(name)}.{c}" for name in VIS_ATTRIBUTES for c in "xyzw")

# SH-4 projection of the unoccluded hemisphere about N, as a function of t = N·d (zonal, closed
# form): S(t) = Σ_l (2l+1)/2 (∫_0^1 P_l) P_l(t) = 1/2 + 3t/4 − (7/16) P_3(t)   (l = 2, 4 vanish)
_SHADOW = """
float globe_visibility(vec3 d, vec3 n) {
  float c[GLOBE_NC] = float[](GLOBE_COEFFS);
  float Y[25];
  shrm_sh(d, Y);
  float v = 0.0;
  for (int i = 0; i < 25; ++i) v += c[i] * Y[i];
#if GLOBE_NORMALIZED
  // c holds occlusion coefficients (vertex step - visibility): V = 1 - O(d) / S(n.d)
  float t = max(dot(n, d), 0.0);
  float s = 0.5 + 0.75 * t - 0.4375 * 0.5 * (5.0 * t * t * t - 3.0 * t);
  v = 1.0 - v / s;
#endif
  return clamp(v, 0.0, 1.0);
}
""".replace("GLOBE_NC", str(4 * N_VIS_ATTRIBUTES)).replace("GLOBE_COEFFS", _VIS_COEFFS)

_BODY = [
    "  float cosO = clamp(dot(shrmR, shrmV), -1.0, 1.0);",
    # θ_v = angle(N, V) = ½ angle(R, V), via atan2 (accurate near 0, unlike acos)
    "  float tv = atan(length(cross(shrmN, shrmV)), dot(shrmN, shrmV));",
    "  vec3 tt = shrmV - cosO * shrmR;",
    "  float tn = length(tt);",
    "  vec3 helper = (abs(shrmR.z) < 0.9) ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);",
    "  tt = (tn > 1e-7) ? tt / tn : normalize(cross(shrmR, helper));",
    "  float pos = 0.0;",
    "  if (GLOBE_N > 1) {",
    "    if (tv >= glNodes[GLOBE_N - 1]) pos = float(GLOBE_N - 1);",
    "    else if (tv > glNodes[0]) {",
    "      for (int n = 0; n < GLOBE_N - 1; ++n) {",
    "        if (tv < glNodes[n + 1]) {",
    "          pos = float(n) + (tv - glNodes[n]) / (glNodes[n + 1] - glNodes[n]);",
    "          break;",
    "        }",
    "      }",
    "    }",
    "  }",
    "  int n0 = min(int(floor(pos)), max(GLOBE_N - 2, 0));",
    "  float fe = pos - float(n0);",
    "  vec3 shrmRad = vec3(0.0);",
    "  for (int e = 0; e < 2; ++e) {",
    "    int n = n0 + e;",
    "    float a = (e == 0) ? 1.0 - fe : fe;",
    "    if (a <= 0.0 || n >= GLOBE_N) continue;",
    "    for (int k = 0; k < GLOBE_K; ++k) {",
    "      int idx = n * GLOBE_K + k;",
    "      vec3 d = glCS[idx].x * shrmR + glCS[idx].y * tt;",
    "      shrmRad += a * glW[idx] * GLOBE_LOBE_VALUE;",
    "    }",
    "  }",
]


def gaussian_fragment_replacements(
    lobes: GaussianLobes, sigmas: np.ndarray, rows: list[int], heights: list[int], *, shadow: bool = False,
    normalized: bool = True,
) -> list[tuple[str, str]]:
    """(tag, replacement) pairs for the fragment shader of one Gaussian-lobe actor.

    Uniforms and prelude as in ``render.glsl``; sampler ``shrmTex`` holds the mip atlas of
    :func:`sg_atlas`; with ``shadow`` the varyings of :data:`VIS_ATTRIBUTES` hold the visibility
    (:func:`gaussian_shading`). The shader computes

        B(R, V) = Σ_n a_n Σ_k w_nk (G_σnk * L)(d_nk),   d_nk = cos θ_μ,nk R + sin θ_μ,nk t,

    with t the unit vector toward V perpendicular to R (for V ∥ R: normalize(R × h), h = +z
    unless |R_z| ≥ 0.9, then +x), a_n the linear interpolation weights of θ_v = angle(N, V)
    between the two neighbouring fitted elevations (clamped to the first/last), and (G_σ * L)
    read from the SG mip stack by linear interpolation in log2 σ between two levels. σ is
    constant per lobe, so the level pair and its weight are computed once on the CPU. The lobe
    table (N elevations × K lobes: cos θ_μ, sin θ_μ, RGB weight, level, level weight) and the
    elevation nodes are compiled into the shader as ``const`` arrays (one shader per object;
    float literals with 9 significant digits are exact in float32).
    """
    sigmas = np.asarray(sigmas, dtype=np.float64)
    dec = [
        f"#define SG_J {len(sigmas)}",
        _const_array("int", "sgRow", [str(r) for r in rows]),
        _const_array("int", "sgH", [str(h) for h in heights]),
        *_lobe_tables(lobes, sigmas),
        _LEVEL,
    ]
    if shadow:
        dec += [f"#define GLOBE_NORMALIZED {1 if normalized else 0}", sh_glsl(4), _SHADOW,
                # the visibility is the mesh's, in the world frame: d and N back from the (rotated)
                # environment's frame, Q d = d * Qᵀ (render.glsl.TO_MAP_UNIFORM)
                f"#define GLOBE_LOBE_VALUE (sg_lookup(idx, d) * globe_visibility(d * {TO_MAP_UNIFORM}, "
                f"shrmN * {TO_MAP_UNIFORM}))"]
    else:
        dec.append("#define GLOBE_LOBE_VALUE sg_lookup(idx, d)")
    return fragment_replacements(dec, _BODY, VIS_ATTRIBUTES if shadow else ())


def gaussian_shading(
    model: GaussianLobeModel, mesh: Mesh, visibility_sh: np.ndarray | None = None, normalized: bool = True
) -> Shading:
    """[Green07]: mip atlas texture + lobe table compiled into the fragment shader.

    ``visibility_sh`` (n_vertices, 25) turns on self-shadowing ([Green07] eq. 7,
    :mod:`shrmkit.analysis.baselines.selfshadow`): the 25 order-4 SH visibility coefficients per
    vertex arrive as seven ``vec4`` vertex attributes ``glVis0..6`` (the last padded), are
    interpolated to the fragment (varyings ``glVis0_f..6_f``, ``render.glsl.varying``), and each
    lobe is multiplied by V(d_nk) = clamp(Σ c_i Y^r_i(d_nk), 0, 1); with ``normalized`` the
    attributes hold the occlusion coefficients o = step(n_vertex) − c and
    V = clamp(1 − Σ o_i Y^r_i(d) / S(max(N·d, 0)), 0, 1), S the SH-4 truncated hemisphere step
    (``selfshadow.visibility_at``). Under a rotated environment (``render.glsl.TO_MAP_UNIFORM``)
    the lobes are read in the map's frame and the visibility, the mesh's own, at the world
    direction Q d_nk.
    """
    image, rows, heights = sg_atlas(model.stack.levels)
    check_texture_size(image.shape, "SG mip atlas")
    attributes: dict[str, np.ndarray] = {}
    if visibility_sh is not None:
        coeffs = hemisphere_step_sh(mesh.normals, 4) - visibility_sh if normalized else visibility_sh
        padded = np.zeros((coeffs.shape[0], 4 * N_VIS_ATTRIBUTES), dtype=np.float32)
        padded[:, :coeffs.shape[1]] = coeffs
        attributes = {name: np.ascontiguousarray(padded[:, 4 * i:4 * i + 4]) for i, name in enumerate(VIS_ATTRIBUTES)}
    shadow = bool(attributes)
    fragment = gaussian_fragment_replacements(
        model.lobes, model.stack.sigmas, rows, heights, shadow=shadow, normalized=normalized
    )
    return Shading(image, vertex_replacements(tuple(attributes)), fragment, attributes)
