// The AutoRally network (dynamics/autorally_nn.hpp): a 6-H1-H2-4 MLP, tanh, tanh, linear, in
// the library's conventions; explicit Euler. Parameters from P_MODEL: W1 (H1 x 6), b1, W2
// (H2 x H1), b2, W3 (4 x H2), b3, row-major. The neuron loops are unrolled (hidden sizes are
// specialization constants), so the weights are read at constant offsets.
#define NX 7
#define NET_IN 6
#define NET_OUT 4
void model_step(inout float x[NX], float steer, float throttle, float dt) {
  const int w1 = P_MODEL;
  const int b1 = w1 + kHidden1 * NET_IN;
  const int w2 = b1 + kHidden1;
  const int b2 = w2 + kHidden2 * kHidden1;
  const int w3 = b2 + kHidden2;
  const int b3 = w3 + NET_OUT * kHidden2;
  float a0[NET_IN] = float[NET_IN](x[6], x[3], x[4], x[5], steer, throttle);
  float h1[kHidden1];
  [[unroll]] for (int o = 0; o < kHidden1; ++o) {
    float acc = PARAM(b1 + o);
    [[unroll]] for (int i = 0; i < NET_IN; ++i) acc += PARAM(w1 + o * NET_IN + i) * a0[i];
    h1[o] = fast_tanh(acc);
  }
  float h2[kHidden2];
  [[unroll]] for (int o = 0; o < kHidden2; ++o) {
    float acc = PARAM(b2 + o);
    [[unroll]] for (int i = 0; i < kHidden1; ++i) acc += PARAM(w2 + o * kHidden1 + i) * h1[i];
    h2[o] = fast_tanh(acc);
  }
  float d[NET_OUT];
  [[unroll]] for (int o = 0; o < NET_OUT; ++o) {
    float acc = PARAM(b3 + o);
    [[unroll]] for (int i = 0; i < kHidden2; ++i) acc += PARAM(w3 + o * kHidden2 + i) * h2[i];
    d[o] = acc;
  }
  precise float s, c;
  fast_sincos(x[2], s, c);
  precise float vx = x[3], vy = x[4];
  x[0] += (c * vx - s * vy) * dt;
  x[1] += (s * vx + c * vy) * dt;
  x[2] += x[5] * dt;
  x[6] += d[0] * dt;
  x[3] = vx + d[1] * dt;
  x[4] = vy + d[2] * dt;
  x[5] += d[3] * dt;
}
