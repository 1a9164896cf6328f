// One texel of a 4x downsample: the mean of the 4 x 4 source texels it covers, as four bilinear
// taps at the centres of its 2 x 2 quads (the source clamps to its edges). Drawn twice: the
// scene's colour -> 1/4, then 1/4 -> 1/16 (kPostFS's forward scatter).
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
