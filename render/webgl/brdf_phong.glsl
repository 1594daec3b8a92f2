// RH02 Phong lobe (brdf_io/models.py PhongLobe): rho_hat = ks (s + 1)/(2 pi) max(R_m . L, 0)^s,
// R_m = 2 (N.V) N - V the mirror direction of V; no horizon clipping (the model defines rho_hat).
// R_m . L = 1 - |R_m - L|^2 / 2, and log(R_m . L) = log(1 - u) by a series for small u, so a
// sharp lobe (large s) keeps its float32 accuracy near its peak.
uniform float shrmPhongS;
uniform vec3 shrmPhongKs;

vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V) {
  vec3 Rm = 2.0 * dot(N, V) * N - V;
  vec3 d = Rm - L;
  float u = 0.5 * dot(d, d);  // 1 - R_m . L
  float lobe = (u < 1.0) ? exp(shrmPhongS * shrm_log1m(u)) : 0.0;
  return ((shrmPhongS + 1.0) / (2.0 * SHRM_PI)) * lobe * shrmPhongKs;
}
