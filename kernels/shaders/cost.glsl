// The AutoRally running cost (costs/autorally_cost.hpp, AutoRallyCost::terms) at the state
// after step t. Cost-map lookup: nearest pixel, clamped to the edge, NaN -> row/column 0.
int clamp_index(float pixel, float max_index) {
  precise float p = (0.0 < pixel) ? pixel : 0.0;  // std::max(0, pixel): NaN -> 0
  return int((p < max_index) ? p : max_index);
}

float stage_cost(float x[NX], int t) {
  precise float px = x[0], py = x[1], vx = x[3], vy = x[4], r = x[5], roll = x[6];
  int col = clamp_index((px - PARAM(P_MAP_X_MIN)) * PARAM(P_MAP_PPM), PARAM(P_MAP_MAX_COL));
  int row = clamp_index((py - PARAM(P_MAP_Y_MIN)) * PARAM(P_MAP_PPM), PARAM(P_MAP_MAX_ROW));
  precise float map_value = map_values[row * int(PARAM(P_MAP_WIDTH)) + col];
  bool crashed = (map_value >= PARAM(P_BOUNDARY)) || (abs(roll) > PARAM(P_MAX_ROLL)) ||
                 (abs(r) > PARAM(P_MAX_YAW_RATE));
  precise float dv = vx - PARAM(P_TARGET_SPEED);
  precise float vmin = PARAM(P_SLIP_MIN_SPEED);
  precise float track = PARAM(P_TRACK_W) * map_value;
  precise float speed = PARAM(P_SPEED_W) * dv * dv;
  precise float crash = crash_cost[t] * (crashed ? 1.0 : 0.0);
  precise float vx2 = vx * vx, vmin2 = vmin * vmin;
  precise float slip = PARAM(P_SLIP_W) * (vy * vy) / ((vx2 < vmin2) ? vmin2 : vx2);
  precise float poison = 0.0 * (px + py + r + roll);
  precise float sum = track + speed + crash + slip + poison;
  return (sum < MPPI_INF) ? sum : MPPI_INF;  // NaN -> +inf
}
