// perpixel (RH02 eq. 8): radiance = max(sum_c Y^r_c(V) B~_c(R), 0) with V per fragment
// (render/shader.py perpixel_shading); the atlas holds the coefficients times uScale
// (half floats), so the sum is divided by it. With SHRM_LIGHTS the explicit lights are added
// per pixel (lights.glsl).
uniform float uScale;

void main() {
  vec3 N, V, R;
  shrm_geometry(N, V, R);
  ivec4 idx;
  vec2 f;
  latlong_setup(R, SHRM_H, SHRM_W, idx, f);
  vec3 rad = max(shrm_sum(V, idx, f) / uScale, vec3(0.0));
#ifdef SHRM_LIGHTS
  rad += shrm_lights(R, V);  // the lights, exactly, per pixel (lights.glsl)
#endif
  outColor = vec4(shrm_display(rad), 1.0);
}
