// Display transform of render/output.py (to_8bit): multiply by 2^exposure, clamp at 0,
// tone map (uTone 0 = "srgb": clip; 1 = "filmic": the ACES fit of Narkowicz 2015,
// x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)), clip to [0, 1], sRGB transfer function
// (IEC 61966-2-1). The canvas quantizes to 8 bits (round to nearest).
// x is limited to 1e4 before the filmic curve so that float32 cannot overflow; the curve
// reaches 1 at x = 7.24 already, so the result is unchanged.
uniform float uExposure;
uniform int uTone;

vec3 shrm_display(vec3 linear) {
  vec3 x = max(linear * exp2(uExposure), vec3(0.0));
  x = min(x, vec3(1.0e4));  // also turns +Inf into 1e4 (NaN compares false: see below)
  if (uTone == 1) {
    x = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
  }
  x = clamp(x, 0.0, 1.0);
  bvec3 nan = notEqual(x, x);
  x = mix(x, vec3(0.0), nan);
  vec3 lo = 12.92 * x;
  vec3 hi = 1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055;
  return mix(hi, lo, lessThanEqual(x, vec3(0.0031308)));
}
