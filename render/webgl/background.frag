// The environment seen along each camera ray (render/output.py environment_background):
// the ray through the pixel centre is normalize(forward + t (x a right + y up)) with
// x = (2j + 1)/W - 1, y = 1 - (2i + 1)/H (render/camera.py Camera.rays), i.e. the NDC of
// gl_FragCoord; the map (times uEnvScale, half floats) is looked up with the bilinear rule, at
// uToMap d = Q^T d when the lighting is rotated by Q (object_prelude.glsl).
uniform vec3 uForward;
uniform vec3 uRight;
uniform vec3 uUp;
uniform float uTanY;
uniform vec2 uSize;
uniform highp sampler2D uEnv;
uniform float uEnvScale;
uniform mat3 uToMap;
out vec4 outColor;

void main() {
  float aspect = uSize.x / uSize.y;
  vec2 ndc = 2.0 * gl_FragCoord.xy / uSize - 1.0;
  vec3 d = uToMap * normalize(uForward + uTanY * (ndc.x * aspect * uRight + ndc.y * uUp));
  ivec2 size = textureSize(uEnv, 0);
  ivec4 idx;
  vec2 f;
  latlong_setup(d, size.y, size.x, idx, f);
  vec3 rad = latlong_fetch(uEnv, ivec2(0, 0), idx, f) / uEnvScale;
  outColor = vec4(shrm_display(rad), 1.0);
}
