// distant (RH02 eq. 12): radiance = M(R), M = max(sum_c B~_c Y^r_c(V~), 0) the view map of
// SHRM.view_map, computed per view on the CPU (view.js) as render/shader.py distant_update
// does and uploaded as a float32 H x W texture uMap; looked up by R with the bilinear rule.
// With SHRM_LIGHTS the explicit lights are added per pixel with its own V (lights.glsl).
uniform highp sampler2D uMap;

void main() {
  vec3 N, V, R;
  shrm_geometry(N, V, R);
  ivec4 idx;
  vec2 f;
  latlong_setup(R, SHRM_H, SHRM_W, idx, f);
  vec3 rad = max(latlong_fetch(uMap, ivec2(0, 0), idx, f), vec3(0.0));
#ifdef SHRM_LIGHTS
  rad += shrm_lights(R, V);  // the lights, exactly, at this pixel's V (lights.glsl)
#endif
  outColor = vec4(shrm_display(rad), 1.0);
}
