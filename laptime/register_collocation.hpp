#pragma once
// Registers the minimum-time lap by collocation (laptime/min_time_lap.hpp) as the limit-lap
// method "collocation" (sim/limit_lap_methods.hpp). A method whose solver stops short of its
// tolerance throws, so that no unconverged lap becomes a reference.
namespace mppi::laptime {

void register_collocation_limit_lap();

}  // namespace mppi::laptime
