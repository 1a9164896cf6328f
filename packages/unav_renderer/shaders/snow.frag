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
