// mppi-bench: the sim-vs-real diagnosis' replay, the loop that every fit runs thousands of times:
// open-loop predictions of 0.5 s (25 rows at 50 Hz, 10 substeps a row, 0.5 s of command history
// through the full model before each start) for 120 segments of a recording, by the corrected
// single-track model with a steering lag and a grip patch, single thread:
//   BM_ReplaySegments/0  one segment at a time (predict_segment)
//   BM_ReplaySegments/1  ReplayModel::kLanes segments at a time in SIMD (predict_segments)
// items = segments.
#include <benchmark/benchmark.h>

#include <vector>

#include "sysid/prepared_recording.hpp"
#include "diagnose/model_family.hpp"
#include "diagnose/replay.hpp"
#include "diagnose/synth.hpp"

namespace {

void BM_ReplaySegments(benchmark::State& state) {
  using namespace mppi::diagnose;
  static const PreparedRecording d = prepare(synthesize_open_loop({}, 7, 80.0), "bench drive");
  mppi::EffectParams e;
  e.steer_lag_s = 0.08;
  e.patch_x_m = 10;
  e.patch_radius_m = 8;
  e.patch_grip_scale = 0.6;
  const auto model = make_model_family("single-track")->make(e);
  std::vector<Segment> segs = make_segments(d, {}, 25, 25);
  segs.resize(std::min<std::size_t>(segs.size(), 120));
  std::vector<double> out(segs.size() * 25 * kPredStride);
  const bool lanes = state.range(0) != 0;
  for (auto _ : state) {
    if (lanes) {
      predict_segments(*model, d, segs, ReplayOptions{}, out.data());
    } else {
      for (std::size_t n = 0; n < segs.size(); ++n)
        predict_segment(*model, d, segs[n], ReplayOptions{}, out.data() + n * 25 * kPredStride);
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(segs.size()));
}
BENCHMARK(BM_ReplaySegments)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
