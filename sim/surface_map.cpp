#include "sim/surface_map.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include "base/error.hpp"

namespace mppi::sim {
namespace {

double smoothstep01(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

struct Reader {
  std::string file;
  [[noreturn]] void fail(const std::string& key, const std::string& why) const {
    throw Error(file + ": " + key + ": " + why);
  }
  double number(const YAML::Node& n, const std::string& key) const {
    try {
      const double v = n.as<double>();
      if (!std::isfinite(v)) fail(key, "must be finite");
      return v;
    } catch (const YAML::Exception&) {
      fail(key, "expected a number");
    }
  }
  Vec2 pair(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != 2) fail(key, "expected [x, y]");
    return {number(n[0], key + "[0]"), number(n[1], key + "[1]")};
  }
};

SurfacePatch read_patch(const Reader& r, const YAML::Node& n, const std::string& key, bool is_grip) {
  SurfacePatch p;
  if (!n.IsMap()) r.fail(key, "a patch is a map with centre_m/radius_m or arc_m, and value");
  for (const auto& kv : n) {
    const std::string k = kv.first.as<std::string>();
    if (k != "centre_m" && k != "radius_m" && k != "arc_m" && k != "half_width_m" && k != "value" && k != "edge_m")
      r.fail(key + "." + k, "unknown key (valid: centre_m, radius_m, arc_m, half_width_m, value, edge_m)");
  }
  if (!n["value"]) r.fail(key, "value is required");
  p.value = r.number(n["value"], key + ".value");
  if (is_grip && !(p.value > 0)) r.fail(key + ".value", "grip scale must be > 0");
  if (n["edge_m"]) p.edge_m = r.number(n["edge_m"], key + ".edge_m");
  if (p.edge_m < 0) r.fail(key + ".edge_m", "must be >= 0");
  if (n["centre_m"]) {
    if (n["arc_m"]) r.fail(key, "give either centre_m/radius_m or arc_m, not both");
    p.shape = SurfacePatch::Shape::kDisc;
    p.centre_m = r.pair(n["centre_m"], key + ".centre_m");
    if (!n["radius_m"]) r.fail(key, "a disc patch needs radius_m");
    p.radius_m = r.number(n["radius_m"], key + ".radius_m");
    if (!(p.radius_m > 0)) r.fail(key + ".radius_m", "must be > 0");
  } else if (n["arc_m"]) {
    p.shape = SurfacePatch::Shape::kArc;
    const Vec2 a = r.pair(n["arc_m"], key + ".arc_m");
    p.arc0_m = a.x;
    p.arc1_m = a.y;
    if (n["half_width_m"]) p.half_width_m = r.number(n["half_width_m"], key + ".half_width_m");
    if (!(p.half_width_m > 0)) r.fail(key + ".half_width_m", "must be > 0");
  } else {
    r.fail(key, "needs centre_m and radius_m, or arc_m");
  }
  return p;
}

SurfaceImage read_image(const Reader& r, const YAML::Node& n, const std::string& key) {
  SurfaceImage img;
  const std::filesystem::path base = std::filesystem::path(r.file).parent_path();
  const std::string file = (base / n["image"].as<std::string>()).string();
  if (!n["origin_m"] || !n["resolution_m"]) r.fail(key, "an image layer needs origin_m and resolution_m");
  img.origin_m = r.pair(n["origin_m"], key + ".origin_m");
  img.resolution_m = r.number(n["resolution_m"], key + ".resolution_m");
  if (!(img.resolution_m > 0)) r.fail(key + ".resolution_m", "must be > 0");
  const double black = n["black"] ? r.number(n["black"], key + ".black") : 0.0;
  const double white = n["white"] ? r.number(n["white"], key + ".white") : 1.0;
  const cv::Mat m = cv::imread(file, cv::IMREAD_GRAYSCALE);
  if (m.empty()) r.fail(key + ".image", "cannot read image '" + file + "'");
  img.cols = m.cols;
  img.rows = m.rows;
  img.values.resize(static_cast<std::size_t>(m.cols) * m.rows);
  for (int row = 0; row < m.rows; ++row)
    for (int col = 0; col < m.cols; ++col)  // row 0 of the image = the top = the largest y
      img.values[static_cast<std::size_t>(m.rows - 1 - row) * m.cols + col] =
          static_cast<float>(black + (white - black) * m.at<std::uint8_t>(row, col) / 255.0);
  return img;
}

SurfaceLayer read_layer(const Reader& r, const YAML::Node& n, const std::string& key, bool is_grip) {
  SurfaceLayer layer;
  layer.default_value = is_grip ? 1.0 : 0.0;
  if (!n) return layer;
  if (!n.IsMap()) r.fail(key, "expected a map");
  for (const auto& kv : n) {
    const std::string k = kv.first.as<std::string>();
    if (k != "default" && k != "patches" && k != "grade" && k != "image" && k != "origin_m" &&
        k != "resolution_m" && k != "black" && k != "white")
      r.fail(key + "." + k, "unknown key");
  }
  if (n["default"]) layer.default_value = r.number(n["default"], key + ".default");
  if (is_grip && !(layer.default_value > 0)) r.fail(key + ".default", "grip scale must be > 0");
  if (n["grade"]) {
    if (is_grip) r.fail(key + ".grade", "only the elevation layer has a grade");
    const Vec2 g = r.pair(n["grade"], key + ".grade");
    layer.grade_x = g.x;
    layer.grade_y = g.y;
  }
  if (n["patches"]) {
    if (!n["patches"].IsSequence()) r.fail(key + ".patches", "expected a list");
    for (std::size_t i = 0; i < n["patches"].size(); ++i)
      layer.patches.push_back(read_patch(r, n["patches"][i], key + ".patches[" + std::to_string(i) + "]", is_grip));
  }
  if (n["image"]) layer.image = read_image(r, n, key);
  if (is_grip && layer.image)
    for (float v : layer.image->values)
      if (!(v > 0)) r.fail(key + ".image", "grip scale must be > 0 everywhere (check black/white)");
  return layer;
}

}  // namespace

double SurfaceImage::bilinear(double x, double y, double outside) const {
  // Cell centres at origin + (i + 0.5) res.
  const double fx = (x - origin_m.x) / resolution_m - 0.5, fy = (y - origin_m.y) / resolution_m - 0.5;
  if (!(fx >= -0.5 && fy >= -0.5 && fx <= cols - 0.5 && fy <= rows - 0.5)) return outside;
  const double cx = std::clamp(fx, 0.0, cols - 1.0), cy = std::clamp(fy, 0.0, rows - 1.0);
  const int i0 = std::min(static_cast<int>(cx), cols - 1), j0 = std::min(static_cast<int>(cy), rows - 1);
  const int i1 = std::min(i0 + 1, cols - 1), j1 = std::min(j0 + 1, rows - 1);
  const double ax = cx - i0, ay = cy - j0;
  auto at = [&](int i, int j) { return static_cast<double>(values[static_cast<std::size_t>(j) * cols + i]); };
  return (1 - ay) * ((1 - ax) * at(i0, j0) + ax * at(i1, j0)) + ay * ((1 - ax) * at(i0, j1) + ax * at(i1, j1));
}

SurfaceMap::SurfaceMap() {
  grip_.default_value = 1.0;
}

SurfaceMap::SurfaceMap(SurfaceLayer grip, SurfaceLayer elevation, Polyline centreline,
                       std::vector<double> centreline_arc_m)
    : grip_(std::move(grip)), elevation_(std::move(elevation)), centreline_(std::move(centreline)),
      arc_m_(std::move(centreline_arc_m)) {
  for (const auto* layer : {&grip_, &elevation_})
    for (const auto& p : layer->patches)
      if (p.shape == SurfacePatch::Shape::kArc && (centreline_.size() < 3 || arc_m_.size() != centreline_.size() + 1))
        throw Error("surface map: arc-length patches need the track's centreline (give `track:`)");
}

SurfaceMap SurfaceMap::load(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw Error(path + ": cannot read surface map: " + e.what());
  }
  const Reader r{path};
  if (!root.IsMap()) r.fail("(top)", "expected a map with grip and/or elevation");
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>();
    if (k != "track" && k != "grip" && k != "elevation" && k != "description")
      r.fail(k, "unknown key (valid: track, grip, elevation, description)");
  }
  SurfaceLayer grip = read_layer(r, root["grip"], "grip", true);
  SurfaceLayer elevation = read_layer(r, root["elevation"], "elevation", false);
  Polyline centre;
  std::vector<double> arc;
  if (root["track"]) {
    const Track track = Track::load(root["track"].as<std::string>());  // counter-clockwise
    centre = track.centreline();
    arc = track.centreline_arc_m();
  }
  try {
    return SurfaceMap(std::move(grip), std::move(elevation), std::move(centre), std::move(arc));
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }
}

double SurfaceMap::arc_and_offset(Vec2 p, double* lateral_m) const {
  const ClosestPoint c = closest_point(centreline_, true, p);
  *lateral_m = c.distance_m;
  return arc_m_[c.segment] + c.t * (arc_m_[c.segment + 1] - arc_m_[c.segment]);
}

double SurfaceMap::patch_weight(const SurfacePatch& patch, Vec2 p, bool is_grip) const {
  double outside_m = 0;  // distance outside the patch (<= 0 inside)
  if (patch.shape == SurfacePatch::Shape::kDisc) {
    const double r = std::hypot(p.x - patch.centre_m.x, p.y - patch.centre_m.y);
    if (!is_grip)  // a hill: raised cosine, full height at the centre, 0 at the radius
      return r < patch.radius_m ? 0.5 * (1 + std::cos(std::numbers::pi * r / patch.radius_m)) : 0.0;
    outside_m = r - patch.radius_m;
  } else {
    double lateral = 0;
    const double s = arc_and_offset(p, &lateral);
    const double length = arc_m_.back();
    double a0 = std::fmod(patch.arc0_m, length), a1 = std::fmod(patch.arc1_m, length);
    if (a0 < 0) a0 += length;
    if (a1 < 0) a1 += length;
    const double span = a1 >= a0 ? a1 - a0 : a1 + length - a0;
    double from_start = s - a0;  // position past the patch's start, in [0, length)
    if (from_start < 0) from_start += length;
    double along_out = 0;
    if (from_start > span) along_out = std::min(from_start - span, length - from_start);
    outside_m = std::max(along_out, lateral - patch.half_width_m);
  }
  if (outside_m <= 0) return 1.0;
  if (patch.edge_m <= 0) return 0.0;
  return smoothstep01(1 - outside_m / patch.edge_m);
}

double SurfaceMap::grip(double x_m, double y_m) const {
  const Vec2 p{x_m, y_m};
  double g = grip_.image ? grip_.image->bilinear(x_m, y_m, grip_.default_value) : grip_.default_value;
  for (const auto& patch : grip_.patches) {
    const double w = patch_weight(patch, p, true);
    g = (1 - w) * g + w * patch.value;
  }
  return std::max(g, 1e-3);
}

double SurfaceMap::elevation_m(double x_m, double y_m) const {
  const Vec2 p{x_m, y_m};
  double z = elevation_.image ? elevation_.image->bilinear(x_m, y_m, elevation_.default_value)
                              : elevation_.default_value;
  z += elevation_.grade_x * x_m + elevation_.grade_y * y_m;
  for (const auto& patch : elevation_.patches) z += patch.value * patch_weight(patch, p, false);
  return z;
}

Vec2 SurfaceMap::slope(double x_m, double y_m) const {
  if (flat()) return {0, 0};
  if (elevation_.patches.empty() && !elevation_.image) return {elevation_.grade_x, elevation_.grade_y};
  const double h = 0.025;
  return {(elevation_m(x_m + h, y_m) - elevation_m(x_m - h, y_m)) / (2 * h),
          (elevation_m(x_m, y_m + h) - elevation_m(x_m, y_m - h)) / (2 * h)};
}

Vec2 SurfaceMap::gravity_body_mps2(double x_m, double y_m, double yaw_rad, double g_mps2) const {
  const Vec2 s = slope(x_m, y_m);
  if (s.x == 0 && s.y == 0) return {0, 0};
  // Along a body axis e (heading, or left), the ground rises by d = slope . e per metre; gravity's
  // component along the axis tilted onto the ground is -g d / sqrt(1 + d^2) = -g sin(theta).
  const double c = std::cos(yaw_rad), sn = std::sin(yaw_rad);
  const double dx = s.x * c + s.y * sn, dy = -s.x * sn + s.y * c;
  return {-g_mps2 * dx / std::sqrt(1 + dx * dx), -g_mps2 * dy / std::sqrt(1 + dy * dy)};
}

bool SurfaceMap::flat() const {
  return elevation_.grade_x == 0 && elevation_.grade_y == 0 && elevation_.patches.empty() && !elevation_.image;
}

}  // namespace mppi::sim
