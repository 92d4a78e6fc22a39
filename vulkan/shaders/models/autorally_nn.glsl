// The AutoRally network (dynamics/autorally_nn.hpp): a 6-H1-H2-4 MLP, tanh, tanh, linear, in
// the library's conventions; explicit Euler. NX and P_MODEL_TAIL come from the generated
// layout_autorally_nn.glsl (dynamics/models/autorally_nn_model.hpp). Parameters from P_MODEL_TAIL,
// each layer as W (rows
// padded to a multiple of 4 floats) then b (padded to a multiple of 4), so that a row is read
// 4 weights per uniform load (lavapipe: one load per weight made the net ~4x slower). The
// neuron loops are unrolled (hidden sizes are specialization constants), so every read is at a
// constant offset, and the sums run in the CPU's order: acc = b; acc += w_i a_i, i = 0, 1, ...
// The hidden sizes are the rollout shader's two model constants.
#define kHidden1 kConstantA
#define kHidden2 kConstantB
#define NET_IN 6
#define NET_OUT 4
#define PAD4(n) ((((n) + 3) / 4) * 4)

// The network's parameters (from P_MODEL_TAIL, a multiple of 4) in vec4s, and a copy of them in
// workgroup memory, which the layers read when kWeightsInShared (on a GPU, the uniform buffer's
// constant cache is too small for them). NET_W4(i): the vec4 at network float offset i.
#define NET_VEC4S ((kHidden1 * PAD4(NET_IN) + PAD4(kHidden1) + kHidden2 * PAD4(kHidden1) + \
                    PAD4(kHidden2) + NET_OUT * PAD4(kHidden2) + PAD4(NET_OUT)) / 4)
shared vec4 net_shared[NET_VEC4S];
#define NET_W4(i) (kWeightsInShared ? net_shared[((i) - P_MODEL_TAIL) >> 2] : params[(i) >> 2])
#define NET_PARAM(i) NET_W4(i)[(i) & 3]
void copy_network_to_shared() {
  if (!kWeightsInShared) return;
  for (uint i = gl_LocalInvocationIndex; i < uint(NET_VEC4S); i += gl_WorkGroupSize.x)
    net_shared[i] = params[(P_MODEL_TAIL >> 2) + int(i)];
  barrier();
}
#define MODEL_PRELUDE copy_network_to_shared

// acc = bias + sum_i w[row][i] a[i] over n inputs, row stride PAD4(n), from float offset w_row.
#define DENSE_ROW(acc, w_row, a, n)                                  \
  [[unroll]] for (int i = 0; i < PAD4(n); i += 4) {                  \
    vec4 w4 = NET_W4(w_row + i);                                     \
    acc += w4.x * a[i];                                              \
    if (i + 1 < (n)) acc += w4.y * a[i + 1];                         \
    if (i + 2 < (n)) acc += w4.z * a[i + 2];                         \
    if (i + 3 < (n)) acc += w4.w * a[i + 3];                         \
  }

void model_step(inout float x[NX], float steer, float throttle, float dt) {
  const int w1 = P_MODEL_TAIL;
  const int b1 = w1 + kHidden1 * PAD4(NET_IN);
  const int w2 = b1 + PAD4(kHidden1);
  const int b2 = w2 + kHidden2 * PAD4(kHidden1);
  const int w3 = b2 + PAD4(kHidden2);
  const int b3 = w3 + NET_OUT * PAD4(kHidden2);
  float a0[NET_IN] = float[NET_IN](x[6], x[3], x[4], x[5], steer, throttle);
  float h1[kHidden1];
  [[unroll]] for (int o = 0; o < kHidden1; ++o) {
    float acc = NET_PARAM(b1 + o);
    DENSE_ROW(acc, w1 + o * PAD4(NET_IN), a0, NET_IN)
    h1[o] = fast_tanh(acc);
  }
  float h2[kHidden2];
  [[unroll]] for (int o = 0; o < kHidden2; ++o) {
    float acc = NET_PARAM(b2 + o);
    DENSE_ROW(acc, w2 + o * PAD4(kHidden1), h1, kHidden1)
    h2[o] = fast_tanh(acc);
  }
  float d[NET_OUT];
  [[unroll]] for (int o = 0; o < NET_OUT; ++o) {
    float acc = NET_PARAM(b3 + o);
    DENSE_ROW(acc, w3 + o * PAD4(kHidden2), h2, kHidden2)
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
