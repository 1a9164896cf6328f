#version 330 core
layout(location = 0) in vec3 a_pos_W;
uniform mat4 u_vp;   // world -> lamp clip
void main() { gl_Position = u_vp * vec4(a_pos_W, 1.0); }
