#version 330 core
in vec3 v_pos_W;
in vec3 v_nrm_W;
in vec2 v_uv;
in float v_z_C;
uniform sampler2D u_tex;
uniform sampler2D u_tex_macro;  // u_tex again, bilinear in the nearest mip level (MACRO)
uniform vec3 u_albedo;
uniform float u_uv_scale;
// Material variants, compiled separately (Renderer picks one per mesh): a branch on a uniform
// costs llvmpipe both sides, so each pixel would pay for every material's texturing.
#ifndef TRIPLANAR
#define TRIPLANAR 0  // rocks, meshes without UVs: three planar projections blended by the normal
#endif
#ifndef MACRO
#define MACRO 0      // seabed: domain-warped UVs, modulated by a low-frequency copy (breaks tiling)
#endif
#ifndef SECTIONS
#define SECTIONS 0   // u along a pipe: each texture tile (coating section) turned differently
#endif
#ifndef BUMP
#define BUMP 0       // the texture's relief (height in alpha x u_relief) shades by bump mapping
#endif
#ifndef SPECULAR
#define SPECULAR 0   // GGX highlights (metals, smooth surfaces)
#endif
#ifndef SEDIMENT
#define SEDIMENT 0   // sand settled on upward faces and near the seabed
#endif
#ifndef NLAMPS
#define NLAMPS 0     // lamps lighting the scene (0..4)
#endif
// Shadow lookups, per draw: off for the terrain chunks nothing can shadow (Renderer culls them).
#ifndef SUN_SHADOW
#define SUN_SHADOW 0  // the sun's shadow map
#endif
#ifndef LAMP_SHADOWS
#define LAMP_SHADOWS 0  // the lamps' shadow maps
#endif
#ifndef NORMAL_MAP
#define NORMAL_MAP 0  // a mesh file's tangent-space normal map (u_normal_map, by v_uv)
#endif
#ifndef ORM_MAP
#define ORM_MAP 0     // a mesh file's occlusion-roughness-metallic map (u_orm, by v_uv)
#endif
uniform float u_relief;          // peak-to-trough height of the texture's relief [m]
uniform sampler2D u_grad;        // the relief height's slope per unit of texture coordinate (nearest mip level)
uniform float u_roughness;       // perceptual (alpha = roughness^2); times the ORM map's green
uniform float u_metallic;        // times the ORM map's blue
uniform sampler2D u_normal_map;  // rgb = (n + 1) / 2 in the (+u, +v, normal) frame
uniform sampler2D u_orm;         // r occlusion of the ambient light, g roughness, b metallic
uniform float u_sediment;        // cover [0, 1]
uniform vec3 u_sediment_albedo;  // the seabed's mean albedo
uniform float u_seabed_z;        // mean seabed depth [m]
uniform float u_seg;
uniform vec3 u_cam_W;
uniform vec3 u_sun_dir_W;    // direction the sunlight travels
uniform vec3 u_E0;           // surface irradiance
uniform float u_ambient;     // diffuse share of the downwelling light
uniform vec3 u_Kd;
uniform vec3 u_betaD;
uniform vec3 u_lamp_pos_W[4];
uniform vec3 u_lamp_dir_W[4];
uniform vec3 u_lamp_I[4];
uniform vec2 u_lamp_cos[4];  // cos(outer), cos(inner)
uniform sampler2DArrayShadow u_shadow;  // one depth layer per lamp
#if LAMP_SHADOWS && NLAMPS > 0
in vec4 v_lamp_clip[NLAMPS];            // lamp clip coordinates (vertex shader)
#endif
uniform float u_caustics;               // caustic_strength (0 = off)
uniform float u_time;                   // frame stamp [s]
uniform sampler2DShadow u_sun_map;
#if SUN_SHADOW
in vec3 v_sun_q;                        // sun map coordinates and depth (vertex shader)
#endif
layout(location = 0) out vec4 o_color;   // rgb: direct signal D = J exp(-beta_D z); a: seg id
layout(location = 1) out float o_depth;  // z along the optical axis [m]

vec4 tex_at(vec2 uv) { return texture(u_tex, uv / u_uv_scale); }  // rgb albedo, a relief height

#include "sin_pi.glsl"
// sin(x) to ~4e-6 absolute for |x| < 4e5: Cody-Waite reduction to [-pi, pi] (2 pi split in a
// short head, exact times k, and a tail), then sin_pi. llvmpipe's sin() reduces to [0, pi/4] and
// evaluates two polynomials: about twice the instructions, and the caustics make 8 of them a pixel.
float sin_fast(float x) {
  float k = floor(x * 0.15915494 + 0.5);
  return sin_pi((x - k * 6.28125) - k * 0.0019353072);
}

// Zero-mean caustic network at horizontal position p [m], time t [s]: two domain-warped,
// drifting layers of sin x sin cells, sharpened into thin bright lines (g |g| keeps the mean 0).
float caustic_pattern(vec2 p, float t) {
  float g = 0.0;
  vec2 q = p * 1.9;
  for (int k = 0; k < 2; ++k) {
    vec2 w = q + 0.55 * vec2(sin_fast(q.y * 1.3 + 0.8 * t + float(k)), sin_fast(q.x * 1.1 - 0.6 * t + 2.0 * float(k)));
    float s = sin_fast(w.x + 0.35 * t) * sin_fast(w.y - 0.3 * t);
    g += s * abs(s);
    q = mat2(0.8, 0.6, -0.6, 0.8) * q * 1.37 + vec2(3.1, 1.7);
  }
  return g;
}

// Share of lamp i's light reaching this pixel (percentage-closer filtered); 1 outside the map.
float lamp_visibility(int i) {
#if !LAMP_SHADOWS || NLAMPS == 0
  return 1.0;
#else
  vec4 c = v_lamp_clip[i];
  if (c.w <= 1e-4) return 1.0;
  vec3 q = c.xyz / c.w * 0.5 + 0.5;
  if (any(lessThan(q.xy, vec2(0.0))) || any(greaterThan(q.xy, vec2(1.0))) || q.z > 1.0) return 1.0;
  // One bilinear comparison: the hardware filters 2x2 depth tests (soft edges over one texel).
  return texture(u_shadow, vec4(q.xy, float(i), q.z));
#endif
}

// Smooth value noise (hash lattice, cell 1 unit): not periodic, unlike the texture tile.
float hash12(vec2 p) {
  vec3 q = fract(vec3(p.xyx) * 0.1031);
  q += dot(q, q.yzx + 33.33);
  return fract((q.x + q.y) * q.z);
}
float value_noise(vec2 p) {
  vec2 i = floor(p), f = fract(p);
  vec2 u = f * f * (3.0 - 2.0 * f);
  return mix(mix(hash12(i), hash12(i + vec2(1.0, 0.0)), u.x), mix(hash12(i + vec2(0.0, 1.0)), hash12(i + vec2(1.0, 1.0)), u.x), u.y);
}

#if SPECULAR
// pi x the Cook-Torrance specular lobe (GGX D, Smith-Schlick G with k = (r + 1)^2 / 8, Schlick F):
// J is pi x radiance here (albedo E is Lambert's), so J += specular() x the source's irradiance.
vec3 specular(vec3 n, vec3 V, vec3 l, vec3 F0, float rough) {
  float ndl = dot(n, l);
  if (ndl <= 0.0) return vec3(0.0);
  float ndv = max(dot(n, V), 1e-3);
  vec3 H = normalize(l + V);
  float ndh = max(dot(n, H), 0.0), vdh = max(dot(V, H), 0.0);
  float a2 = rough * rough * rough * rough;
  float d = ndh * ndh * (a2 - 1.0) + 1.0;
  float k = (rough + 1.0) * (rough + 1.0) / 8.0;
  float G = ndl / (ndl * (1.0 - k) + k) * ndv / (ndv * (1.0 - k) + k);
  // max(): rounding can give vdh a hair above 1 where the light comes from the eye (a lamp beside
  // the camera, a far surface), and pow() of a negative base is NaN (which the forward-scatter
  // blur's mip chain then spreads over 16 x 16 pixel squares).
  // (1 - vdh)^5 by multiplications: pow() is exp2(5 log2 x) on llvmpipe, three times a pixel.
  float m = max(1.0 - vdh, 0.0), m2 = m * m;
  vec3 F = F0 + (1.0 - F0) * (m2 * m2 * m);
  return a2 / (d * d) * G * F / (4.0 * ndl * ndv);   // pi D = a2 / d^2
}
#endif

void main() {
  vec3 n = normalize(v_nrm_W);
  vec3 V = u_cam_W - v_pos_W;
  float range = length(V);
  V /= max(range, 1e-6);
  if (dot(n, V) < 0.0) n = -n;   // two-sided surfaces
  vec4 t;
#if TRIPLANAR
  vec3 w = pow(abs(n), vec3(4.0));
  w /= (w.x + w.y + w.z);
  t = tex_at(v_pos_W.yz) * w.x + tex_at(v_pos_W.xz) * w.y + tex_at(v_pos_W.xy) * w.z;
#if BUMP
  // World gradient of the blended height: each projection's slope along its two world axes.
  vec2 gx = texture(u_grad, v_pos_W.yz / u_uv_scale).rg, gy = texture(u_grad, v_pos_W.xz / u_uv_scale).rg,
       gz = texture(u_grad, v_pos_W.xy / u_uv_scale).rg;
  vec3 grad_W = (w.x * vec3(0.0, gx) + w.y * vec3(gy.x, 0.0, gy.y) + w.z * vec3(gz, 0.0)) / u_uv_scale;
#endif
#else
  vec2 uv = v_uv;
#if MACRO
  // Macro materials (the seabed) are domain-warped by low-frequency noise in world units, so
  // the texture tile never repeats exactly: a seabed that looks the same every tile would
  // alias visual place recognition.
  uv += u_uv_scale * 0.45 * (vec2(value_noise(v_uv / 1.7), value_noise(v_uv / 1.7 + vec2(41.3, 17.9))) - 0.5);
#endif
#if SECTIONS
  // Pipe coating sections are not copies of each other: each shows the texture turned by its
  // own angle about the pipe (field joints stay at the section ends).
  uv.y += u_uv_scale * hash12(vec2(floor(uv.x / u_uv_scale), 7.0));
#endif
  t = tex_at(uv);
#endif
  vec3 albedo = t.rgb;
  float relief = u_relief;
#if MACRO
  albedo *= 0.7 + 0.6 * texture(u_tex_macro, v_uv / (u_uv_scale * 7.31) + vec2(0.37, 0.11)).g;
#endif
  albedo *= u_albedo;
#if SEDIMENT
  // Sand settles where the surface faces up (faces steeper than ~55 deg shed it), in patches
  // (value noise over 0.25 m), and buries what lies within 0.3 m of the mean seabed; it fills the
  // relief it covers.
  float cover = smoothstep(0.55, 0.9, -n.z) * (0.3 + 0.7 * value_noise(v_pos_W.xy * 4.0)) +
                smoothstep(u_seabed_z - 0.3, u_seabed_z, v_pos_W.z);
  cover = clamp(u_sediment * cover, 0.0, 1.0);
  albedo = mix(albedo, u_sediment_albedo, cover);
  relief *= 1.0 - cover;
#endif
#if BUMP
  // Bump mapping: the normal tilted against the surface gradient of the relief height. Its slope
  // comes from a texture (per pixel, filtered), not from screen-space derivatives of the height
  // (constant over 2x2 pixels: blocky and grid-locked). UV mappings turn the texture-space slope
  // into screen derivatives by the (per-triangle exact) derivatives of uv and of the position
  // (Mikkelsen 2010: no tangents, so the macro warp and pipe sections need none either).
  {
#if TRIPLANAR
    vec3 G = relief * grad_W;
    vec3 nb = n - (G - n * dot(n, G));
#else
    vec2 tuv = uv / u_uv_scale;
    vec2 g = relief * texture(u_grad, tuv).rg;
    vec3 dpdx = dFdx(v_pos_W), dpdy = dFdy(v_pos_W);
    vec3 r1 = cross(dpdy, n), r2 = cross(n, dpdx);
    float det = dot(dpdx, r1);
    vec3 nb = abs(det) * n - sign(det) * (dot(g, dFdx(tuv)) * r1 + dot(g, dFdy(tuv)) * r2);
#endif
    if (dot(nb, nb) > 1e-30) nb = normalize(nb);
    if (dot(nb, V) > 0.02) n = nb;   // never turned away from the camera
  }
#endif
#if NORMAL_MAP
  // The file's normal map in the frame of its UVs, built per pixel from the screen derivatives
  // of the position and of the UVs (Schueler's cotangent frame: no tangents in the mesh; exact
  // per triangle, mirrored UVs and the back faces included).
  {
    vec3 tn = texture(u_normal_map, v_uv).xyz * 2.0 - 1.0;
    vec3 dp1 = dFdx(v_pos_W), dp2 = dFdy(v_pos_W);
    vec2 duv1 = dFdx(v_uv), duv2 = dFdy(v_uv);
    vec3 dp2perp = cross(dp2, n), dp1perp = cross(n, dp1);
    // T, B: the gradients of u and v along the surface, up to 1 / det[dp1, dp2, n] (its sign
    // depends on how the screen axes sit on the surface: kept, the size normalised away).
    float flip = dot(dp1, dp2perp) < 0.0 ? -1.0 : 1.0;
    vec3 T = flip * (dp2perp * duv1.x + dp1perp * duv2.x);
    vec3 B = flip * (dp2perp * duv1.y + dp1perp * duv2.y);
    float m2 = max(dot(T, T), dot(B, B));
    if (m2 > 1e-30) {
      vec3 nm = normalize(inversesqrt(m2) * (T * tn.x + B * tn.y) + n * tn.z);
      if (dot(nm, V) > 0.02) n = nm;   // never turned away from the camera
    }
  }
#endif
  float rough = u_roughness, metallic = u_metallic, occlusion = 1.0;
#if ORM_MAP
  {
    vec3 orm = texture(u_orm, v_uv).rgb;
    occlusion = orm.r;
    rough = clamp(u_roughness * orm.g, 0.05, 1.0);
    metallic = u_metallic * orm.b;
  }
#endif
#if SPECULAR
  vec3 F0 = mix(vec3(0.0032), albedo, metallic);   // ((1.5 - 1.34) / (1.5 + 1.34))^2 for dielectrics
  vec3 Jspec = vec3(0.0);
#endif

  // Sunlight at this depth: E0 exp(-K_d d); diffuse part from the upper hemisphere, direct
  // part with the cosine law. A surface facing straight up under a vertical sun gets E(d).
  // Every irradiance below is carried on to the camera already (times exp(-beta_D range)): one
  // exponential of the summed path per light instead of a product of two.
  float depth = max(v_pos_W.z, 0.0);
  vec3 Ed = u_E0 * exp(-u_Kd * depth - u_betaD * range);
  float up = -n.z;
  float ndl = max(dot(n, -u_sun_dir_W), 0.0);
#if SUN_SHADOW
  if (ndl > 0.0) {   // the direct part is blocked by what lies up-sun
    vec3 q = v_sun_q;
    if (all(greaterThanEqual(q, vec3(0.0))) && all(lessThanEqual(q, vec3(1.0))))
      ndl *= texture(u_sun_map, q);
  }
#endif
  if (u_caustics > 0.0 && ndl > 0.0) {
    float Kd = u_Kd.g;
    float A = u_caustics * exp(-depth * (2.0 * Kd + 1.0 / 15.0));
    ndl *= max(1.0 + A * caustic_pattern(v_pos_W.xy, u_time), 0.0);
  }
  vec3 Eamb = Ed * u_ambient * (0.5 + 0.5 * up) * occlusion;   // diffuse skylight: no highlight
  vec3 E = Ed * (1.0 - u_ambient) * ndl;             // direct: sun, then lamps
#if SPECULAR
  Jspec += specular(n, V, -u_sun_dir_W, F0, rough) * E;
#endif

  // Lamps: inverse square, cone, attenuated lamp -> surface -> camera.
  // NLAMPS is a compile-time count: the loop unrolls and the lamp arrays are read at constant
  // indices (a loop-variable index makes llvmpipe gather every uniform per pixel).
  for (int i = 0; i < NLAMPS; ++i) {
    vec3 L = u_lamp_pos_W[i] - v_pos_W;
    float dl = max(length(L), 0.05);
    vec3 l = L / dl;
    float cone = smoothstep(u_lamp_cos[i].x, u_lamp_cos[i].y, dot(-l, u_lamp_dir_W[i]));
    if (cone > 0.0) {
      vec3 Ei = u_lamp_I[i] * cone * lamp_visibility(i) * max(dot(n, l), 0.0) / (dl * dl) * exp(-u_betaD * (dl + range));
      E += Ei;
#if SPECULAR
      Jspec += specular(n, V, l, F0, rough) * Ei;
#endif
    }
  }
  // A metal has no diffuse term under direct light; under the diffuse skylight a rough one
  // returns about its albedo, as a Lambertian surface would.
#if SPECULAR
  vec3 J = albedo * (Eamb + (1.0 - metallic) * E) + Jspec;
#else
  vec3 J = albedo * (Eamb + E);
#endif
  o_color = vec4(J, u_seg);
  o_depth = v_z_C;
}
