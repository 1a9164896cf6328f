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
