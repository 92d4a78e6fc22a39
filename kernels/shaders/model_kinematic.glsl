// The kinematic bicycle (dynamics/kinematic_bicycle.hpp). Parameters from P_MODEL:
// 1 / wheelbase, max steer [rad], max acceleration, speed damping.
#define NX 7
void model_step(inout float x[NX], float steer, float throttle, float dt) {
  precise float inv_l = PARAM(P_MODEL + 0), max_steer = PARAM(P_MODEL + 1);
  precise float a_max = PARAM(P_MODEL + 2), damping = PARAM(P_MODEL + 3);
  precise float delta = clampf(steer, -1.0, 1.0) * max_steer;
  precise float sd, cd, sy, cy;
  fast_sincos(delta, sd, cd);
  fast_sincos(x[2], sy, cy);
  precise float curvature = sd / cd * inv_l;
  precise float v = x[3];
  x[0] += v * cy * dt;
  x[1] += v * sy * dt;
  x[2] += v * curvature * dt;
  precise float v_new = v + (a_max * throttle - damping * v) * dt;
  x[3] = v_new;
  x[4] = 0.0;
  x[5] = v_new * curvature;
  x[6] = 0.0;
}
