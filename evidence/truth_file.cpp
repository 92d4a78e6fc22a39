#include "evidence/truth_file.hpp"

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

namespace mppi::evidence {
namespace {

using json = nlohmann::ordered_json;

json passes_json(const std::vector<std::pair<double, double>>& passes) {
  json out = json::array();
  for (const auto& [enter, leave] : passes) out.push_back({enter, leave});
  return out;
}

// One effect of the truth: its form, its sizes (with where the ground has it), the times the car
// was on it, and the effect-table ids a diagnosis may name for it.
json effect_json(const std::string& name, const EvidenceOptions& o, const Ground& ground, const EvidenceResult& res) {
  const TruthEffectInfo& info = truth_effect_info(name);
  json e;
  e["name"] = info.name;
  e["form"] = info.form;
  json sizes;
  for (const auto& key : info.keys) sizes[key] = truth_effect_value(o.truth, key);
  if (info.name == "hill") {
    sizes["grade_x"] = ground.grade_x;
    sizes["grade_y"] = ground.grade_y;
  }
  if (info.name == "bump") sizes["centre_m"] = {ground.bump.centre_m.x, ground.bump.centre_m.y};
  if (info.name == "grip_patches") {
    json discs = json::array();
    for (const auto& p : ground.patches)
      discs.push_back({{"centre_m", {p.centre_m.x, p.centre_m.y}}, {"radius_m", p.radius_m}, {"edge_m", p.edge_m}});
    sizes["patches"] = discs;
  }
  for (const auto& pp : res.place_passes)  // when the car was on it: [enter, leave] of each pass [s]
    if (pp.effect == info.name) {
      if (info.name == "bump") sizes["passes_s"] = passes_json(pp.disc_passes_s[0]);
      else
        for (std::size_t i = 0; i < pp.disc_passes_s.size(); ++i)
          sizes["patches"][i]["passes_s"] = passes_json(pp.disc_passes_s[i]);
      e["crossed_once"] = pp.crossed_once();
    }
  e["sizes"] = sizes;
  e["table_ids"] = info.table_ids;
  e["in_library"] = !info.table_ids.empty();
  if (info.table_ids.empty())
    e["expected_answer"] = "out of library: a correct diagnosis names nothing reliable or says suspected";
  return e;
}

}  // namespace

// FILE.truth.json: the run, the noise and the effects with their sizes.
void write_truth_json(const EvidenceOptions& o, const Ground& ground, const EvidenceResult& res) {
  json j;
  j["generator"] = "mppi evidence generator (evidence/), independent of the diagnosis' candidates";
  j["recording"] = std::filesystem::path(res.csv).filename().string();
  j["clean_states"] = std::filesystem::path(res.clean_csv).filename().string();
  j["seed"] = o.seed;
  j["track"] = res.track;
  j["direction"] = res.direction;
  j["driver"] = res.driver;
  j["duration_s"] = o.duration_s;
  j["vehicle_params"] = res.vehicle_yaml;  // an effect-free recording has these constants: the nominal
  j["crashes"] = res.crashes;
  j["noise"] = {{"position_m", o.noise.position_m * o.noise.scale}, {"yaw_rad", o.noise.yaw_rad * o.noise.scale},
                {"vx_mps", o.noise.vx_mps * o.noise.scale}, {"vy_mps", o.noise.vy_mps * o.noise.scale},
                {"yaw_rate_radps", o.noise.yaw_rate_radps * o.noise.scale}, {"glitch_rate", o.noise.glitch_rate},
                {"drop_rate", o.noise.drop_rate}};
  json effects = json::array();
  for (const auto& name : o.truth_names) effects.push_back(effect_json(name, o, ground, res));
  j["effects"] = effects;
  std::ofstream(res.truth_json) << j.dump(2) << "\n";
}

}  // namespace mppi::evidence
