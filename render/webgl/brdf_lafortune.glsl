// Lafortune et al. 1997, isotropic (brdf_io/models.py Lafortune):
// rho = kd / pi + sum_k ks_k max(Cxy_k (LxVx + LyVy) + Cz_k LzVz, 0)^n_k per channel, in the
// frame of N: LzVz = (N.L)(N.V) and LxVx + LyVy = L.V - (N.L)(N.V); rho_hat = rho N.L where
// N.L > 0 and N.V > 0. SHRM_LAF_LOBES (#define, >= 1) lobes in the uniform arrays.
uniform vec3 shrmLafKd;
uniform vec3 shrmLafCxy[SHRM_LAF_LOBES];
uniform vec3 shrmLafCz[SHRM_LAF_LOBES];
uniform vec3 shrmLafN[SHRM_LAF_LOBES];
uniform vec3 shrmLafKs[SHRM_LAF_LOBES];

vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V) {
  float ci = dot(N, L);
  float co = dot(N, V);
  if (!(ci > 0.0 && co > 0.0)) return vec3(0.0);
  float dz = ci * co;
  float dxy = dot(L, V) - dz;
  vec3 rho = shrmLafKd / SHRM_PI;
  for (int k = 0; k < SHRM_LAF_LOBES; ++k) {
    rho += shrmLafKs[k] * shrm_safe_pow3(shrmLafCxy[k] * dxy + shrmLafCz[k] * dz, shrmLafN[k]);
  }
  return rho * ci;
}
