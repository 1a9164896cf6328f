#version 330 core
// Features compiled in or out (Renderer keeps one program per combination in use): llvmpipe
// pays for both sides of a branch on a uniform.
#ifndef REMAP
#define REMAP 0       // distortion / port: each output pixel resamples a RADIANCE pass through u_distmap
#endif
#ifndef RADIANCE
#define RADIANCE 0    // write the linear radiance I (seg in alpha) for a REMAP pass, no sensor stage
#endif
#ifndef FWD
#define FWD 1         // forward-scatter blur
#endif
#ifndef INSCATTER
#define INSCATTER 1   // lamp in-scattering, upsampled from u_inscatter
#endif
#ifndef VIGNETTING
#define VIGNETTING 1
#endif
#ifndef SHOT
#define SHOT 1        // shot noise
#endif
#ifndef READ_NOISE
#define READ_NOISE 1  // read noise
#endif
#ifndef SNELL
#define SNELL 1       // Snell's window: sky and sun seen through the surface
#endif
#ifndef MOTION
#define MOTION 0      // motion blur over the exposure
#endif
#ifndef DEFOCUS
#define DEFOCUS 0     // depth of field: a disc of 16 taps per pixel of geometry
#endif
#ifndef CHROMA
#define CHROMA 0      // lateral chromatic aberration (REMAP only: red and blue resampled)
#endif
#ifndef PIXELS
#define PIXELS 0      // 0 every pixel; 1 those with geometry, 2 the water only (the pass is drawn
#endif                // twice, split by a depth test against the scene's depth buffer)
// A distorted camera (or one behind a port) runs two programs: the RADIANCE variant at the
// internal (undistorted) resolution, split by PIXELS like a pinhole's, then the REMAP variant at
// the output's, which resamples it (bilinear, as a lens images the radiance; seg and depth from
// the nearest source pixel) and adds the sensor (vignetting, noise, encoding). One program doing
// both per output pixel pays for the geometry's and the water's branches on every pixel.
uniform sampler2D u_color;     // RGBA16F: D and seg (REMAP: RGBA32F, the RADIANCE pass's I and seg)
uniform sampler2D u_color_px;  // the same through a nearest sampler: texel centres read one texel
uniform sampler2D u_depth;     // R32F: z_C
uniform sampler2D u_distmap;   // RG32F: undistorted pixel for each output pixel (REMAP)
uniform sampler2D u_blur4;     // RGBA32F, 1/4 resolution: means of 4 x 4 pixels of u_color (kBlurDownFS)
uniform sampler2D u_blur16;    // RGBA32F, 1/16 resolution: means of 16 x 16 pixels
uniform vec4 u_blur_uv;        // pixel coordinates -> u_blur4's, u_blur16's texture coordinates (xy, zw)
uniform vec4 u_K;              // fx, fy, cx, cy
uniform ivec2 u_size;
uniform vec3 u_betaD;
uniform vec3 u_betaB;
uniform vec3 u_Binf;           // veiling light at the camera depth
uniform float u_veil_gradient;
uniform mat3 u_R_WC;           // optical -> world rotation
uniform float u_fwd_per_m;
uniform float u_blur_px_per_m;
uniform sampler2D u_inscatter; // RGBA32F, low resolution: lamp light scattered into the ray
uniform sampler2D u_inscatter_water;  // the same times the water pixels' weight w, and w (bilinear)
uniform float u_march_max_m;
uniform vec3 u_gain;           // exposure x white balance, per channel of the linear signal
uniform vec2 u_coc;            // defocus: blur diameter [px] = x |y - 1 / z_C| (y = 1 / focus distance)
uniform vec2 u_disc[24];       // defocus taps in the unit disc (centred): 16 for r >= 2 px, then 8 for smaller discs
uniform vec2 u_chroma;         // lateral colour: red and blue sampled at the principal point + these x the offset
uniform float u_noise_std;
uniform float u_shot;          // shot noise: variance u_shot * I (linear signal)
uniform float u_vignetting;    // share of the cos^4 falloff
uniform vec4 u_Kout;           // output (in-air) camera fx, fy, cx, cy: field angle of a pixel
uniform float u_cam_depth;     // camera depth below the surface [m]
uniform float u_n_water;       // refractive index of the water
uniform vec3 u_sky;            // radiance through the window's centre: n^2 ambient E0 / T(0)
uniform vec3 u_sun_glow;       // pi (1 - ambient) E0 / T(0): the sun, spread over the glint kernel
uniform vec3 u_sun_dir_W;      // direction the sunlight travels in the water
uniform vec3 u_motion_v;       // camera translation over the exposure, optical frame [m]
uniform vec3 u_motion_w;       // camera rotation over the exposure (angle x axis), optical frame
uniform uint u_seed;           // the frame's noise seed, pcg-hashed once on the CPU (pcg_seed())
uniform bool u_srgb;
layout(location = 0) out vec4 o_rgba;   // rgb8 + seg id in alpha (RADIANCE: linear I and seg id)
layout(location = 1) out float o_depth;
#if !REMAP
noperspective in vec3 v_ray;    // the vertex shader's view rays (see kPostVS)
noperspective in vec3 v_ray_W;
#endif

const float PI = 3.14159265358979;

uint pcg(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
#include "sin_pi.glsl"
// Two independent standard normal numbers from one 32-bit hash (Box-Muller, both outputs used):
// 20 bits for the radius (|z| up to sqrt(2 ln 2^21) = 5.4), 12 bits for the angle; cos(a) from
// sin(a) by a square root (one instruction, where sin_pi is a polynomial; within 5e-4 where
// |cos| is smallest, a 1e-4 sigma shift of the output).
vec2 gauss2(uint h) {
  // ln u for u = (k + 0.5) / 2^20: log2 of x = k + 0.5 (exact in a float) from its exponent and a
  // degree-6 polynomial in its mantissa (within 4.4e-6), minus 20.
  float x = float(h >> 12u) + 0.5;
  uint bits = floatBitsToUint(x);
  float t = uintBitsToFloat((bits & 0x7FFFFFu) | 0x3F800000u) - 1.0;   // mantissa - 1, [0, 1)
  float p = 0.456894174 + t * (-0.27736505 + t * (0.121914139 + t * -0.0260663015));
  float lg = float(int(bits >> 23u) - 147) + t * (1.44251703 + t * (-0.717898381 + t * p));   // exponent - 127 - 20
  float a = (float(h & 4095u) + 0.5) * (2.0 * PI / 4096.0) - PI;   // (-pi, pi)
  float r = sqrt(max(-2.0 * 0.69314718 * lg, 0.0));
  float s = sin_pi(a), c = sqrt(max(1.0 - s * s, 0.0));
  return r * vec2(abs(a) > 0.5 * PI ? -c : c, s);
}

vec3 encode(vec3 x) {
  // Soft shoulder above 0.8 (identity below), then sRGB.
  vec3 s = 0.8 + 0.2 * (1.0 - exp(-(x - 0.8) / 0.2));
  x = mix(x, s, step(vec3(0.8), x));
  x = clamp(x, 0.0, 1.0);
  if (!u_srgb) return x;
  // 1.055 x^(1 / 2.4) - 0.055 from three nested square roots (a minimax fit over [0.0031308, 1],
  // within 0.012 of an 8-bit level): a square root is one instruction, where pow() is a log2 and
  // an exp2 polynomial each on llvmpipe.
  vec3 s1 = sqrt(x), s2 = sqrt(s1), s3 = sqrt(s2);
  vec3 hi = 0.64236626 * s1 + 0.71210972 * s2 - 0.33686962 * s3 - 0.01756329 * x;
  return mix(12.92 * x, hi, step(vec3(0.0031308), x));
}

void main() {
  ivec2 pix = ivec2(gl_FragCoord.xy);
#if REMAP
  vec2 src = texture(u_distmap, gl_FragCoord.xy / vec2(textureSize(u_distmap, 0))).xy;   // nearest: pixel pix
  ivec2 si = ivec2(floor(src + 0.5));
  bool inside = si.x >= 0 && si.y >= 0 && si.x < u_size.x && si.y < u_size.y;
  vec2 tc = (vec2(si) + 0.5) / vec2(u_size);   // the centre of texel si (nearest samplers)
  float seg = inside ? texture(u_color_px, tc).a : 0.0;
  bool hit = seg > 0.5;
  float z = texture(u_depth, tc).x;
  vec3 I = textureLod(u_color, (src + 0.5) / vec2(u_size), 0.0).rgb;   // clamps to the edge outside
#if CHROMA
  // Lateral colour: the lens images red larger by 1 + k (blue smaller by 1 - k) about the principal
  // point, so this pixel's red is the radiance 1 / (1 + k) as far out.
  {
    vec2 q = src - u_K.zw;
    I.r = textureLod(u_color, (u_K.zw + u_chroma.x * q + 0.5) / vec2(u_size), 0.0).r;
    I.b = textureLod(u_color, (u_K.zw + u_chroma.y * q + 0.5) / vec2(u_size), 0.0).b;
  }
#endif
#else
  vec2 src = vec2(pix);
  vec2 uv = (src + 0.5) / vec2(u_size);
  vec4 c = texture(u_color_px, uv);
  float seg = c.a;
  float z = 0.0;
#if PIXELS != 2
  z = texture(u_depth, uv).x;
#endif
  vec3 D = c.rgb;
  vec3 ray = v_ray;
  float raylen = length(ray);
  vec3 d = ray / raylen;
#if PIXELS == 2
  const bool hit = false;
#else
  bool hit = seg > 0.5;
#endif
  float range = hit ? z * raylen : 1.0e6;

#if MOTION || DEFOCUS
  // Motion blur: the point seen here (water: far away, so rotation only) was at
  // P0 = P + w x P + v when the shutter opened; its image moved by g = here - there during the
  // exposure, so this pixel gathers the sharp frame along +g (a box filter over the exposure).
  // Defocus: the pixel gathers the disc of its own blur diameter (thin lens, from its depth; 8 taps
  // below a 2 px radius, 16 above; the
  // taps on water are left out, so an object's edge does not darken; a gather, so a sharp
  // foreground bleeds onto a blurred background behind it). Both: each tap of the disc moved along
  // the smear. Depth and segmentation stay those of the stamp's sharp frame.
  {
    vec2 g = vec2(0.0);
    bool moved = false;
#if MOTION
    vec3 P = ray * (hit ? z : 1.0e3);
    vec3 P0 = P + cross(u_motion_w, P) + u_motion_v;
    if (P0.z > 1e-3) {
      g = src - (u_K.xy * P0.xy / P0.z + u_K.zw);
      moved = true;
    }
#endif
    float r = 0.0;
#if DEFOCUS
    if (hit) r = min(0.5 * u_coc.x * abs(u_coc.y - 1.0 / max(z, 1e-4)), 32.0);
#endif
    vec2 px_uv = 1.0 / vec2(u_size);
    if (r > 0.5 && !moved) {
      // The disc alone (the common case): fixed trip counts, nearest texels (a bilinear half-float
      // fetch is four texel conversions on llvmpipe), the taps on water weighted 0.
      vec3 acc = vec3(0.0);
      float wsum = 0.0;
      if (r >= 2.0) {
        for (int k = 0; k < 16; ++k) {
          vec4 s = texture(u_color_px, (src + r * u_disc[k] + 0.5) * px_uv);
          float w = step(0.5, s.a);
          acc += w * s.rgb;
          wsum += w;
        }
      } else {
        for (int k = 16; k < 24; ++k) {
          vec4 s = texture(u_color_px, (src + r * u_disc[k] + 0.5) * px_uv);
          float w = step(0.5, s.a);
          acc += w * s.rgb;
          wsum += w;
        }
      }
      if (wsum > 0.0) D = acc / wsum;
    } else if (moved) {
      // The smear (bilinear), each tap also moved over the disc when there is one.
      int n = int(clamp(ceil(length(g)), 1.0, 32.0));
      if (r > 0.5) n = max(n, 16);
      vec3 acc = vec3(0.0);
      float wsum = 0.0;
      for (int k = 0; k < n; ++k) {
        vec2 o = ((float(k) + 0.5) / float(n)) * g + (r > 0.5 ? r * u_disc[k & 15] : vec2(0.0));
        vec4 s = textureLod(u_color, (src + o + 0.5) * px_uv, 0.0);
        float w = r > 0.5 ? step(0.5, s.a) : 1.0;
        acc += w * s.rgb;
        wsum += w;
      }
      if (wsum > 0.0) D = acc / wsum;
    }
  }
#endif

  // Forward scattering: a share 1 - exp(-f z) of the direct signal spreads over a disc whose
  // radius grows with range: the image blended towards its 4 x 4 and 16 x 16 means (bilinear:
  // smooth, no ghost taps) by the radius's octave, as a mip chain's levels 0, 2 and 4 would be
  // (two fetches at a fixed level: llvmpipe's cheap path, where a per-pixel level is not).
#if FWD && PIXELS != 2
  if (hit) {
    float w = 1.0 - exp(-u_fwd_per_m * range);
    float lod = log2(clamp(u_blur_px_per_m * range, 1.0, 16.0));   // 0..4
    // Texel i of a level covers pixels 4i .. 4i + 3 (16i .. 16i + 15): its centre at pixel 4i + 2,
    // also where the image's size is not a multiple of 4 (16) and the level has a part-covered texel.
    vec3 b4 = textureLod(u_blur4, (src + 0.5) * u_blur_uv.xy, 0.0).rgb;
    vec3 b16 = textureLod(u_blur16, (src + 0.5) * u_blur_uv.zw, 0.0).rgb;
    vec3 blur = lod < 2.0 ? mix(D, b4, 0.5 * lod) : mix(b4, b16, 0.5 * lod - 1.0);
    D = mix(D, blur, w);
  }
#endif

  // Backscatter of ambient light towards the veiling light. The veiling light is brighter
  // looking up than down (downwelling radiance): factor 1 + gradient * up-component of the ray.
  vec3 d_W = v_ray_W / raylen;
  vec3 Bdir = u_Binf * (1.0 + u_veil_gradient * (-d_W.z));
  vec3 B = Bdir * (1.0 - exp(-u_betaB * range));

#if SNELL && PIXELS != 1
  // Snell's window: a water ray closer to the zenith than asin(1 / n) leaves through the surface,
  // s = depth / cos(zenith angle) away, and brings the sky (and the sun's glint) from above,
  // weighted by the Fresnel transmittance; the reflected share R continues in the water like a
  // ray beyond the window (total internal reflection), which keeps the veiling light.
  float up = -d_W.z;
  if (!hit && up > 0.0 && u_cam_depth > 0.0) {
    float sin_a = u_n_water * sqrt(max(1.0 - up * up, 0.0));
    if (sin_a < 1.0) {
      float cos_a = sqrt(1.0 - sin_a * sin_a);
      float rs = (u_n_water * up - cos_a) / (u_n_water * up + cos_a);
      float rp = (up - u_n_water * cos_a) / (up + u_n_water * cos_a);
      float T = 1.0 - 0.5 * (rs * rs + rp * rp);
      float s = u_cam_depth / up;
      // Glint: the sun's image spread by surface waves, a normalised Gaussian of 2 deg.
      const float SIG2 = 0.0012;
      float a = acos(clamp(dot(d_W, -u_sun_dir_W), -1.0, 1.0));
      float glint = exp(-a * a / SIG2) / (PI * SIG2);
      D += T * (u_sky + u_sun_glow * glint) * exp(-u_betaD * s);   // D: marine snow in front
      B = Bdir * (1.0 - T * exp(-u_betaB * s));
    }
  }
#endif

  // Depth-aware upsampling of the low-resolution in-scatter: of the 4 nearest texels, trust
  // those whose marched length matches this pixel's (no halos at silhouettes).
  vec3 Ls = vec3(0.0);
#if INSCATTER && PIXELS == 2
  {
    // Water: the pixel's marched length is u_march_max_m, so each texel's depth weight depends on
    // the texel only, and the weighted bilinear sum is one filtered fetch of the premultiplied
    // texture (the same weights as below, to float rounding).
    vec4 s = texture(u_inscatter_water, uv);
    Ls = s.rgb / max(s.a, 1e-9);
  }
#elif INSCATTER
  {
    vec2 isz = vec2(textureSize(u_inscatter, 0));
    vec2 p = uv * isz - 0.5;
    vec2 f = fract(p);
    ivec2 b = ivec2(floor(p));
    float tmax = min(range, u_march_max_m);
    float wsum = 0.0;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        // Texel b + (i, j) (nearest; the texture clamps to its edges as texelFetch's clamp did).
        vec4 s = texture(u_inscatter, (vec2(b + ivec2(i, j)) + 0.5) / isz);
        float wb = (i == 1 ? f.x : 1.0 - f.x) * (j == 1 ? f.y : 1.0 - f.y);
        float wd = 1.0 / (1e-3 + abs(s.a - tmax) / max(tmax, 0.1));
        Ls += s.rgb * wb * wd;
        wsum += wb * wd;
      }
    Ls /= max(wsum, 1e-9);
  }
#endif

  vec3 I = (D + B + Ls) * u_gain;
#endif  // REMAP
#if RADIANCE
  o_rgba = vec4(I, seg);   // RGBA32F: seg exact for REMAP's nearest read
#else
#if VIGNETTING
  // Natural vignetting: cos^4 of the in-air field angle (1 / (1 + |x|^2)^2 for the normalized x).
  vec2 xn = (vec2(pix) - u_Kout.zw) / u_Kout.xy;
  float c4 = 1.0 / ((1.0 + dot(xn, xn)) * (1.0 + dot(xn, xn)));
  I *= 1.0 - u_vignetting * (1.0 - c4);
#endif
  // Six independent normal numbers at most, two per Box-Muller draw: shot noise takes the
  // first three, read noise the next three.
  uint h = pcg(uint(pix.x) + 8192u * uint(pix.y) + u_seed);
#if SHOT || READ_NOISE
  vec2 g01 = gauss2(h);
  vec2 g23 = gauss2(pcg(h + 0x85EBCA6Bu));
#endif
#if SHOT && READ_NOISE
  vec2 g45 = gauss2(pcg(h + 0x9E3779B9u));
  vec3 g_read = vec3(g23.y, g45);
#elif READ_NOISE
  vec3 g_read = vec3(g01, g23.x);
#endif
#if SHOT
  // Shot noise on the linear signal (Poisson, Gaussian approximation): std sqrt(u_shot I).
  I = max(I + sqrt(u_shot * max(I, 0.0)) * vec3(g01, g23.x), 0.0);
#endif
  vec3 col = encode(I);
#if READ_NOISE
  col = clamp(col + u_noise_std * g_read, 0.0, 1.0);
#endif
  o_rgba = vec4(col, seg / 255.0);
  o_depth = hit ? z : uintBitsToFloat(0x7f800000u);
#endif  // RADIANCE
}
