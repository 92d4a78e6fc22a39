// AutoRally's basis-function model (dynamics/autorally_bf.hpp), float, the same fast math:
// d/dt [roll, u_x, u_y, yaw_mder] = W phi(s, u) with the 25 basis functions in AutoRally's
// conventions (yaw_mder = minus the yaw rate, steering positive right). NX and P_MODEL_TAIL
// come from the generated layout_autorally_bf.glsl; W (4 x 25, row-major) starts at
// P_MODEL_TAIL. Every loop has a compile-time trip count and is unrolled. The basis functions
// themselves are the C++ model's list (dynamics/autorally_bf_features.hpp).
#define BF_COUNT 25

void bf_basis(float roll, float ux, float uy, float yaw_mder, float u0, float u1, out float phi[BF_COUNT]) {
  bool moving = ux > 0.1;
  precise float inv_ux = 1.0 / (moving ? ux : 1.0);
  precise float beta = moving ? fast_atan((uy + 0.45 * yaw_mder) * inv_ux) : 0.0;
  precise float sa, ca, su, cu;
  fast_sincos(beta - u0, sa, ca);
  fast_sincos(u0, su, cu);
  precise float t = sa / ca;
  precise float t_abs = t * abs(t);
  precise float t3 = t * t * t;
  precise float q = moving ? (uy - 0.35 * yaw_mder) * inv_ux : 0.0;
#include "dynamics/autorally_bf_features.hpp"
}

void model_step(inout float x[NX], float steer, float throttle, float dt) {
  precise float vx = x[3], vy = x[4], r = x[5], roll = x[6];
  float phi[BF_COUNT];
  bf_basis(roll, vx, vy, -r, -steer, throttle, phi);
  float d[4];
  [[unroll]] for (int o = 0; o < 4; ++o) {
    precise float acc = 0.0;
    [[unroll]] for (int b = 0; b < BF_COUNT; ++b) acc += PARAM(P_MODEL_TAIL + o * BF_COUNT + b) * phi[b];
    d[o] = acc;
  }
  precise float sy, cy;
  fast_sincos(x[2], sy, cy);
  x[0] += (cy * vx - sy * vy) * dt;
  x[1] += (sy * vx + cy * vy) * dt;
  x[2] += r * dt;
  x[6] = roll + d[0] * dt;
  x[3] = vx + d[1] * dt;
  x[4] = vy + d[2] * dt;
  x[5] = r - d[3] * dt;
}
