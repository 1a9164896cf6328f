// GLSL 3.30 core shaders, embedded. World frame NED; camera optical frame (x right, y down,
// z forward). Radiometry in linear "display units" (E0 = 1 gives white on an albedo-1 surface).
#pragma once

namespace unav::renderer::detail {

// sin(x) for |x| <= pi, spliced into the scene and post shaders: folded to [-pi/2, pi/2], degree-9
// Taylor (error (pi/2)^11 / 11! = 3.6e-6). llvmpipe's sin() and cos() reduce any argument and
// evaluate two polynomials each: several times this.
#define UNAV_GLSL_SIN_PI                                                                \
  "float sin_pi(float x) {\n"                                                           \
  "  float r = abs(x) > 1.5707964 ? 3.1415927 * sign(x) - x : x;\n"                     \
  "  float r2 = r * r;\n"                                                               \
  "  return r * (1.0 + r2 * (-0.16666667 + r2 * (0.0083333333 + r2 * (-1.9841270e-4 + " \
  "r2 * 2.7557319e-6))));\n"                                                            \
  "}\n"

// ---------------------------------------------------------------- scene pass (geometry)
inline constexpr const char* kSceneVS = R"GLSL(
#version 330 core
#ifndef SUN_SHADOW
#define SUN_SHADOW 0
#endif
#ifndef LAMP_SHADOWS
#define LAMP_SHADOWS 0
#endif
#ifndef NLAMPS
#define NLAMPS 0
#endif
layout(location = 0) in vec3 a_pos_W;
layout(location = 1) in vec3 a_nrm_W;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in float a_drop;  // terrain skirts: drawn this far below the point [m] (else 0)
uniform mat4 u_view;   // world -> optical
uniform mat4 u_proj;   // optical -> clip (from K)
// A coarse level of detail: its shadow lookups are made this far above it [m] (sun's map, lamps'
// maps), over the finest surface the maps hold (see Renderer's terrain tiles and rock levels); a
// skirt takes its edge's.
uniform vec2 u_shadow_lift;
out vec3 v_pos_W;
out vec3 v_nrm_W;
out vec2 v_uv;
out float v_z_C;
// Shadow-map coordinates per vertex: linear in the world position, so the perspective-correct
// interpolation gives each pixel exactly its own (a matrix product per pixel costs llvmpipe ~4 %
// of a frame).
#if LAMP_SHADOWS && NLAMPS > 0
uniform mat4 u_shadow_vp[NLAMPS];   // world -> lamp clip
out vec4 v_lamp_clip[NLAMPS];
#endif
#if SUN_SHADOW
uniform mat4 u_sun_vp;   // world -> sun clip (orthographic: no division)
out vec3 v_sun_q;        // sun map coordinates and depth
#endif
void main() {
#if LAMP_SHADOWS && NLAMPS > 0
  vec4 s_lamp = vec4(a_pos_W - vec3(0.0, 0.0, u_shadow_lift.y), 1.0);
  for (int i = 0; i < NLAMPS; ++i) v_lamp_clip[i] = u_shadow_vp[i] * s_lamp;
#endif
#if SUN_SHADOW
  v_sun_q = (u_sun_vp * vec4(a_pos_W - vec3(0.0, 0.0, u_shadow_lift.x), 1.0)).xyz * 0.5 + 0.5;
  // Half a millimetre towards the sun (depth spans 139 m): a 32-bit float map's polygon offset
  // units are ~3e-8 at its depths, below the rounding of a large (clipped) triangle's depth in
  // the map; a 30 m floor of two triangles showed acne streaks ~10 m away without it.
  v_sun_q.z -= 5e-6;
#endif
  vec3 p_W = a_pos_W + vec3(0.0, 0.0, a_drop);
  vec4 p_C = u_view * vec4(p_W, 1.0);
  v_pos_W = p_W;
  v_nrm_W = a_nrm_W;
  v_uv = a_uv;
  v_z_C = p_C.z;
  gl_Position = u_proj * p_C;
}
)GLSL";

inline constexpr const char* kSceneFS = R"GLSL(
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

)GLSL" UNAV_GLSL_SIN_PI R"GLSL(
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
)GLSL";

// ---------------------------------------------------------------- marine snow (points)
inline constexpr const char* kSnowVS = R"GLSL(
#version 330 core
layout(location = 0) in vec3 a_seed;   // uniform in [0, 1)^3
uniform mat4 u_view;
uniform mat4 u_proj;
uniform vec3 u_cam_W;
uniform float u_box;
uniform float u_time;
uniform float u_size_m;
uniform float u_fx;
out vec3 v_pos_W;
out float v_cover;
void main() {
  // Particles fixed in the water (sinking slowly), wrapped into a box around the camera.
  vec3 p = a_seed * u_box + vec3(0.0, 0.0, 0.01 * u_time);
  vec3 rel = mod(p - u_cam_W, u_box) - 0.5 * u_box;
  vec3 pos_W = u_cam_W + rel;
  vec4 p_C = u_view * vec4(pos_W, 1.0);
  float px = u_size_m * u_fx / max(p_C.z, 1e-3);
  gl_PointSize = clamp(px, 1.0, 5.0);
  v_cover = clamp(px * px, 0.0, 1.0);   // sub-pixel particles cover part of a pixel
  v_pos_W = pos_W;
  gl_Position = u_proj * p_C;
  if (p_C.z < 0.15) gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // too close: clip
}
)GLSL";

inline constexpr const char* kSnowFS = R"GLSL(
#version 330 core
#ifndef NLAMPS
#define NLAMPS 0   // compile-time: constant indices into the lamp arrays (no per-pixel gathers)
#endif
in vec3 v_pos_W;
in float v_cover;
uniform vec3 u_cam_W;
uniform vec3 u_E0;
uniform vec3 u_Kd;
uniform vec3 u_betaD;
uniform vec3 u_lamp_pos_W[4];
uniform vec3 u_lamp_dir_W[4];
uniform vec3 u_lamp_I[4];
uniform vec2 u_lamp_cos[4];
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_depth;
void main() {
  vec2 q = gl_PointCoord * 2.0 - 1.0;
  float disc = clamp(1.0 - dot(q, q), 0.0, 1.0);
  vec3 E = 0.6 * u_E0 * exp(-u_Kd * max(v_pos_W.z, 0.0));
  for (int i = 0; i < NLAMPS; ++i) {
    vec3 L = u_lamp_pos_W[i] - v_pos_W;
    float dl = max(length(L), 1.0);
    float cone = smoothstep(u_lamp_cos[i].x, u_lamp_cos[i].y, dot(-L / dl, u_lamp_dir_W[i]));
    E += u_lamp_I[i] * cone / (dl * dl) * exp(-u_betaD * dl);
  }
  float range = length(u_cam_W - v_pos_W);
  o_color = vec4(0.5 * E * exp(-u_betaD * range) * disc * v_cover, 0.0);
  o_depth = 0.0;
}
)GLSL";

// ---------------------------------------------------------------- full-screen post pass
inline constexpr const char* kPostVS = R"GLSL(
#version 330 core
// The post pass at the internal resolution (not REMAP): each pixel's view ray (camera and world
// frames) is affine in its coordinates, so it is interpolated from the corners, not per pixel.
#if defined(REMAP) && !REMAP
#define POST_RAYS 1
uniform vec4 u_K;      // fx, fy, cx, cy
uniform ivec2 u_size;  // the viewport
uniform mat3 u_R_WC;   // optical -> world rotation
noperspective out vec3 v_ray;    // ((x - cx) / fx, (y - cy) / fy, 1) at pixel (x, y)
noperspective out vec3 v_ray_W;  // the same in the world frame
#endif
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  gl_Position = vec4(p, 1.0, 1.0);   // on the far plane: depth 1, the scene's clear value (see PIXELS)
#ifdef POST_RAYS
  vec2 src = (p + 1.0) * 0.5 * vec2(u_size) - 0.5;   // pixel (x, y) has its centre at x + 0.5
  v_ray = vec3((src.x - u_K.z) / u_K.x, (src.y - u_K.w) / u_K.y, 1.0);
  v_ray_W = u_R_WC * v_ray;
#endif
}
)GLSL";

inline constexpr const char* kPostFS = R"GLSL(
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
uniform float u_gain;
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
)GLSL" UNAV_GLSL_SIN_PI R"GLSL(
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

#if MOTION
  // Motion blur: the point seen here (water: far away, so rotation only) was at
  // P0 = P + w x P + v when the shutter opened; its image moved by g = here - there during the
  // exposure, so this pixel gathers the sharp frame along +g (a box filter over the exposure).
  // Depth and segmentation stay those of the stamp.
  {
    vec3 P = ray * (hit ? z : 1.0e3);
    vec3 P0 = P + cross(u_motion_w, P) + u_motion_v;
    if (P0.z > 1e-3) {
      vec2 g = src - (u_K.xy * P0.xy / P0.z + u_K.zw);
      int n = int(clamp(ceil(length(g)), 1.0, 32.0));
      vec3 acc = vec3(0.0);
      for (int k = 0; k < n; ++k)
        acc += textureLod(u_color, (src + ((float(k) + 0.5) / float(n)) * g + 0.5) / vec2(u_size), 0.0).rgb;
      D = acc / float(n);
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
)GLSL";

// ---------------------------------------------------------------- forward-scatter blur levels
// One texel of a 4x downsample: the mean of the 4 x 4 source texels it covers, as four bilinear
// taps at the centres of its 2 x 2 quads (the source clamps to its edges). Drawn twice: the
// scene's colour -> 1/4, then 1/4 -> 1/16 (kPostFS's forward scatter).
inline constexpr const char* kBlurDownFS = R"GLSL(
#version 330 core
uniform sampler2D u_src;     // bilinear
uniform vec2 u_src_texel;    // 1 / the source's size
layout(location = 0) out vec4 o_mean;
void main() {
  vec2 c = gl_FragCoord.xy * 4.0 * u_src_texel;   // the block's centre (texel (i, j) covers 4i .. 4i + 3)
  vec2 d = u_src_texel;
  o_mean = vec4(0.25 * (textureLod(u_src, c - d, 0.0).rgb + textureLod(u_src, c + vec2(d.x, -d.y), 0.0).rgb +
                        textureLod(u_src, c + vec2(-d.x, d.y), 0.0).rgb + textureLod(u_src, c + d, 0.0).rgb),
                1.0);
}
)GLSL";

// ---------------------------------------------------------------- lamp in-scattering
// Single scattering of the lamps' light into each view ray, ray-marched with samples dense
// near the camera (t = tmax f^2), Schlick phase function plus a backward share. Runs at a
// fraction of the image resolution: the veil is smooth, and this is the costliest shader.
inline constexpr const char* kInscatterFS = R"GLSL(
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
)GLSL";

// ---------------------------------------------------------------- lamp shadow maps (depth only)
inline constexpr const char* kShadowVS = R"GLSL(
#version 330 core
layout(location = 0) in vec3 a_pos_W;
uniform mat4 u_vp;   // world -> lamp clip
void main() { gl_Position = u_vp * vec4(a_pos_W, 1.0); }
)GLSL";

inline constexpr const char* kShadowFS = R"GLSL(
#version 330 core
void main() {}
)GLSL";

// ---------------------------------------------------------------- context self-test
inline constexpr const char* kConstFS = R"GLSL(
#version 330 core
out vec4 o;
void main() { o = vec4(0.25, 0.5, 0.75, 1.0); }
)GLSL";

}  // namespace unav::renderer::detail
