"""GLSL for Green, Kautz & Durand 2007 Gaussian-lobe shading (render mode ``gaussian-lobes``).

The fragment shader evaluates exactly what :meth:`shrmkit.analysis.baselines.gaussian_lobes.
GaussianLobeModel.radiance` computes on the CPU:

    B(R, V) = Σ_n a_n Σ_k w_nk (G_σnk * L)(d_nk),   d_nk = cos θ_μ,nk R + sin θ_μ,nk t,

with t the unit vector toward V perpendicular to R (for V ∥ R: normalize(R × h), h = +z
unless |R_z| ≥ 0.9, then +x), a_n the linear interpolation weights of θ_v = angle(N, V)
between the two neighbouring fitted elevations (clamped to the first/last), and
(G_σ * L) read from the SG mip stack by linear interpolation in log2 σ between two levels.
σ is constant per lobe, so the level pair and its weight are computed once on the CPU.

Storage (all float32, no 8-bit data anywhere):

- the mip stack is one atlas texture (:func:`sg_atlas`): level j (H_j × 2H_j) occupies rows
  [row_j, row_j + H_j) and columns [0, 2H_j), levels stacked top to bottom; each level is
  read with the bilinear lat-long rule of ``brdf_io.latlong.bilinear_lookup`` by four
  ``texelFetch``es (φ wraps, θ clamped to the first/last row centres), as in ``shader``;
- the lobe table (N elevations × K lobes: cos θ_μ, sin θ_μ, RGB weight, level, level weight)
  and the elevation nodes are compiled into the shader as ``const`` arrays (one shader per
  object; float literals with 9 significant digits are exact in float32).

Optional self-shadowing (Green et al. 2007 eq. 7, :mod:`shrmkit.analysis.baselines.selfshadow`):
25 order-4 SH visibility coefficients per vertex arrive as seven ``vec4`` vertex attributes
``glVis0..6`` (the last padded), are interpolated to the fragment, and each lobe is multiplied
by V(d_nk) = clamp(Σ c_i Y^r_i(d_nk), 0, 1), or (``normalized``) the attributes hold the
occlusion coefficients o = step(n_vertex) − c and V = clamp(1 − Σ o_i Y^r_i(d) / S(max(N·d, 0)), 0, 1)
with S the SH-4 truncated hemisphere step (``selfshadow.visibility_at``).
"""

from __future__ import annotations

import numpy as np

from .shader import LATLONG_GLSL, sh_glsl

__all__ = ["sg_atlas", "gaussian_vertex_replacements", "gaussian_fragment_replacements", "N_VIS_ATTRIBUTES"]

#: vec4 vertex attributes carrying the 25 SH-4 visibility coefficients (28 slots, 3 unused).
N_VIS_ATTRIBUTES = 7


def _f(x: float) -> str:
    return f"{float(x):.9e}"


def sg_atlas(levels: tuple[np.ndarray, ...]) -> tuple[np.ndarray, list[int], list[int]]:
    """Stack the mip levels (H_j, 2H_j, 3) into one float32 image; returns (atlas, row offsets, heights).

    The atlas is (Σ H_j, max 2H_j, 3); texel (x, y) of the texture is ``atlas[y, x]``.
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


def gaussian_vertex_replacements(shadow: bool) -> list[tuple[str, str]]:
    """Vertex shader replacements: world position and normal (and the visibility SH when ``shadow``)."""
    dec = ["//VTK::Normal::Dec", "out vec3 shrmPosWC;", "out vec3 shrmNormWC;"]
    impl = ["//VTK::Normal::Impl", "  shrmPosWC = vertexMC.xyz;", "  shrmNormWC = normalMC;"]
    if shadow:
        for i in range(N_VIS_ATTRIBUTES):
            dec += [f"in vec4 glVis{i};", f"out vec4 glVisF{i};"]
            impl.append(f"  glVisF{i} = glVis{i};")
    return [("//VTK::Normal::Dec", "\n".join(dec) + "\n"), ("//VTK::Normal::Impl", "\n".join(impl) + "\n")]


def _const_array(glsl_type: str, name: str, items: list[str]) -> str:
    return f"const {glsl_type} {name}[{len(items)}] = {glsl_type}[](" + ", ".join(items) + ");"


def _lobe_tables(lobes, sigmas: np.ndarray) -> list[str]:
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
    return [
        f"#define GLOBE_N {N}",
        f"#define GLOBE_K {K}",
        _const_array("float", "glNodes", [_f(x) for x in nodes]),
        _const_array("vec2", "glCS", [f"vec2({_f(np.cos(m))}, {_f(np.sin(m))})" for m in mu]),
        _const_array("vec3", "glW", [f"vec3({_f(a)}, {_f(b)}, {_f(c)})" for a, b, c in w]),
        _const_array("int", "glLev", [str(int(j)) for j in j0]),
        _const_array("float", "glLevF", [_f(x) for x in f]),
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

# SH-4 projection of the unoccluded hemisphere about N, as a function of t = N·d (zonal, closed
# form): S(t) = Σ_l (2l+1)/2 (∫_0^1 P_l) P_l(t) = 1/2 + 3t/4 − (7/16) P_3(t)   (l = 2, 4 vanish)
_SHADOW = """
float globe_visibility(vec3 d, vec3 n) {
  float c[28] = float[](glVisF0.x, glVisF0.y, glVisF0.z, glVisF0.w, glVisF1.x, glVisF1.y, glVisF1.z,
    glVisF1.w, glVisF2.x, glVisF2.y, glVisF2.z, glVisF2.w, glVisF3.x, glVisF3.y, glVisF3.z, glVisF3.w,
    glVisF4.x, glVisF4.y, glVisF4.z, glVisF4.w, glVisF5.x, glVisF5.y, glVisF5.z, glVisF5.w,
    glVisF6.x, glVisF6.y, glVisF6.z, glVisF6.w);
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
"""


def gaussian_fragment_replacements(
    lobes, sigmas: np.ndarray, rows: list[int], heights: list[int], *, shadow: bool = False, normalized: bool = True
) -> list[tuple[str, str]]:
    """(tag, replacement) pairs for the fragment shader of one Gaussian-lobe actor.

    Uniforms as in ``shader.fragment_replacements`` (``shrmEye``, ``shrmOrtho``, ``shrmViewDir``);
    sampler ``shrmTex`` holds the mip atlas of :func:`sg_atlas`.
    """
    sigmas = np.asarray(sigmas, dtype=np.float64)
    J = len(sigmas)
    dec = [
        "//VTK::Edges::Dec",
        "in vec3 shrmPosWC;",
        "in vec3 shrmNormWC;",
        f"#define SG_J {J}",
        _const_array("int", "sgRow", [str(r) for r in rows]),
        _const_array("int", "sgH", [str(h) for h in heights]),
        *_lobe_tables(lobes, sigmas),
        _LEVEL,
    ]
    if shadow:
        dec += [f"in vec4 glVisF{i};" for i in range(N_VIS_ATTRIBUTES)]
        dec += [f"#define GLOBE_NORMALIZED {1 if normalized else 0}", sh_glsl(4), _SHADOW]
    lobe_value = "sg_lookup(idx, d)"
    if shadow:
        lobe_value = "sg_lookup(idx, d) * globe_visibility(d, shrmN)"
    impl = [
        "  vec3 shrmN = normalize(shrmNormWC);",
        "  if (!gl_FrontFacing) shrmN = -shrmN;",
        "  vec3 shrmV = (shrmOrtho != 0) ? normalize(shrmViewDir) : normalize(shrmEye - shrmPosWC);",
        "  vec3 shrmR = normalize(2.0 * dot(shrmN, shrmV) * shrmN - shrmV);",
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
        f"      shrmRad += a * glW[idx] * {lobe_value};",
        "    }",
        "  }",
        "  gl_FragData[0] = vec4(shrmRad, 1.0);",
    ]
    return [("//VTK::Edges::Dec", "\n".join(dec) + "\n"), ("//VTK::Light::Impl", "\n".join(impl) + "\n")]
