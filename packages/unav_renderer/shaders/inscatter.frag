// Single scattering of the lamps' light into each view ray, ray-marched with samples dense
// near the camera (t = tmax f^2), Schlick phase function plus a backward share. Runs at a
// fraction of the image resolution: the veil is smooth, and this is the costliest shader.
#version 330 core
// Compile-time counts (Renderer keeps one program per combination in use): the loops unroll and
// the lamp arrays are read at constant indices (a loop-variable index makes llvmpipe gather every
// uniform per pixel), and llvmpipe pays for both sides of a branch on a uniform.
#ifndef NLAMPS
#define NLAMPS 1
#endif
#ifndef NSAMPLES
#define NSAMPLES 8
#endif
#ifndef SHADOWS
#define SHADOWS 1
#endif
uniform sampler2D u_color;     // RGBA16F: a = seg id (0 = water); a nearest sampler (one texel)
uniform sampler2D u_depth;     // R32F: z_C
uniform vec4 u_K;              // fx, fy, cx, cy of the full-resolution (internal) image
uniform ivec2 u_size;          // full-resolution size
uniform float u_scale;         // full-resolution pixels per low-resolution pixel
uniform vec3 u_betaD;
uniform vec3 u_lamp_pos_C[4];
uniform vec3 u_lamp_dir_C[4];
uniform vec3 u_lamp_I[4];
uniform vec2 u_lamp_cos[4];
uniform sampler2DArrayShadow u_shadow;
uniform mat4 u_shadow_vp_C[4];   // camera optical -> lamp clip
uniform vec3 u_b_scatter;
uniform float u_schlick_k;
uniform float u_back_frac;
uniform float u_march_max_m;
layout(location = 0) out vec4 o_Ls;
layout(location = 1) out vec4 o_Ls_water;  // weighted for the water pixels' upsampling (kPostFS)
const float PI = 3.14159265358979;
void main() {
  vec2 src = (gl_FragCoord.xy) * u_scale - 0.5;   // full-res pixel coordinates of this texel
  ivec2 si = clamp(ivec2(floor(src + 0.5)), ivec2(0), u_size - 1);
  vec2 tc = (vec2(si) + 0.5) / vec2(u_size);   // the centre of texel si (nearest samplers)
  float seg = texture(u_color, tc).a;
  float z = texture(u_depth, tc).x;
  vec3 ray = vec3((src.x - u_K.z) / u_K.x, (src.y - u_K.w) / u_K.y, 1.0);
  float raylen = length(ray);
  vec3 d = ray / raylen;
  float range = seg > 0.5 ? z * raylen : 1.0e6;
  float tmax = min(range, u_march_max_m);
  float k = u_schlick_k;
  vec3 Ls = vec3(0.0);
  // Lamps outer, samples inner: what depends on the lamp and the ray only is computed once (the
  // sample at t is x = d t, so its lamp-clip position is t M(d, 0) + M(0, 0, 0, 1)).
  for (int i = 0; i < NLAMPS; ++i) {
    vec4 Ad = u_shadow_vp_C[i] * vec4(d, 0.0);
    vec4 A0 = u_shadow_vp_C[i][3];
    vec3 lamp_p = u_lamp_pos_C[i];
    vec3 lamp_dir = u_lamp_dir_C[i];
    vec2 lamp_cos = u_lamp_cos[i];
    vec3 Li = u_b_scatter * u_lamp_I[i];
    for (int s = 0; s < NSAMPLES; ++s) {
      float f = (float(s) + 0.5) / float(NSAMPLES);
      float t = tmax * f * f;
      float dt = 2.0 * tmax * f / float(NSAMPLES);
      vec3 L = d * t - lamp_p;
      float dl = max(length(L), 0.05);
      vec3 l = L / dl;   // propagation direction of the lamp light
      float cone = smoothstep(lamp_cos.x, lamp_cos.y, dot(l, lamp_dir));
      if (cone <= 0.0) continue;
#if SHADOWS
      {   // water behind an object, seen from the lamp, is not lit: shafts
        vec4 c = t * Ad + A0;
        vec3 q = c.xyz / c.w * 0.5 + 0.5;
        if (c.w > 1e-4 && all(greaterThanEqual(q.xy, vec2(0.0))) && all(lessThanEqual(q.xy, vec2(1.0))) && q.z <= 1.0)
          cone *= texture(u_shadow, vec4(q.xy, float(i), q.z));
      }
#endif
      float cth = dot(l, -d);   // cosine of the scattering angle
      float den = 1.0 - k * cth;
      float ph = (1.0 - u_back_frac) * (1.0 - k * k) / (4.0 * PI * den * den) +
                 u_back_frac * ((cth < 0.0) ? 1.0 / (2.0 * PI) : 0.0);
      // Attenuated lamp -> x (dl) and x -> camera (t): one exponential of the summed path.
      Ls += Li * (ph * cone / (dl * dl) * dt) * exp(-u_betaD * (dl + t));
    }
  }
  o_Ls = vec4(Ls, tmax);   // alpha: marched length, for depth-aware upsampling
  // A water pixel marches u_march_max_m, so its upsampling weight for this texel depends on the
  // texel alone: premultiplied, one bilinear fetch does the weighted sum (kPostFS).
  // (kPostFS's 1 / (1e-3 + x) times 1e-3: at most 1, well inside any float format's range.)
  float wd = 1.0 / (1.0 + 1e3 * abs(tmax - u_march_max_m) / max(u_march_max_m, 0.1));
  o_Ls_water = vec4(Ls * wd, wd);
}
