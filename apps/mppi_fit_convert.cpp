// mppi-fit convert: a shipped real recording (DART JetRacer, ETH RC car) or a rosbag -> the project's
// recording format (docs/RECORDING_FORMAT.md). Conventions: sysid/real_data.hpp.
#include <cstdio>
#include <memory>
#include <string>

#include "base/error.hpp"
#include "cli/app.hpp"
#include "cli/options.hpp"
#include "mppi_fit_bag.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/data_dir.hpp"
#include "sysid/real_data.hpp"

namespace {

struct ConvertArgs {
  std::string input, out, source = "auto", list_archive;
  mppi::sysid::RealConvertSettings settings;
};

int run_convert(ConvertArgs& args) {
  mppi::sysid::RealConvertSettings s = args.settings;
  if (args.source == "dart") s.source = mppi::sysid::RealSource::kDartJetracer;
  else if (args.source == "eth") s.source = mppi::sysid::RealSource::kEthRccar;
  else s.source = mppi::sysid::RealSource::kAuto;
  std::string input = args.input;
  const std::string& out = args.out;
  try {
    if (!args.list_archive.empty()) {
      for (const auto& m : mppi::sysid::zip_members(args.list_archive)) std::printf("%s\n", m.c_str());
      return 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit convert: %s\n", e.what());
    return 2;
  }
  if (input.empty()) throw mppi::cli::usage_error("INPUT", "no input given");
  try {
    if (input.rfind("real/", 0) == 0) {
      const std::size_t z = input.find(".zip:");
      input = z == std::string::npos ? mppi::sim::data_file(input)
                                     : mppi::sim::data_file(input.substr(0, z + 4)) + input.substr(z + 4);
    }
    const bool bag = input.size() > 4 && input.compare(input.size() - 4, 4, ".bag") == 0;
    const mppi::sim::Recording rec =
        bag ? mppi::sysid::load_any_recording(input) : mppi::sysid::convert_real_file(input, s);
    const auto& t = rec.column("t");
    std::printf("%s: %zu rows, %.2f s, vehicle %s\n", input.c_str(), rec.rows(),
                rec.rows() ? t.back() - t.front() : 0.0, rec.metadata.at("vehicle").c_str());
    if (!out.empty()) {
      mppi::sysid::write_recording(rec, out);
      std::printf("wrote %s\n", out.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit convert: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

void add_convert_command(CLI::App& fit, FitCommands& commands) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* cmd =
      fit.add_subcommand("convert", "convert a shipped real-data recording into the project's recording format");
  cmd->add_option("input", args->input,
                  "a raw CSV, or ARCHIVE.zip:MEMBER.csv (e.g. the shipped "
                  "data/real/dart_jetracer.zip:car_1_Datarecording_09_16_2024_10_27_02.csv), or a rosbag FILE.bag "
                  "(docs/ROSBAG.md); a name starting with \"real/\" is looked up in the data folder")
      ->type_name("INPUT");
  cmd->add_option("--out", args->out, "output recording (default: stdout summary only, nothing written)")
      ->type_name("FILE");
  cmd->add_option("--source", args->source, "auto | dart | eth (auto: from the header)")
      ->type_name("NAME")
      ->check(CLI::IsMember({"auto", "dart", "eth"}).description(""));
  cmd->add_option("--smoothing", args->settings.smoothing_half_window,
                  "DART: samples each side of the Vicon pose fit (10 = +-0.1 s)")
      ->type_name("N");
  add_bag_options(cmd);
  cmd->add_option("--list", args->list_archive, "list the members of a zip archive and exit")->type_name("ARCHIVE");
  commands.add(cmd, [args] { return run_convert(*args); });
}
