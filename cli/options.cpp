#include "cli/options.hpp"

#include <cstdlib>
#include <limits>
#include <sstream>

#include "dynamics/model_registry.hpp"
#include "sim/track.hpp"

namespace mppi::cli {
namespace {

std::string join(const std::vector<std::string>& names, const char* sep = " | ") {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : sep) + n;
  return out;
}

std::vector<std::string> registered_model_names() {
  std::vector<std::string> names;
  for_each_type(RegisteredModels{}, [&]<class D>() { names.emplace_back(D::kName); });
  return names;
}

bool parse_double(const std::string& text, double* v) {
  if (text.empty()) return false;
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return *end == '\0';
}

}  // namespace

CLI::Option* add_model_option(CLI::App& app, const std::string& flag, std::string& model, const std::string& what,
                              std::vector<std::string> allowed, const std::vector<std::string>& extra) {
  if (allowed.empty()) allowed = registered_model_names();
  allowed.insert(allowed.end(), extra.begin(), extra.end());
  return app.add_option(flag, model, what + ": " + join(allowed))
      ->type_name("NAME")
      ->check(CLI::IsMember(allowed).name("MODEL").description(""));
}

CLI::Option* add_track_option(CLI::App& app, std::string& track, const std::string& what) {
  const std::vector<std::string> names = sim::Track::names();
  return app.add_option("--track", track, what + ": " + join(names))
      ->type_name("NAME")
      ->check(CLI::IsMember(names).name("TRACK").description(""));
}

CLI::Option* add_seed_option(CLI::App& app, std::uint64_t& seed, const std::string& what) {
  return app.add_option("--seed", seed, what)->type_name("N");
}

CLI::Option* add_out_option(CLI::App& app, std::string& out, const std::string& what) {
  return app.add_option("--out", out, what)->type_name("DIR");
}

CLI::Option* add_threads_option(CLI::App& app, int& threads) {
  return app.add_option("--threads", threads, "CPU threads, 0 = all")
      ->type_name("N")
      ->check(CLI::Range(0, std::numeric_limits<int>::max()).description(""));
}

CLI::Option* add_backend_option(CLI::App& app, BackendChoice& backend) {
  return app
      .add_option_function<std::string>(
          "--backend", [&backend](const std::string& name) { backend = parse_backend_choice(name); },
          "rollout backend: auto | cpu | vulkan. auto takes a GPU through Vulkan if there is one, else the "
          "CPU; vulkan also takes a CPU Vulkan device (lavapipe); MPPI_VULKAN_DEVICE=<index|name> picks one")
      ->type_name("NAME")
      ->check(CLI::IsMember({"auto", "cpu", "vulkan"}).name("BACKEND").description(""))
      ->default_str(to_string(backend));
}

CLI::Option* add_data_dir_option(CLI::App& app, std::string& data_dir) {
  return app
      .add_option_function<std::string>(
          "--data-dir",
          [&data_dir](const std::string& dir) {
            data_dir = dir;
            if (!dir.empty()) ::setenv("MPPI_DATA_DIR", dir.c_str(), 1);
          },
          "data folder (cost maps, tracks, model data; default: $MPPI_DATA_DIR, else the installed or source data/)")
      ->type_name("DIR")
      ->check(CLI::Validator(
          [](std::string& dir) { return dir.empty() ? std::string() : CLI::ExistingDirectory(dir); }, "", "DIR"))
      ->default_str(data_dir);
}

std::string model_parameter_help(std::string_view model, const std::vector<std::string>& keys) {
  std::string out;
  with_model(model, [&]<class D>() {
    if constexpr (HasParamTable<D>) {
      typename D::Params defaults{};
      std::vector<ParamField> fields = D::params(defaults);
      if (!keys.empty()) {
        std::vector<ParamField> kept;
        std::string untabled;
        for (const std::string& k : keys) {
          bool found = false;
          for (const ParamField& f : fields)
            if (k == f.key) kept.push_back(f), found = true;
          if (!found) untabled += "  " + k + "\n";
        }
        fields = std::move(kept);
        out = untabled;
      }
      out = std::string(D::kName) + " parameters (YAML key = default [unit], valid range: meaning):\n" +
            param_help(fields) + out;
    }
  });
  return out;
}

CLI::Validator number_pair(const std::string& shape) {
  return CLI::Validator(
      [shape](std::string& text) -> std::string {
        const std::size_t colon = text.find(':');
        double a = 0, b = 0;
        if (colon == std::string::npos || !parse_double(text.substr(0, colon), &a) ||
            !parse_double(text.substr(colon + 1), &b))
          return "expects " + shape + " (two numbers), got '" + text + "'";
        return {};
      },
      shape, "");
}

std::pair<double, double> parse_number_pair(const std::string& text) {
  const std::size_t colon = text.find(':');
  double a = 0, b = 0;
  if (colon == std::string::npos || !parse_double(text.substr(0, colon), &a) ||
      !parse_double(text.substr(colon + 1), &b))
    throw CLI::ValidationError("expected two numbers A:B, got '" + text + "'");
  return {a, b};
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace mppi::cli
