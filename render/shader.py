"""GLSL for SHRM shading, inserted into VTK's polydata shaders as shader replacements.

Per fragment (RH02 §5, DESIGN §5), all in the z-up world frame (= VTK world frame, the
mesh is uploaded in world coordinates so model coordinates are world coordinates):

- N = normalize(interpolated vertex normal), flipped on back faces;
- V = normalize(eye − P) (perspective) or the constant direction toward the camera (ortho);
- R = 2 (N·V) N − V, so that N = normalize(R + V);
- ``distant`` mode (RH02 eq. 12): radiance = M(R) with M = Σ B̃_pq Y^r_pq(Ṽ) one lat-long map
  per frame (computed on the CPU, uploaded as a float texture);
- ``perpixel`` mode (RH02 eq. 8): radiance = Σ B̃_pq(R) Y^r_pq(V), the (P+1)² coefficient
  maps tiled in one float texture (tile c at column (c mod cols)·W, row (c div cols)·H) and
  Y^r_pq(V) evaluated in the shader.

Lat-long lookup is the bilinear interpolation of :func:`shrmkit.brdf_io.latlong.bilinear_lookup`
done with ``texelFetch`` (four exact float texels, weights in float32): φ wraps around with no
seam, θ is clamped to the first and last row centres; θ = atan2(|R_xy|, R_z) stays accurate
at the poles. No hardware filtering or mipmapping is involved, so there is no seam from
derivative jumps and no 8-bit weight quantization.

The real SH (DESIGN §2 basis, index l² + l + m) are generated as straight-line GLSL:
Y^r_lm = K_lm h_lm(z) Re (x + iy)^m (m ≥ 0) or Im (x + iy)^|m| (m < 0), with
K_m = √2 (−1)^m f_mm / sin^m θ and h_lm the normalized-Legendre three-term recurrence of
:func:`shrmkit.analysis.sh.legendre_f` divided by f_mm (no trigonometric functions).
"""

from __future__ import annotations

import math

__all__ = [
    "sh_glsl",
    "vertex_replacements",
    "fragment_replacements",
    "atlas_layout",
    "MODES",
]

MODES = ("distant", "perpixel")


def _f(x: float) -> str:
    return f"{x:.9e}"


def sh_glsl(lmax: int) -> str:
    """GLSL function ``void shrm_sh(vec3 v, out float Y[n])`` for the real SH up to ``lmax``."""
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
                expr = f"{_f(math.sqrt(2.0 * m + 3.0))} * z"
            else:
                a_l = math.sqrt((4.0 * l * l - 1.0) / (l * l - m * m))
                a_lm1 = math.sqrt((4.0 * (l - 1) ** 2 - 1.0) / ((l - 1) ** 2 - m * m))
                expr = f"{_f(a_l)} * (z * h{l - 1}_{m} - {_f(1.0 / a_lm1)} * h{l - 2}_{m})"
            lines.append(f"  float h{l}_{m} = {expr};")
            if m == 0:
                lines.append(f"  Y[{l * l + l}] = {_f(k)} * h{l}_0;")
            else:
                lines.append(f"  Y[{l * l + l + m}] = {_f(k)} * h{l}_{m} * c{m};")
                lines.append(f"  Y[{l * l + l - m}] = {_f(k)} * h{l}_{m} * s{m};")
    lines.append("}")
    return "\n".join(lines) + "\n"


def atlas_layout(n_tiles: int) -> tuple[int, int]:
    """(columns, rows) of the tile grid holding ``n_tiles`` coefficient maps."""
    cols = max(1, math.ceil(math.sqrt(n_tiles)))
    rows = math.ceil(n_tiles / cols)
    return cols, rows


def vertex_replacements() -> list[tuple[str, str]]:
    """(tag, replacement) pairs for the vertex shader: pass world position and normal on.

    The actor's model matrix is the identity (meshes are uploaded in world coordinates and
    VBO shift/scale is disabled), so ``vertexMC`` and ``normalMC`` are world-space.
    """
    return [
        ("//VTK::Normal::Dec", "//VTK::Normal::Dec\nout vec3 shrmPosWC;\nout vec3 shrmNormWC;\n"),
        ("//VTK::Normal::Impl", "//VTK::Normal::Impl\n  shrmPosWC = vertexMC.xyz;\n  shrmNormWC = normalMC;\n"),
    ]


LATLONG_GLSL = """
// bilinear lat-long lookup set-up (brdf_io.latlong.bilinear_lookup) on an H x W tile:
// texel columns x0, x1 (phi wraps), rows y0, y1 (theta clamped to the first/last row centre),
// weights f = (fx, fy)
void latlong_setup(vec3 d, int H, int W, out ivec4 idx, out vec2 f) {
  const float PI = 3.14159265358979;
  float rxy = length(d.xy);
  float theta = atan(rxy, d.z);
  float phi = (rxy > 0.0) ? atan(d.y, d.x) : 0.0;
  if (phi < 0.0) phi += 2.0 * PI;
  float yy = clamp(theta * float(H) / PI - 0.5, 0.0, float(H) - 1.0);
  float xx = phi * float(W) / (2.0 * PI) - 0.5;
  float y0f = min(floor(yy), float(max(H - 2, 0)));
  float x0f = floor(xx);
  int x0 = int(x0f);
  x0 = x0 - W * int(floor(float(x0) / float(W)));
  int x1 = x0 + 1;
  if (x1 >= W) x1 -= W;
  int y0 = int(y0f);
  int y1 = min(y0 + 1, H - 1);
  idx = ivec4(x0, x1, y0, y1);
  f = vec2(xx - x0f, yy - y0f);
}
// bilinear fetch from shrmTex at tile offset o (texel units)
vec3 shrm_fetch(ivec2 o, ivec4 idx, vec2 f) {
  vec3 t00 = texelFetch(shrmTex, o + ivec2(idx.x, idx.z), 0).rgb;
  vec3 t01 = texelFetch(shrmTex, o + ivec2(idx.y, idx.z), 0).rgb;
  vec3 t10 = texelFetch(shrmTex, o + ivec2(idx.x, idx.w), 0).rgb;
  vec3 t11 = texelFetch(shrmTex, o + ivec2(idx.y, idx.w), 0).rgb;
  vec3 top = t00 * (1.0 - f.x) + t01 * f.x;
  vec3 bottom = t10 * (1.0 - f.x) + t11 * f.x;
  return top * (1.0 - f.y) + bottom * f.y;
}
"""

_LOOKUP = LATLONG_GLSL + """
void shrm_setup(vec3 d, out ivec4 idx, out vec2 f) {
  latlong_setup(d, SHRM_H, SHRM_W, idx, f);
}
"""


def fragment_replacements(mode: str, lmax: int, height: int, width: int) -> list[tuple[str, str]]:
    """(tag, replacement) pairs for the fragment shader of one SHRM actor.

    Uniforms (set per frame as custom uniforms): ``shrmEye`` (vec3), ``shrmOrtho`` (int),
    ``shrmViewDir`` (vec3, toward the camera, used when ortho). Sampler ``shrmTex``: the
    dynamic map (distant) or the coefficient atlas (perpixel).
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    n = (lmax + 1) ** 2
    cols, _ = atlas_layout(n)
    dec = [
        "//VTK::Edges::Dec",
        "in vec3 shrmPosWC;",
        "in vec3 shrmNormWC;",
        f"#define SHRM_H {int(height)}",
        f"#define SHRM_W {int(width)}",
        f"#define SHRM_COLS {cols}",
        f"#define SHRM_NC {n}",
        _LOOKUP,
    ]
    if mode == "perpixel":
        dec.append(sh_glsl(lmax))
    impl = [
        "  vec3 shrmN = normalize(shrmNormWC);",
        "  if (!gl_FrontFacing) shrmN = -shrmN;",
        "  vec3 shrmV = (shrmOrtho != 0) ? normalize(shrmViewDir) : normalize(shrmEye - shrmPosWC);",
        "  vec3 shrmR = normalize(2.0 * dot(shrmN, shrmV) * shrmN - shrmV);",
        "  ivec4 shrmIdx; vec2 shrmF;",
        "  shrm_setup(shrmR, shrmIdx, shrmF);",
    ]
    if mode == "distant":
        impl.append("  vec3 shrmRad = shrm_fetch(ivec2(0, 0), shrmIdx, shrmF);")
    else:
        impl += [
            "  float shrmY[SHRM_NC];",
            "  shrm_sh(shrmV, shrmY);",
            "  vec3 shrmRad = vec3(0.0);",
            "  for (int c = 0; c < SHRM_NC; ++c) {",
            "    ivec2 o = ivec2((c % SHRM_COLS) * SHRM_W, (c / SHRM_COLS) * SHRM_H);",
            "    shrmRad += shrmY[c] * shrm_fetch(o, shrmIdx, shrmF);",
            "  }",
        ]
    impl.append("  gl_FragData[0] = vec4(shrmRad, 1.0);")
    # declarations go at the last declaration tag before main(), after VTK has declared the
    # texture samplers (//VTK::TMap::Dec); the tag is kept so VTK's own code still lands there
    return [("//VTK::Edges::Dec", "\n".join(dec) + "\n"), ("//VTK::Light::Impl", "\n".join(impl) + "\n")]
