// Range from the sonar, incidence cosine, Lambert mu; alpha 1 marks a hit (clear colour: 0).
#version 330 core
in vec3 v_pos_W;
in vec3 v_nrm_W;
uniform vec3 u_origin_W;
uniform float u_mu;
layout(location = 0) out vec4 o_echo;
void main() {
  vec3 d = v_pos_W - u_origin_W;
  float r = length(d);
  float c = abs(dot(normalize(v_nrm_W), d / max(r, 1e-6)));
  o_echo = vec4(r, c, u_mu, 1.0);
}
