// The single-track model with Pacejka tyres (dynamics/single_track.hpp, dynamics/pacejka.hpp),
// float, the same fast math. Its parameters (K_*, SingleTrackCoeffs<float>) and NX are defined
// by the generated layout_single_track.glsl from dynamics/models/single_track_model.hpp.

float maxf(float a, float b) { return (a < b) ? b : a; }  // std::max
float minf(float a, float b) { return (b < a) ? b : a; }  // std::min

// b, c, d: the axle's B, C, D (front K_B, K_C, K_D; rear K_RB, K_RC, K_RD); E, Sh, Sv shared.
float magic_formula_mu(float total_slip, float b, float c_shape, float d) {
  precise float se = total_slip - K_SH;
  precise float bse = b * se;
  precise float s, c;
  fast_sincos(c_shape * fast_atan(bse - K_E * (bse - fast_atan(se))), s, c);
  return d * s + K_SV;
}

// (mu_x, mu_y) of one tyre from its tyre-frame velocity and rim speed (tyre_friction()).
vec2 tyre_mu(float v_x, float v_y, float rim_speed, float b, float c_shape, float d) {
  precise float inv_den = 1.0 / maxf(abs(rim_speed), K_SLIP_FLOOR);
  precise float slip_x = (v_x - rim_speed) * inv_den;
  precise float slip_y = v_y * inv_den;
  precise float slip = fast_sqrt(slip_x * slip_x + slip_y * slip_y);
  precise float mu = magic_formula_mu(slip, b, c_shape, d);
  precise float scale = -mu * fast_tanh(slip * K_INV_SLIP_BLEND) / maxf(slip, 1e-12);
  return vec2(slip_x * scale, slip_y * scale);
}

void model_step(inout float x[NX], float steer, float throttle, float dt) {
  precise float vx = x[3], vy = x[4], r = x[5], omega_f = x[7], omega_r = x[8];
  precise float delta = minf(maxf(steer, -1.0), 1.0) * K_MAX_STEER;
  precise float sd, cd;
  fast_sincos(delta, sd, cd);
  precise float vy_front = vy + r * K_LF;
  precise float front_vx = vx * cd + vy_front * sd;
  precise float front_vy = -vx * sd + vy_front * cd;
  vec2 fmu = tyre_mu(front_vx, front_vy, omega_f * K_RADIUS, K_B, K_C, K_D);
  vec2 rmu = tyre_mu(vx, vy - r * K_LR, omega_r * K_RADIUS, K_RB, K_RC, K_RD);
  precise float den = K_LF + K_LR + K_H * (fmu.x * cd - fmu.y * sd - rmu.x);
  precise float fz_front = K_WEIGHT * (K_LR - K_H * rmu.x) / maxf(den, 1e-3);
  precise float front_fz = minf(maxf(fz_front, 0.0), K_WEIGHT);
  precise float rear_fz = K_WEIGHT - front_fz;
  precise float ffx = fmu.x * front_fz, ffy = fmu.y * front_fz;
  precise float rfx = rmu.x * rear_fz, rfy = rmu.y * rear_fz;
  precise float motor_omega = K_FRONT_DRIVE * omega_f + K_REAR_DRIVE * omega_r;
  precise float drive = K_STALL * (maxf(throttle, 0.0) + K_BRAKE_RATIO * minf(throttle, 0.0) - motor_omega * K_RADIUS * K_INV_NO_LOAD);
  precise float resist = -K_ROLLING * fast_tanh(vx * K_INV_ROLLING_SPEED) - K_DRAG * vx * abs(vx);
  precise float body_fx = ffx * cd - ffy * sd + rfx;
  precise float body_fy = ffx * sd + ffy * cd + rfy;
  precise float dvx = (body_fx + resist) * K_INV_MASS + vy * r;
  precise float dvy = body_fy * K_INV_MASS - vx * r;
  precise float dr = ((ffy * cd + ffx * sd) * K_LF - rfy * K_LR) * K_INV_IZ;
  precise float dwf = (K_FRONT_DRIVE * drive - ffx * K_RADIUS) * K_INV_IF;
  precise float dwr = (K_REAR_DRIVE * drive - rfx * K_RADIUS) * K_INV_IR;
  precise float sy, cy;
  fast_sincos(x[2], sy, cy);
  x[0] += (cy * vx - sy * vy) * dt;
  x[1] += (sy * vx + cy * vy) * dt;
  x[2] += r * dt;
  x[3] = vx + dvx * dt;
  x[4] = vy + dvy * dt;
  x[5] = r + dr * dt;
  x[7] += dwf * dt;
  x[8] += dwr * dt;
}
