#include "evidence/ground.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace mppi::evidence {

Ground make_ground(const TruthEffects& e, const sim::Track& ccw, std::uint64_t seed) {
  Ground g;
  std::mt19937_64 rng(seed * 7477 + 11);
  std::uniform_real_distribution<double> uni(0, 1);
  sim::SurfaceLayer grip, elevation;
  grip.default_value = 1;
  auto centreline_at = [&](double arc_m) {  // the centreline point at this arc length
    const auto& arc = ccw.centreline_arc_m();
    const auto it = std::upper_bound(arc.begin(), arc.end(), arc_m);
    const std::size_t k =
        static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - arc.begin() - 1)) % ccw.centreline().size();
    return ccw.centreline()[k];
  };
  for (int i = 0; i < e.grip_patches; ++i) {  // spread along the lap, jittered
    sim::SurfacePatch p;
    p.centre_m = centreline_at(ccw.length_m() * (i + 0.2 + 0.6 * uni(rng)) / e.grip_patches);
    p.radius_m = 2.5 + 1.5 * uni(rng);
    p.edge_m = 1.0;
    p.value = e.grip_patch_scale;
    grip.patches.push_back(p);
  }
  if (e.bump_height_m != 0) {  // on the centreline, somewhere along the lap
    sim::SurfacePatch hill;
    hill.centre_m = centreline_at(ccw.length_m() * uni(rng));
    hill.radius_m = e.bump_radius_m;
    hill.value = e.bump_height_m;
    elevation.patches.push_back(hill);
    g.bump = hill;
  }
  if (e.grade != 0) {
    const double heading = 2 * std::numbers::pi * uni(rng);
    g.grade_x = elevation.grade_x = e.grade * std::cos(heading);
    g.grade_y = elevation.grade_y = e.grade * std::sin(heading);
  }
  g.patches = grip.patches;
  g.map = sim::SurfaceMap(std::move(grip), std::move(elevation));
  return g;
}

}  // namespace mppi::evidence
