#include "evidence/drivers.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "base/error.hpp"
#include "sim/geometry.hpp"

namespace mppi::evidence {

constexpr double kReactionDelay_s = 0.12;  // the human's
constexpr double kHandKeepPer20ms = 0.65;   // the human's hand: share of its position kept per 20 ms
constexpr double kPedalRate_per_s = 2.0;    // the human's foot: throttle change per second

Driver::Driver(const std::string& kind, const sim::Track& track, std::uint64_t seed, double speed_min_mps,
               double speed_max_mps, double wheelbase_m, double max_steer_rad, double period_s)
    : kind_(kind), period_s_(period_s), track_(track), rng_(seed * 2654435761ULL + 97), speed_min_(speed_min_mps),
      speed_max_(speed_max_mps), wheelbase_(wheelbase_m), max_steer_(max_steer_rad) {
  if (kind != "pursuit" && kind != "human") throw Error("evidence driver '" + kind + "': valid are pursuit, human");
  if (!(speed_min_mps > 0 && speed_max_mps >= speed_min_mps)) throw Error("evidence driver: need 0 < speed min <= max");
  if (!(period_s > 0 && period_s <= 0.5)) throw Error("evidence driver: need a period in (0, 0.5] s");
}

void Driver::respawned() {
  have_hint_ = false;
  integral_ = 0;
  hand_ = 0;
  foot_ = 0;
  steer_memory_.clear();
}

double Driver::curvature_ahead(double arc_m, double distance_m) const {
  // Largest |heading change per metre| over the next distance_m of centreline, 2 m chords.
  const auto& c = track_.centreline();
  const auto& arc = track_.centreline_arc_m();
  const double length = track_.length_m();
  auto point_at = [&](double s) {
    s = std::fmod(s, length);
    if (s < 0) s += length;
    const auto it = std::upper_bound(arc.begin(), arc.end(), s);
    const std::size_t i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - arc.begin() - 1)) % c.size();
    const sim::Vec2 a = c[i], b = c[(i + 1) % c.size()];
    const double f = (s - arc[i]) / std::max(1e-9, arc[i + 1] - arc[i]);
    return sim::Vec2{a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)};
  };
  double worst = 0;
  for (double d = 0; d < distance_m; d += 1.0) {
    const sim::Vec2 p0 = point_at(arc_m + d), p1 = point_at(arc_m + d + 2), p2 = point_at(arc_m + d + 4);
    const double h1 = std::atan2(p1.y - p0.y, p1.x - p0.x), h2 = std::atan2(p2.y - p1.y, p2.x - p1.x);
    double dh = h2 - h1;
    while (dh > std::numbers::pi) dh -= 2 * std::numbers::pi;
    while (dh < -std::numbers::pi) dh += 2 * std::numbers::pi;
    worst = std::max(worst, std::abs(dh) / 2.0);
  }
  return worst;
}

double Driver::target_speed(const DriverView& v, double arc_m) {
  std::uniform_real_distribution<double> uni(0, 1);
  if (kind_ == "pursuit") {
    if (v.t_s >= schedule_until_s_) {
      schedule_speed_ = speed_min_ + (speed_max_ - speed_min_) * uni(rng_);
      schedule_until_s_ = v.t_s + 2 + 4 * uni(rng_);
    }
    // Bold, but not blind: the schedule is capped where the curvature ahead asks 5 m/s^2.
    const double kappa = curvature_ahead(arc_m, 3 + 1.2 * v.speed_mps);
    return kappa > 1e-4 ? std::max(speed_min_, std::min(schedule_speed_, std::sqrt(5.0 / kappa))) : schedule_speed_;
  }
  if (v.t_s >= nerve_until_s_) {  // a human's daring changes from stretch to stretch
    nerve_mps2_ = 2.5 + 3.0 * uni(rng_);
    nerve_until_s_ = v.t_s + 5 + 10 * uni(rng_);
  }
  const double kappa = curvature_ahead(arc_m, 3 + 1.2 * v.speed_mps);
  const double corner = kappa > 1e-4 ? std::sqrt(nerve_mps2_ / kappa) : speed_max_;
  return std::clamp(corner, speed_min_, speed_max_);
}

std::pair<double, double> Driver::command(const DriverView& v) {
  const auto& c = track_.centreline();
  const sim::Vec2 p{v.x_m, v.y_m};
  const sim::ClosestPoint cp = have_hint_ ? sim::closest_point_in_range(c, true, p, static_cast<std::ptrdiff_t>(hint_) - 20, 60)
                                          : sim::closest_point(c, true, p);
  hint_ = cp.segment;
  have_hint_ = true;
  const auto& arc = track_.centreline_arc_m();
  const double s = arc[cp.segment] + cp.t * (arc[cp.segment + 1] - arc[cp.segment]);

  // Pure pursuit to a point lookahead metres further along the centreline.
  const double lookahead = (kind_ == "human" ? 2.5 : 1.2) + 0.25 * v.speed_mps;
  const double length = track_.length_m();
  double target_s = std::fmod(s + lookahead, length);
  const auto it = std::upper_bound(arc.begin(), arc.end(), target_s);
  const std::size_t i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - arc.begin() - 1)) % c.size();
  const sim::Vec2 a = c[i], b = c[(i + 1) % c.size()];
  const double f = (target_s - arc[i]) / std::max(1e-9, arc[i + 1] - arc[i]);
  const double gx = a.x + f * (b.x - a.x) - v.x_m, gy = a.y + f * (b.y - a.y) - v.y_m;
  const double alpha = std::atan2(gy, gx) - v.yaw_rad;
  const double ld = std::max(0.5, std::hypot(gx, gy));
  double steer = std::atan(2 * wheelbase_ * std::sin(alpha) / ld) / max_steer_;

  std::uniform_real_distribution<double> uni(0, 1);
  if (kind_ == "pursuit") {  // steering dither: random steps, held 0.1-0.4 s
    if (v.t_s >= dither_until_s_) {
      dither_ = 0.18 * (2 * uni(rng_) - 1);
      dither_until_s_ = v.t_s + 0.1 + 0.3 * uni(rng_);
    }
    steer += dither_ + 0.06 * std::sin(2 * std::numbers::pi * 1.3 * v.t_s);
  } else {  // a human: reacts 0.12 s late, moves the hand smoothly, small tremor
    steer_memory_.push_back(steer);
    const std::size_t late = static_cast<std::size_t>(std::lround(kReactionDelay_s / period_s_));
    const double seen = steer_memory_.size() > late ? steer_memory_[steer_memory_.size() - 1 - late] : steer;
    if (steer_memory_.size() > 2 * late + 64)
      steer_memory_.erase(steer_memory_.begin(), steer_memory_.end() - static_cast<std::ptrdiff_t>(late + 32));
    hand_ += (1.0 - std::pow(kHandKeepPer20ms, period_s_ / 0.02)) * (seen - hand_);
    std::normal_distribution<double> tremor(0, 0.02);
    steer = hand_ + tremor(rng_);
  }
  steer = std::clamp(steer, -1.0, 1.0);

  // Speed: feed-forward for the car's steady speed, PI on the error, brakes when too fast.
  const double vt = target_speed(v, s);
  const double err = vt - v.speed_mps;
  integral_ = std::clamp(integral_ + err * period_s_, -3.0, 3.0);
  double throttle = std::clamp(0.05 * vt + 0.25 * err + 0.05 * integral_, -0.9, 0.9);
  if (kind_ == "human") {
    // A human's foot: it squeezes the throttle at low speed (no full throttle from rest), lifts
    // when the car yaws beyond what the road's bend asks (the rear stepping out) and moves at
    // most 2 per second (about half a second from idle to full).
    throttle = std::min(throttle, 0.35 + 0.12 * v.speed_mps);
    const double bend_radps = v.speed_mps * curvature_ahead(s, 2.0);
    const double excess_radps = std::abs(v.yaw_rate_radps) - (1.15 * bend_radps + 0.15);
    if (excess_radps > 0) throttle = std::min(throttle, std::max(0.0, 0.3 - 0.6 * excess_radps));
    const double step = kPedalRate_per_s * period_s_;
    foot_ = std::clamp(throttle, foot_ - step, foot_ + step);
    throttle = foot_;
  }
  return {steer, throttle};
}

}  // namespace mppi::evidence
