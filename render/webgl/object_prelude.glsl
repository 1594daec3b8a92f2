// The prelude of render/glsl.py fragment_replacements: N = normalize(interpolated normal),
// flipped on back faces; V = normalize(eye - P) (perspective camera); R = 2 (N.V) N - V.
in vec3 vPosition;
in vec3 vNormal;
uniform vec3 uEye;
out vec4 outColor;

void shrm_geometry(out vec3 N, out vec3 V, out vec3 R) {
  N = normalize(vNormal);
  if (!gl_FrontFacing) N = -N;
  V = normalize(uEye - vPosition);
  R = normalize(2.0 * dot(N, V) * N - V);
}
