// Lambert (brdf_io/models.py Lambert): rho = albedo / pi, rho_hat = rho N.L where N.L > 0 and N.V > 0.
uniform vec3 shrmLambertAlbedo;

vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V) {
  float ci = dot(N, L);
  if (!(ci > 0.0 && dot(N, V) > 0.0)) return vec3(0.0);
  return shrmLambertAlbedo * (ci / SHRM_PI);
}
