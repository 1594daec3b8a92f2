// Helpers of the BRDF shaders (brdf_*.glsl; render/brdf_glsl.py). Every model defines
//   vec3 shrm_brdf_rho_hat(vec3 N, vec3 L, vec3 V)
// = rho_hat(L; V, N), the cosine-weighted transfer function of RH02 section 3.1 for unit
// directions in any one frame (the z-up world frame here): N the surface normal, L toward the
// light, V toward the viewer. The models are isotropic, so only dot products of N, L, V enter:
// no tangent frame is built. What analysis/reference.py computes in the local frame of N.

const float SHRM_PI = 3.14159265358979;

// max(b, 0)^e without overflow or pow(0, 0): 0 where b <= 0 (brdf_io/models.py _safe_pow)
float shrm_safe_pow(float b, float e) {
  return (b > 0.0) ? exp(e * log(b)) : 0.0;
}

vec3 shrm_safe_pow3(vec3 b, vec3 e) {
  return vec3(shrm_safe_pow(b.x, e.x), shrm_safe_pow(b.y, e.y), shrm_safe_pow(b.z, e.z));
}

// log(1 - u) for u in [0, 1), accurate for small u (a series below 1e-2: error < u^4 / 4)
float shrm_log1m(float u) {
  return (u < 1.0e-2) ? -u * (1.0 + u * (0.5 + u / 3.0)) : log(1.0 - u);
}

// (cos, sin) of the angle between unit vectors a and b, the sine from |a x b| (accurate near 0)
vec2 shrm_cos_sin(vec3 a, vec3 b) {
  return vec2(dot(a, b), length(cross(a, b)));
}
