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
