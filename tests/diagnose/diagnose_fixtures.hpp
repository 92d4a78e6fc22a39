#pragma once
// Set-ups shared by the diagnosis tests: a training problem over a whole recording, and a
// recording of the independent evidence generator (other code than the diagnosis' candidates).
#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "sysid/prepared_recording.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/fit.hpp"
#include "diagnose/model_family.hpp"
#include "evidence/generator.hpp"
#include "evidence/truth_effects.hpp"
#include "test_data.hpp"

namespace mppi::test {

// Training problem over the whole recording: 0.5 s segments, the built-in single-track nominal.
inline diagnose::FitProblem training_problem(const diagnose::PreparedRecording& d) {
  static const auto family = diagnose::make_model_family("single-track");
  diagnose::FitProblem p;
  p.data = &d;
  p.family = family.get();
  p.segments = diagnose::make_segments(d, {}, 25, 25);
  p.scale = diagnose::channel_scales(d, {});
  return p;
}

// A recording of the independent generator (40 s unless told) with the calibrated car and the
// hidden effects `truth` (key=value,...), written to csv.
inline evidence::EvidenceResult independent_recording(const std::filesystem::path& csv, const std::string& truth,
                                                      std::uint64_t seed, const std::string& track,
                                                      const std::string& direction, const std::string& driver,
                                                      double duration_s = 40.0) {
  evidence::EvidenceOptions o;
  o.duration_s = duration_s;
  o.seed = seed;
  o.track = track;
  o.direction = direction;
  o.driver = driver;
  o.vehicle_yaml = data_path("config/autorally_single_track.yaml");
  o.truth_names = evidence::set_truth_effects(truth, &o.truth);
  return evidence::generate_evidence(o, csv.string());
}

// The ids, each followed by a space (for a test's messages): "grip_patch steer_delay ".
inline std::string joined(const std::vector<std::string>& ids) {
  std::string out;
  for (const auto& id : ids) out += id + " ";
  return out;
}

// A fresh directory under the system's temporary directory, removed with what it holds at scope exit.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) : path_(std::filesystem::temp_directory_path() / name) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::filesystem::path operator/(const std::string& file) const { return path_ / file; }

 private:
  std::filesystem::path path_;
};

// The diagnosis of an independent recording, its nominal the car the generator was built from
// (as the sweep runs it), without plots.
inline diagnose::DiagnoseResult diagnose_independent(const evidence::EvidenceResult& rec,
                                                     diagnose::DiagnoseOptions opt = {}) {
  opt.plots = false;
  const diagnose::PreparedRecording d = diagnose::load_recording(rec.csv);
  return diagnose::run_diagnosis(d, *diagnose::make_model_family("single-track", rec.vehicle_yaml), opt);
}

}  // namespace mppi::test
