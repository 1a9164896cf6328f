// sin(x) for |x| <= pi, spliced into the scene and post shaders: folded to [-pi/2, pi/2], degree-9
// Taylor (error (pi/2)^11 / 11! = 3.6e-6). llvmpipe's sin() and cos() reduce any argument and
// evaluate two polynomials each: several times this.
float sin_pi(float x) {
  float r = abs(x) > 1.5707964 ? 3.1415927 * sign(x) - x : x;
  float r2 = r * r;
  return r * (1.0 + r2 * (-0.16666667 + r2 * (0.0083333333 + r2 * (-1.9841270e-4 + r2 * 2.7557319e-6))));
}
