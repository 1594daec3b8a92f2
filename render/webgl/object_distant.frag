// distant (RH02 eq. 12): radiance = M(R), M = max(sum_c B~_c Y^r_c(V~), 0) the view map of
// SHRM.view_map, computed per view on the CPU (view.js) as render/shader.py distant_update
// does and uploaded as a float32 H x W texture uMap; looked up by R with the bilinear rule.
uniform highp sampler2D uMap;

void main() {
  vec3 N, V, R;
  shrm_geometry(N, V, R);
  ivec4 idx;
  vec2 f;
  latlong_setup(R, SHRM_H, SHRM_W, idx, f);
  vec3 rad = latlong_fetch(uMap, ivec2(0, 0), idx, f);
  outColor = vec4(shrm_display(max(rad, vec3(0.0))), 1.0);
}
