// The sonar pass: world positions and normals of the echoing surfaces.
#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_pos_W;
out vec3 v_nrm_W;
void main() {
  v_pos_W = a_pos;
  v_nrm_W = a_nrm;
  gl_Position = u_proj * u_view * vec4(a_pos, 1.0);
}
