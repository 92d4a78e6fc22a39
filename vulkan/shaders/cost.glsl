// The AutoRally running cost (costs/autorally_cost.hpp, AutoRallyCost::terms) at the state
// after step t: a sum of the terms of costs/autorally_cost_terms.hpp, each a function below
// (its kGlsl), added in the list's order by COST_TERMS_SUM (generated into layout_cost.glsl).
// Cost-map lookup: nearest pixel, clamped to the edge, NaN -> row/column 0.
int clamp_index(float pixel, float max_index) {
  precise float p = (0.0 < pixel) ? pixel : 0.0;  // std::max(0, pixel): NaN -> 0
  return int((p < max_index) ? p : max_index);
}

// What the terms read at one state (CostState in costs/autorally_cost_terms.hpp).
struct CostState {
  float map_value;
  float crashed;  // 0 or 1
  float vx, vy;
  float crash_cost;
};

float track_term(CostState s) {
  precise float r = PARAM(P_TRACK_W) * s.map_value;
  return r;
}

float speed_term(CostState s) {
  precise float dv = s.vx - PARAM(P_TARGET_SPEED);
  precise float r = PARAM(P_SPEED_W) * dv * dv;
  return r;
}

float crash_term(CostState s) {
  precise float r = s.crash_cost * s.crashed;
  return r;
}

float slip_term(CostState s) {
  precise float vmin = PARAM(P_SLIP_MIN_SPEED);
  precise float vx2 = s.vx * s.vx, vmin2 = vmin * vmin;
  precise float r = PARAM(P_SLIP_W) * (s.vy * s.vy) / ((vx2 < vmin2) ? vmin2 : vx2);
  return r;
}

float stage_cost(float x[NX], int t) {
  precise float px = x[0], py = x[1], vx = x[3], vy = x[4], r = x[5], roll = x[6];
  int col = clamp_index((px - PARAM(P_MAP_X_MIN)) * PARAM(P_MAP_PPM), PARAM(P_MAP_MAX_COL));
  int row = clamp_index((py - PARAM(P_MAP_Y_MIN)) * PARAM(P_MAP_PPM), PARAM(P_MAP_MAX_ROW));
  precise float map_value = map_values[row * int(PARAM(P_MAP_WIDTH)) + col];
  bool crashed = (map_value >= PARAM(P_BOUNDARY)) || (abs(roll) > PARAM(P_MAX_ROLL)) ||
                 (abs(r) > PARAM(P_MAX_YAW_RATE));
  CostState s = CostState(map_value, crashed ? 1.0 : 0.0, vx, vy, crash_cost[t]);
  precise float poison = 0.0 * (px + py + r + roll);
  precise float sum = COST_TERMS_SUM(s) + poison;
  return (sum < MPPI_INF) ? sum : MPPI_INF;  // NaN -> +inf
}
