#pragma once
// The ground of an evidence run (generator.hpp): grip discs on the track, a bump and a tilted
// plane, placed by the hidden effects and the seed.
#include <cstdint>
#include <vector>

#include "evidence/truth_effects.hpp"
#include "sim/surface_map.hpp"
#include "sim/track.hpp"

namespace mppi::evidence {

// The ground: grip discs on the track, a bump and a tilted plane, from the effects and the seed.
struct Ground {
  sim::SurfaceMap map;
  double grade_x = 0, grade_y = 0;
  std::vector<sim::SurfacePatch> patches;
  sim::SurfacePatch bump;  // radius 0: none
};

// The ground for these effects; the places of its discs and the grade's heading drawn from the seed.
Ground make_ground(const TruthEffects& e, const sim::Track& ccw, std::uint64_t seed);

}  // namespace mppi::evidence
