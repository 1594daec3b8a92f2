// A tabulated BRDF (measured: MERL, RGL, tables; render/brdf_glsl.py BrdfTable): rho in
// Rusinkiewicz's half/difference angles (brdf_io/halfdiff.py), trilinear in the table's indices
//   u = (NH - 1) sqrt(theta_h / (pi/2)),  v = (ND - 1) theta_d / (pi/2),  w = (NP - 1) |phi_d| / pi
// (theta_h on a square-root scale as MERL's; phi_d folded by the mirror symmetry of an isotropic
// BRDF, rho(phi_d) = rho(-phi_d)), each clamped to the table, 8 exact texels by texelFetch; with
// SHRM_TAB_PERIODIC 1, w = NP (phi_d mod pi) / pi, periodic (MERL's reciprocity fold, phi_d ~ phi_d + pi).
// The table is a 2-D atlas of NH tiles of NP x ND texels (phi_d along x, theta_d along y): tile i
// (theta_h index) at column (i mod COLS) NP, row (i div COLS) ND; values rho x shrmBrdfScale.
// The texels hold rho (N.L)(N.V) (bounded where rho grows like 1/cos toward the horizon, as RGL
// materials do); rho_hat = texel / N.V where N.L > 0 and N.V > 0. #defines SHRM_TAB_NH, SHRM_TAB_ND, SHRM_TAB_NP,
// SHRM_TAB_COLS, SHRM_TAB_PERIODIC; sampler shrmBrdfTex (declared here unless SHRM_VTK).
#ifndef SHRM_VTK  // VTK declares the samplers of the textures it binds
uniform highp sampler2D shrmBrdfTex;
#endif
uniform float shrmBrdfScale;

vec3 shrm_tab_fetch(int i, int j, int k) {
  return texelFetch(shrmBrdfTex, ivec2((i % SHRM_TAB_COLS) * SHRM_TAB_NP + k, (i / SHRM_TAB_COLS) * SHRM_TAB_ND + j),
                    0).rgb;
}

// lower index (clamped so that index + 1 is in the table) and fraction of a continuous index x
void shrm_tab_axis(float x, int n, out int i0, out float f) {
  float xc = clamp(x, 0.0, float(n - 1));
  float lo = min(floor(xc), float(max(n - 2, 0)));
  i0 = int(lo);
  f = xc - lo;
}

vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V) {
  float ci = dot(N, L);
  float co = dot(N, V);
  if (!(ci > 0.0 && co > 0.0)) return vec3(0.0);
  vec3 h = L + V;
  float len = length(h);
  if (!(len > 0.0)) return vec3(0.0);
  vec3 H = h / len;
  // the difference frame about H: y' = N x H / |N x H| (normal to the plane of N and H), x' = y' x H
  vec3 y = cross(N, H);
  float sh = length(y);
  if (sh > 0.0) {
    y /= sh;
  } else {  // theta_h = 0: rho does not depend on phi_d there; any axis normal to N
    vec3 a = (abs(N.z) < 0.9) ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
    y = normalize(cross(N, a));
  }
  vec3 x = cross(y, H);
  float th = atan(sh, dot(N, H));
  float dx = dot(L, x);
  float dy = dot(L, y);
  float td = atan(length(vec2(dx, dy)), dot(L, H));
  const float HALF_PI = 1.5707963267948966;
  int i, j, k;
  float fu, fv, fw;
  shrm_tab_axis(float(SHRM_TAB_NH - 1) * sqrt(clamp(th / HALF_PI, 0.0, 1.0)), SHRM_TAB_NH, i, fu);
  shrm_tab_axis(float(SHRM_TAB_ND - 1) * td / HALF_PI, SHRM_TAB_ND, j, fv);
#if SHRM_TAB_PERIODIC
  float wp = mod(atan(dy, dx), SHRM_PI) * (float(SHRM_TAB_NP) / SHRM_PI);
  k = min(int(floor(wp)), SHRM_TAB_NP - 1);
  fw = wp - float(k);
  int k1 = (k + 1 < SHRM_TAB_NP) ? k + 1 : 0;
#else
  shrm_tab_axis(float(SHRM_TAB_NP - 1) * abs(atan(dy, dx)) / SHRM_PI, SHRM_TAB_NP, k, fw);
  int k1 = min(k + 1, SHRM_TAB_NP - 1);
#endif
  int i1 = min(i + 1, SHRM_TAB_NH - 1), j1 = min(j + 1, SHRM_TAB_ND - 1);
  vec3 c00 = mix(shrm_tab_fetch(i, j, k), shrm_tab_fetch(i, j, k1), fw);
  vec3 c01 = mix(shrm_tab_fetch(i, j1, k), shrm_tab_fetch(i, j1, k1), fw);
  vec3 c10 = mix(shrm_tab_fetch(i1, j, k), shrm_tab_fetch(i1, j, k1), fw);
  vec3 c11 = mix(shrm_tab_fetch(i1, j1, k), shrm_tab_fetch(i1, j1, k1), fw);
  vec3 rho = mix(mix(c00, c01, fv), mix(c10, c11, fv), fu);
  // the table holds rho cos(theta_L) cos(theta_V) (bounded near the horizon): rho_hat = that / cos(theta_V)
  return rho / (max(co, 1e-6) * shrmBrdfScale);
}
