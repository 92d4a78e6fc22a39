#pragma once
// Set-ups shared by the diagnosis tests: a training problem over a whole recording, and a
// recording of the independent evidence generator (other code than the diagnosis' candidates).
#include <cstdint>
#include <filesystem>
#include <string>

#include "sysid/diagnose/data.hpp"
#include "sysid/diagnose/fit.hpp"
#include "sysid/diagnose/model_family.hpp"
#include "sysid/evidence/generator.hpp"
#include "sysid/evidence/truth_effects.hpp"
#include "test_data.hpp"

namespace mppi::test {

// Training problem over the whole recording: 0.5 s segments, the built-in single-track nominal.
inline diagnose::FitProblem training_problem(const diagnose::DiagData& d) {
  static const auto family = diagnose::make_model_family("single-track");
  diagnose::FitProblem p;
  p.data = &d;
  p.family = family.get();
  p.segments = diagnose::make_segments(d, {}, 25, 25);
  p.scale = diagnose::channel_scales(d, {});
  return p;
}

// A 40-s recording of the independent generator with the calibrated car and the hidden effects
// `truth` (key=value,...), written to csv.
inline evidence::EvidenceResult independent_recording(const std::filesystem::path& csv, const std::string& truth,
                                                      std::uint64_t seed, const std::string& track,
                                                      const std::string& direction, const std::string& driver) {
  evidence::EvidenceOptions o;
  o.duration_s = 40;
  o.seed = seed;
  o.track = track;
  o.direction = direction;
  o.driver = driver;
  o.vehicle_yaml = data_path("config/autorally_single_track.yaml");
  o.truth_names = evidence::set_truth_effects(truth, &o.truth);
  return evidence::generate_evidence(o, csv.string());
}

}  // namespace mppi::test
