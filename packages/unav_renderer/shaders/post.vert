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
