#include "sim/racing_line.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include <Eigen/Sparse>

#include "base/error.hpp"

namespace mppi::sim {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Triplet = Eigen::Triplet<double>;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Distance along the ray o + t d (t > 0) to the first crossing of the closed polygon, or inf.
double ray_to_polygon(Vec2 o, Vec2 d, const Polyline& polygon) {
  double best = kInf;
  const std::size_t n = polygon.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 a = polygon[k];
    const Vec2 e = polygon[(k + 1) % n] - a;
    const double den = cross(d, e);
    if (den == 0.0) continue;
    const Vec2 ao = a - o;
    const double t = cross(ao, e) / den;
    const double u = cross(ao, d) / den;
    if (t > 0.0 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
  }
  return best;
}

// The box-constrained quadratic programme min 1/2 x'Hx + f'x, lo <= x <= hi, by the primal-dual
// active-set method (Hintermueller, Ito, Kunisch 2002): guess the bounds that hold, solve the
// equality-constrained problem on the rest, re-guess from the multipliers, until the guess holds.
Eigen::VectorXd box_qp(const SparseMatrix& H, const Eigen::VectorXd& f, const Eigen::VectorXd& lo,
                       const Eigen::VectorXd& hi, int max_iterations) {
  const Eigen::Index n = f.size();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n).cwiseMax(lo).cwiseMin(hi);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(n);
  std::vector<int> state(static_cast<std::size_t>(n), 2);  // -1 lower, +1 upper, 0 free; 2 = unset
  const double c = H.diagonal().mean();
  for (int it = 0; it < max_iterations; ++it) {
    std::vector<int> next(state.size());
    for (Eigen::Index i = 0; i < n; ++i)
      next[i] = lambda[i] + c * (x[i] - hi[i]) > 0.0 ? 1 : (lambda[i] + c * (x[i] - lo[i]) < 0.0 ? -1 : 0);
    if (next == state) break;
    state = next;
    // Free variables: index in the reduced system.
    std::vector<Eigen::Index> free_index(state.size(), -1);
    Eigen::Index m = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (state[i] == 0) free_index[i] = m++;
      else x[i] = state[i] > 0 ? hi[i] : lo[i];
    }
    if (m > 0) {
      std::vector<Triplet> triplets;
      Eigen::VectorXd rhs = -f;
      for (Eigen::Index col = 0; col < H.outerSize(); ++col)
        for (SparseMatrix::InnerIterator e(H, col); e; ++e) {
          const Eigen::Index r = e.row();
          if (free_index[r] < 0) continue;
          if (free_index[col] >= 0) triplets.emplace_back(free_index[r], free_index[col], e.value());
          else rhs[r] -= e.value() * x[col];
        }
      Eigen::VectorXd rhs_free(m);
      for (Eigen::Index i = 0; i < n; ++i)
        if (free_index[i] >= 0) rhs_free[free_index[i]] = rhs[i];
      SparseMatrix reduced(m, m);
      reduced.setFromTriplets(triplets.begin(), triplets.end());
      Eigen::SimplicialLDLT<SparseMatrix> solver(reduced);
      if (solver.info() != Eigen::Success) throw Error("racing_line: the quadratic programme is singular");
      const Eigen::VectorXd x_free = solver.solve(rhs_free);
      for (Eigen::Index i = 0; i < n; ++i)
        if (free_index[i] >= 0) x[i] = x_free[free_index[i]];
    }
    lambda = -(H * x + f);
    for (Eigen::Index i = 0; i < n; ++i)
      if (state[i] == 0) lambda[i] = 0.0;
  }
  return x.cwiseMax(lo).cwiseMin(hi);  // feasible even if the active set did not settle
}

// Signed Menger curvature at b of the path a -> b -> c (the circle through the three points).
double menger_curvature(Vec2 a, Vec2 b, Vec2 c) {
  const double den = distance(a, b) * distance(b, c) * distance(a, c);
  return den > 0.0 ? 2.0 * cross(b - a, c - b) / den : 0.0;
}

// Offsets n minimising sum_i kappa_i^2 + w sum_i |p_{i+1} - p_i|^2 / h^2, kappa_i the Menger
// curvature at p_i = c_i + n_i N_i, h the stations' spacing: the line's curvature traded for its
// length (w = length_weight; the second sum is least, for a given number of stations, on the
// shortest line). Gauss-Newton with Levenberg-Marquardt damping from x0: each step minimises
// |r + J dn|^2 + mu |dn|^2 within the bounds (r the residuals kappa_i and sqrt(w) (p_{i+1} - p_i) / h,
// J = dr / dn: the curvature rows by central differences), and is taken if it lowers the sum.
Eigen::VectorXd min_curvature_offsets(const Polyline& c, const Polyline& normal, const Eigen::VectorXd& lo,
                                      const Eigen::VectorXd& hi, double length_weight, const Eigen::VectorXd& x0,
                                      int max_iterations) {
  const auto n = static_cast<Eigen::Index>(c.size());
  const double h = polyline_length(c, true) / static_cast<double>(n);
  const double scale = std::sqrt(length_weight) / h;
  auto point = [&](const Eigen::VectorXd& x, Eigen::Index j, Eigen::Index moved, double dn) {
    j = (j + n) % n;
    return c[j] + (x[j] + (j == moved ? dn : 0.0)) * normal[j];
  };
  auto kappa = [&](const Eigen::VectorXd& x, Eigen::Index i, Eigen::Index moved, double dn) {
    return menger_curvature(point(x, i - 1, moved, dn), point(x, i, moved, dn), point(x, i + 1, moved, dn));
  };
  auto residuals = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd r(3 * n);
    for (Eigen::Index i = 0; i < n; ++i) {
      r[i] = kappa(x, i, -1, 0.0);
      const Vec2 d = point(x, i + 1, -1, 0.0) - point(x, i, -1, 0.0);
      r[n + i] = scale * d.x;
      r[2 * n + i] = scale * d.y;
    }
    return r;
  };
  Eigen::VectorXd x = x0.cwiseMax(lo).cwiseMin(hi);
  Eigen::VectorXd r = residuals(x);
  double damping = -1.0;
  constexpr double kStep = 1e-6;
  for (int it = 0; it < 200; ++it) {
    std::vector<Triplet> jt;
    for (Eigen::Index i = 0; i < n; ++i) {
      for (Eigen::Index d = -1; d <= 1; ++d) {
        const Eigen::Index j = (i + d + n) % n;
        jt.emplace_back(i, j, (kappa(x, i, j, kStep) - kappa(x, i, j, -kStep)) / (2 * kStep));
      }
      const Eigen::Index next = (i + 1) % n;
      jt.emplace_back(n + i, next, scale * normal[next].x);
      jt.emplace_back(n + i, i, -scale * normal[i].x);
      jt.emplace_back(2 * n + i, next, scale * normal[next].y);
      jt.emplace_back(2 * n + i, i, -scale * normal[i].y);
    }
    SparseMatrix J(3 * n, n);
    J.setFromTriplets(jt.begin(), jt.end());
    const SparseMatrix H = (J.transpose() * J).pruned();
    if (damping < 0.0) damping = 1e-3 * H.diagonal().mean();
    const Eigen::VectorXd f = J.transpose() * r;
    bool taken = false;
    while (!taken && damping < 1e12) {
      SparseMatrix Hd = H;
      for (Eigen::Index i = 0; i < n; ++i) Hd.coeffRef(i, i) += damping;
      const Eigen::VectorXd x_new = (x + box_qp(Hd, f, lo - x, hi - x, max_iterations)).cwiseMax(lo).cwiseMin(hi);
      const Eigen::VectorXd r_new = residuals(x_new);
      if (r_new.squaredNorm() < r.squaredNorm()) {
        taken = true;
        damping = std::max(damping / 3.0, 1e-12);
        const double moved = (x_new - x).cwiseAbs().maxCoeff();
        x = x_new;
        r = r_new;
        if (moved < 1e-6) return x;
      } else {
        damping *= 10.0;
      }
    }
    if (!taken) break;  // no step lowers the sum: a minimum
  }
  return x;
}

// Distance from p to the nearer boundary and the side (+1 along N, -1 against) it lies on.
double clearance(const Track& track, Vec2 p, Vec2 normal, int* side) {
  const ClosestPoint in = closest_point(track.inner(), true, p);
  const ClosestPoint out = closest_point(track.outer(), true, p);
  const ClosestPoint& near = in.distance_m < out.distance_m ? in : out;
  *side = dot(near.point - p, normal) > 0.0 ? 1 : -1;
  return near.distance_m;
}

}  // namespace

Polyline left_normals(const Polyline& line) {
  const std::size_t n = line.size();
  Polyline normal(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 t = line[(i + 1) % n] - line[(i + n - 1) % n];
    const double len = norm(t);
    if (!(len > 0.0)) throw Error("left_normals: the neighbours of vertex " + std::to_string(i) + " coincide");
    normal[i] = {-t.y / len, t.x / len};
  }
  return normal;
}

void track_half_widths(const Track& track, const Polyline& centre, const Polyline& normal,
                       std::vector<double>* left_m, std::vector<double>* right_m) {
  left_m->resize(centre.size());
  right_m->resize(centre.size());
  for (std::size_t i = 0; i < centre.size(); ++i) {
    const Vec2 minus{-normal[i].x, -normal[i].y};
    (*left_m)[i] = std::min(ray_to_polygon(centre[i], normal[i], track.inner()),
                            ray_to_polygon(centre[i], normal[i], track.outer()));
    (*right_m)[i] = std::min(ray_to_polygon(centre[i], minus, track.inner()),
                             ray_to_polygon(centre[i], minus, track.outer()));
    if (!std::isfinite((*left_m)[i]) || !std::isfinite((*right_m)[i]))
      throw Error("track_half_widths: the normal at station " + std::to_string(i) + " meets no boundary");
  }
}

RacingLine racing_line(const Track& track, const RacingLineOptions& options) {
  if (!(std::isfinite(options.margin_m) && options.margin_m >= 0.0))
    throw Error("racing_line: margin_m must be finite and >= 0");
  if (!(std::isfinite(options.station_spacing_m) && options.station_spacing_m > 0.0))
    throw Error("racing_line: station_spacing_m must be finite and > 0");
  if (options.max_iterations < 1) throw Error("racing_line: max_iterations must be >= 1");
  if (!(std::isfinite(options.length_weight_1pm2) && options.length_weight_1pm2 >= 0.0))
    throw Error("racing_line: length_weight_1pm2 must be finite and >= 0");
  RacingLine r;
  r.centre = resample(track.centreline(), true, options.station_spacing_m);
  if (r.centre.size() < 8) throw Error("racing_line: station_spacing_m leaves fewer than 8 stations");
  r.normal = left_normals(r.centre);
  track_half_widths(track, r.centre, r.normal, &r.left_m, &r.right_m);
  const auto n = static_cast<Eigen::Index>(r.centre.size());
  Eigen::VectorXd lo(n), hi(n);
  const std::vector<double> arc = cumulative_arc_length(r.centre, true);
  for (Eigen::Index i = 0; i < n; ++i) {
    lo[i] = -(r.right_m[i] - options.margin_m);
    hi[i] = r.left_m[i] - options.margin_m;
    if (lo[i] > hi[i])
      throw Error("racing_line: the track is " + std::to_string(r.left_m[i] + r.right_m[i]) + " m wide at station " +
                  std::to_string(i) + " (s = " + std::to_string(arc[i]) + " m), less than twice the margin " +
                  std::to_string(options.margin_m) + " m");
  }
  // Solve; where an oblique boundary comes closer than the margin, tighten that side and again.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (int round = 0; round < 20; ++round) {
    x = min_curvature_offsets(r.centre, r.normal, lo, hi, options.length_weight_1pm2, x, options.max_iterations);
    bool tightened = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      int side = 0;
      const double d = clearance(track, r.centre[i] + x[i] * r.normal[i], r.normal[i], &side);
      const double deficit = options.margin_m - d;
      if (deficit <= 0.0) continue;
      tightened = true;
      if (side > 0) hi[i] = std::max(lo[i], std::min(hi[i], x[i] - deficit - 0.01));
      else lo[i] = std::min(hi[i], std::max(lo[i], x[i] + deficit + 0.01));
    }
    if (!tightened) break;
  }
  r.offset_m.assign(x.data(), x.data() + n);
  r.line.resize(r.centre.size());
  for (Eigen::Index i = 0; i < n; ++i) r.line[i] = r.centre[i] + x[i] * r.normal[i];
  return r;
}

void closed_line_curvature(const Polyline& line, std::vector<double>* curvature_1pm, std::vector<double>* ds_m) {
  const std::size_t n = line.size();
  if (n < 3) throw Error("closed_line_curvature: needs at least 3 vertices");
  curvature_1pm->resize(n);
  ds_m->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a = line[(i + n - 1) % n], b = line[i], c = line[(i + 1) % n];
    if (!(distance(a, b) > 0.0 && distance(b, c) > 0.0 && distance(a, c) > 0.0))
      throw Error("closed_line_curvature: vertex " + std::to_string(i) + " repeats a neighbour");
    (*curvature_1pm)[i] = menger_curvature(a, b, c);
    (*ds_m)[i] = distance(b, c);
  }
}

}  // namespace mppi::sim
