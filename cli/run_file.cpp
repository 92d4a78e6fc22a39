#include "cli/run_file.hpp"

#include <yaml-cpp/yaml.h>

#include <vector>

namespace mppi::cli {
namespace {

// The options a run file may set: configurable, with a long name.
bool is_key(const CLI::Option* opt) { return opt->get_configurable() && !opt->get_lnames().empty(); }

bool is_flag(const CLI::Option* opt) { return opt->get_expected_min() == 0; }

std::string valid_keys(const CLI::App& app) {
  std::string out;
  for (const CLI::Option* opt : app.get_options())
    if (is_key(opt)) out += (out.empty() ? "" : ", ") + opt->get_lnames().front();
  return out;
}

std::string yaml_scalar(const std::string& text) {
  YAML::Emitter e;
  e << text;
  return e.c_str();
}

}  // namespace

void RunFile::add_options(CLI::App& app) {
  app.add_option("--config", path_,
                 "run file (YAML): every long flag is a key (speed: 8, clockwise: true); flags on the command "
                 "line win over the file")
      ->type_name("FILE")
      ->check(CLI::ExistingFile.description(""))
      ->configurable(false);
  app.add_flag("--dump-config", dump_, "print the effective configuration as a run file (YAML) and exit")
      ->configurable(false);
}

void RunFile::apply(CLI::App& app) const {
  if (!path_.empty()) apply_run_file(app, path_);
}

void apply_run_file(CLI::App& app, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw CLI::ConfigError(path + ": not a readable YAML file: " + e.what());
  }
  if (root.IsNull()) return;  // an empty file sets nothing
  if (!root.IsMap()) throw CLI::ConfigError(path + ": expected a map of keys (the long flags without --)");
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    const YAML::Node& node = entry.second;
    CLI::Option* opt = app.get_option_no_throw("--" + key);
    if (opt == nullptr || !is_key(opt) || opt->get_lnames().front() != key)
      throw CLI::ConfigError(path + ": unknown key '" + key + "' (valid keys: " + valid_keys(app) + ")");
    if (opt->count() > 0) continue;  // given on the command line: the command line wins
    std::vector<std::string> values;
    if (node.IsScalar()) {
      values.push_back(node.Scalar());
    } else if (node.IsSequence()) {
      for (const auto& item : node) {
        if (!item.IsScalar()) throw CLI::ConfigError(path + ": key '" + key + "': expected a list of values");
        values.push_back(item.Scalar());
      }
    } else {
      throw CLI::ConfigError(path + ": key '" + key + "' has no value");
    }
    try {
      if (is_flag(opt)) {
        if (values.size() != 1) throw CLI::ConversionError(key, values);
        const std::string& v = values.front();
        if (v != "true" && v != "false")
          throw CLI::ConfigError(path + ": key '" + key + "' is a flag: expected true or false, got '" + v + "'");
        if (v == "false") continue;  // a flag's default is off
        opt->add_result(opt->get_flag_value(key, v));
      } else {
        opt->add_result(values);
      }
      opt->run_callback();
    } catch (const CLI::ConfigError&) {
      throw;
    } catch (const CLI::Error& e) {
      throw CLI::ConfigError(path + ": key '" + key + "': " + e.what());
    }
  }
}

std::string dump_run_file(const CLI::App& app) {
  std::string out = "# " + app.get_name() + " run file (" + app.get_name() + " --config FILE); keys are the long flags\n";
  for (const CLI::Option* opt : app.get_options()) {
    if (!is_key(opt)) continue;
    const std::string& key = opt->get_lnames().front();
    if (!opt->get_description().empty()) out += "# " + opt->get_description() + "\n";
    if (is_flag(opt)) {
      out += key + ": " + (opt->count() > 0 && opt->as<bool>() ? "true" : "false") + "\n";
      continue;
    }
    std::vector<std::string> values = opt->count() > 0 ? opt->results() : std::vector<std::string>{opt->get_default_str()};
    if (opt->get_expected_max() > 1 || values.size() > 1) {
      out += key + ":";
      if (values.empty()) out += " []";
      out += "\n";
      for (const auto& v : values) out += "  - " + yaml_scalar(v) + "\n";
    } else {
      out += key + ": " + yaml_scalar(values.front()) + "\n";
    }
  }
  return out;
}

}  // namespace mppi::cli
