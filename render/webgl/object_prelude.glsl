// The prelude of render/glsl.py fragment_replacements: N = normalize(interpolated normal),
// flipped on back faces; V = normalize(eye - P) (perspective camera); R = 2 (N.V) N - V;
// then all three turned into the unrotated environment's frame by uToMap = Q^T (the lighting
// rotated by Q at view time, brdf_io/env_rotation.py; the identity when it does not turn).
in vec3 vPosition;
in vec3 vNormal;
uniform vec3 uEye;
uniform mat3 uToMap;
out vec4 outColor;

void shrm_geometry(out vec3 N, out vec3 V, out vec3 R) {
  N = normalize(vNormal);
  if (!gl_FrontFacing) N = -N;
  V = normalize(uEye - vPosition);
  R = normalize(2.0 * dot(N, V) * N - V);
  N = uToMap * N;
  V = uToMap * V;
  R = uToMap * R;
}
