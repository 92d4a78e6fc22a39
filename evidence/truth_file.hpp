#pragma once
// FILE.truth.json of an evidence run (generator.hpp): the run, the noise, and each effect with its
// sizes, where the ground has it, the times the car was on it and the effect-table ids.
#include "evidence/generator.hpp"
#include "evidence/ground.hpp"

namespace mppi::evidence {

// Writes res.truth_json.
void write_truth_json(const EvidenceOptions& o, const Ground& ground, const EvidenceResult& res);

}  // namespace mppi::evidence
