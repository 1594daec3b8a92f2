// Per-pixel SHRM (RH02 eq. 8): B(R, V) = sum_c Y^r_c(V) B~_c(R) over the (P+1)^2 coefficient
// maps, c = p^2 + p + q, tiled in the atlas uCoef (tile c at column (c mod SHRM_COLS) * SHRM_W,
// row (c div SHRM_COLS) * SHRM_H: render/shader.py coefficient_atlas), each looked up with the
// bilinear lat-long rule at the same texel positions (idx, f from latlong_setup(R)).
// The real SH are those of analysis.sh.real_sph_harm (DESIGN §2), by the recurrence of
// render/glsl.py sh_glsl written as loops: Y^r_pm = K_m h_pm(z) Re (x + iy)^m (m >= 0) or
// Im (x + iy)^|m| (m < 0), K_0 = f_00, K_m = sqrt(2) (-1)^m f_mm / sin^m(theta), f_mm the
// normalized associated Legendre value, h_pm the three-term recurrence divided by f_mm.
// Needs SHRM_P, SHRM_H, SHRM_W, SHRM_COLS (#defines) and uniform sampler uCoef.
uniform highp sampler2D uCoef;

vec3 shrm_tile(int c, ivec4 idx, vec2 f) {
  ivec2 o = ivec2((c % SHRM_COLS) * SHRM_W, (c / SHRM_COLS) * SHRM_H);
  return latlong_fetch(uCoef, o, idx, f);
}

vec3 shrm_sum(vec3 v, ivec4 idx, vec2 f) {
  float x = v.x, y = v.y, z = v.z;
  vec3 sum = vec3(0.0);
  float cm = 1.0, sm = 0.0;            // Re and Im of (x + iy)^m
  float fmm = 0.28209479177387814;     // f_00 = 1 / sqrt(4 pi)
  for (int m = 0; m <= SHRM_P; ++m) {
    float fm = float(m);
    if (m > 0) {
      fmm *= -sqrt((2.0 * fm + 1.0) / (2.0 * fm));
      float c = cm * x - sm * y;
      float s = cm * y + sm * x;
      cm = c;
      sm = s;
    }
    float k = (m == 0) ? fmm : 1.4142135623730951 * ((m % 2 == 1) ? -1.0 : 1.0) * fmm;
    float h1 = 0.0, h2 = 0.0;          // h_{l-1, m}, h_{l-2, m}
    for (int l = m; l <= SHRM_P; ++l) {
      float fl = float(l);
      float h;
      if (l == m) {
        h = 1.0;
      } else if (l == m + 1) {
        h = sqrt(2.0 * fm + 3.0) * z;
      } else {
        float a = sqrt((4.0 * fl * fl - 1.0) / (fl * fl - fm * fm));
        float b = sqrt((4.0 * (fl - 1.0) * (fl - 1.0) - 1.0) / ((fl - 1.0) * (fl - 1.0) - fm * fm));
        h = a * (z * h1 - h2 / b);
      }
      int c0 = l * l + l;
      if (m == 0) {
        sum += (k * h) * shrm_tile(c0, idx, f);
      } else {
        sum += (k * h * cm) * shrm_tile(c0 + m, idx, f);
        sum += (k * h * sm) * shrm_tile(c0 - m, idx, f);
      }
      h2 = h1;
      h1 = h;
    }
  }
  return sum;
}
