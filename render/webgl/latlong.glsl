// Lat-long bilinear lookup: the rule of brdf_io.latlong.bilinear_lookup, for the WebGL viewer
// and, read by render/glsl.py (LATLONG_GLSL), for the VTK shader. Four exact texels by
// texelFetch, weights in float32: phi wraps with no seam, theta is clamped to the first and
// last row centres, theta = atan(|d_xy|, d_z) stays accurate at the poles. No hardware filtering, no mipmaps.
// Direction d is in the z-up frame; row i of an H x W map is at theta = (i + 1/2) pi / H,
// column j at phi = 2 pi (j + 1/2) / W; texel (x, y) is row y, column x.
void latlong_setup(vec3 d, int H, int W, out ivec4 idx, out vec2 f) {
  const float PI = 3.14159265358979;
  float rxy = length(d.xy);
  float theta = atan(rxy, d.z);
  float phi = (rxy > 0.0) ? atan(d.y, d.x) : 0.0;
  if (phi < 0.0) phi += 2.0 * PI;
  float yy = clamp(theta * float(H) / PI - 0.5, 0.0, float(H) - 1.0);
  float xx = phi * float(W) / (2.0 * PI) - 0.5;
  float y0f = min(floor(yy), float(max(H - 2, 0)));
  float x0f = floor(xx);
  int x0 = int(x0f);
  x0 = x0 - W * int(floor(float(x0) / float(W)));
  int x1 = x0 + 1;
  if (x1 >= W) x1 -= W;
  int y0 = int(y0f);
  int y1 = min(y0 + 1, H - 1);
  idx = ivec4(x0, x1, y0, y1);
  f = vec2(xx - x0f, yy - y0f);
}

// bilinear fetch from tex at tile offset o (texel units), set up by latlong_setup
vec3 latlong_fetch(highp sampler2D tex, ivec2 o, ivec4 idx, vec2 f) {
  vec3 t00 = texelFetch(tex, o + ivec2(idx.x, idx.z), 0).rgb;
  vec3 t01 = texelFetch(tex, o + ivec2(idx.y, idx.z), 0).rgb;
  vec3 t10 = texelFetch(tex, o + ivec2(idx.x, idx.w), 0).rgb;
  vec3 t11 = texelFetch(tex, o + ivec2(idx.y, idx.w), 0).rgb;
  vec3 top = t00 * (1.0 - f.x) + t01 * f.x;
  vec3 bottom = t10 * (1.0 - f.x) + t11 * f.x;
  return top * (1.0 - f.y) + bottom * f.y;
}
