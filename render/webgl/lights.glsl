// Explicit lights beside the SHRM (DESIGN section 5a; analysis/lights.py light_radiance):
//   B_lights(R, V) = sum_k rho_hat(omega_k; V, N) E_k,   N = normalize(R + V),
// with shrm_brdf_rho_hat of the BRDF's shader (brdf_*.glsl). The samples, in the z-up frame:
// directions shrmLightDir[k] (unit) and RGB powers shrmLightPower[k] (radiance x solid angle),
// k < shrmLightCount <= SHRM_NLIGHTS (#define: the array size, the SHRM's sample count).
uniform int shrmLightCount;
uniform vec3 shrmLightDir[SHRM_NLIGHTS];
uniform vec3 shrmLightPower[SHRM_NLIGHTS];

vec3 shrm_lights(vec3 R, vec3 V) {
  vec3 h = R + V;
  float len = length(h);
  if (!(len > 0.0)) return vec3(0.0);  // R = -V: no surface reflects V into R
  vec3 N = h / len;
  vec3 sum = vec3(0.0);
  for (int k = 0; k < SHRM_NLIGHTS; ++k) {
    if (k >= shrmLightCount) break;
    sum += shrm_brdf_rho_hat(N, shrmLightDir[k], V) * shrmLightPower[k];
  }
  return sum;
}
