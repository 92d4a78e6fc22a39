// The kinematic bicycle (dynamics/kinematic_bicycle.hpp). Its parameters (K_*) and NX are
// defined by the generated layout_kinematic.glsl from dynamics/models/kinematic_model.hpp.
void model_step(inout float x[NX], float steer, float throttle, float dt) {
  precise float inv_l = K_INV_WHEELBASE, max_steer = K_MAX_STEER;
  precise float a_max = K_MAX_ACCEL, damping = K_DAMPING;
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
