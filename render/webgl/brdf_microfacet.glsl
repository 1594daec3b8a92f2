// RH02 eq. 11 simplified microfacet (brdf_io/models.py SimplifiedMicrofacet):
// rho_hat = ks exp(-(theta_h / sigma)^2) / (4 pi sigma^2), theta_h the angle between N and
// H = normalize(L + V) (from atan(|N x H|, N.H): accurate for small angles), 0 unless N.L > 0
// and N.V > 0.
uniform float shrmMicrofacetSigma;
uniform vec3 shrmMicrofacetKs;

vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V) {
  if (!(dot(N, L) > 0.0 && dot(N, V) > 0.0)) return vec3(0.0);
  vec3 h = L + V;
  float len = length(h);
  vec3 H = (len > 0.0) ? h / len : vec3(0.0);
  vec2 cs = shrm_cos_sin(N, H);
  float t = atan(cs.y, cs.x) / shrmMicrofacetSigma;
  float s2 = shrmMicrofacetSigma * shrmMicrofacetSigma;
  return (exp(-t * t) / (4.0 * SHRM_PI * s2)) * shrmMicrofacetKs;
}
