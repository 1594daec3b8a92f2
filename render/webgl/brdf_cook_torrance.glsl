// Cook-Torrance + Lambert (brdf_io/models.py CookTorrance): rho = kd / pi + ks D(theta_h)
// F(L.H) G1(N.L) G1(N.V) / (4 N.L N.V), Schlick F = f0 + (1 - f0)(1 - L.H)^5, Smith G1 / cos of
// smith_g1_over_cos (GGX exact; Beckmann: Walter et al. 2007's rational approximation);
// rho_hat = rho N.L where N.L > 0 and N.V > 0. SHRM_CT_GGX (#define) 1: GGX, 0: Beckmann.
// cos^2 theta_h is clipped below at 1e-24 (cos at 1e-12) and D is 0 where N.H <= 0, as the model;
// sin^2 theta_h comes from |N x H|^2 (accurate for small roughness).
uniform vec3 shrmCtKd;
uniform vec3 shrmCtKs;
uniform vec3 shrmCtF0;
uniform float shrmCtAlpha;

float shrm_ct_g1_over_cos(float cos_t) {
  float c = clamp(cos_t, 0.0, 1.0);
  float s = sqrt(max(1.0 - c * c, 0.0));
  float a = shrmCtAlpha;
#if SHRM_CT_GGX
  return 2.0 / (c + sqrt(c * c + a * a * s * s));
#else
  if (!(s > 0.0)) return 1.0 / c;
  float q = c / (a * s);
  if (q < 1.6) return (3.535 + 2.181 * q) / (a * s * (1.0 + 2.276 * q + 2.577 * q * q));
  return (c > 0.0) ? 1.0 / c : 1.0;
#endif
}

vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V) {
  float ci = dot(N, L);
  float co = dot(N, V);
  if (!(ci > 0.0 && co > 0.0)) return vec3(0.0);
  vec3 h = L + V;
  float len = length(h);
  vec3 H = (len > 0.0) ? h / len : vec3(0.0);
  vec2 cs = shrm_cos_sin(N, H);
  float a2 = shrmCtAlpha * shrmCtAlpha;
  float D = 0.0;
  if (cs.x > 0.0) {
    float c2 = max(min(cs.x, 1.0) * min(cs.x, 1.0), 1.0e-24);
    float s2 = cs.y * cs.y;
#if SHRM_CT_GGX
    float q = a2 * c2 + s2;  // c2 (a2 - 1) + 1
    D = a2 / (SHRM_PI * q * q);
#else
    D = exp(-s2 / (c2 * a2)) / (SHRM_PI * a2 * c2 * c2);
#endif
  }
  float cd = clamp(dot(L, H), 0.0, 1.0);
  float m = 1.0 - cd;
  float m5 = m * m * m * m * m;
  vec3 fresnel = shrmCtF0 + (1.0 - shrmCtF0) * m5;
  float spec = D * shrm_ct_g1_over_cos(ci) * shrm_ct_g1_over_cos(co) / 4.0;
  return (shrmCtKd / SHRM_PI + spec * fresnel * shrmCtKs) * ci;
}
