// The rollout shader, part 1 (before the model): shader constants, the descriptor set, NU.
// The build writes one rollout_<model>.comp per vulkan/shaders/models/<model>.glsl:
//   rollout_head.glsl, layout_<model>.glsl (generated), models/<model>.glsl, rollout_body.glsl.
// One invocation = one sample k: draws its perturbed controls with Philox (kGenerate) or reads
// them (kGenerate = false), steps the model over the horizon and sums the AutoRally running
// cost, as CpuBackend + Controller::sample do. Every loop inside a time step has a compile-time
// trip count and is unrolled, so one invocation runs only T loop iterations (lavapipe silently
// stops loops after 65,535 in all).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool kGenerate = true;  // sample the controls on the device
layout(constant_id = 2) const int kConstantA = 1;    // the model's two integer constants
layout(constant_id = 3) const int kConstantB = 1;    // (GpuTail; e.g. the network's hidden sizes)
layout(constant_id = 4) const bool kWeightsInShared = false;  // model reads its weights from workgroup memory

#include "common.glsl"
#include "interface.glsl"

#define NU 2
