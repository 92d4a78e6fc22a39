// mppi-fit convert: a shipped real recording (DART JetRacer, ETH RC car) -> the project's
// recording format (docs/RECORDING_FORMAT.md). Conventions: sysid/real_data.hpp.
#include <cstdio>
#include <cstring>
#include <string>

#include "mppi/error.hpp"
#include "mppi_fit_commands.hpp"
#include "sim/data_dir.hpp"
#include "sysid/real_data.hpp"

namespace {

const char* kConvertUsage = R"(usage: mppi-fit convert INPUT [options]
  INPUT                a raw CSV, or ARCHIVE.zip:MEMBER.csv (e.g. the shipped
                       data/real/dart_jetracer.zip:car_1_Datarecording_09_16_2024_10_27_02.csv);
                       a name starting with "real/" is looked up in the data folder
  --out FILE           output recording (default: stdout summary only, nothing written)
  --source NAME        auto | dart | eth                       (auto: from the header)
  --smoothing N        DART: samples each side of the Vicon pose fit (10 = +-0.1 s)
  --list ARCHIVE       list the members of a zip archive and exit
)";

}  // namespace

int mppi_fit_convert(int argc, char** argv) {
  std::string input, out;
  mppi::sysid::RealConvertSettings s;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw mppi::Error(a + " expects a value");
        return argv[++i];
      };
      if (a == "--help" || a == "-h") {
        std::fputs(kConvertUsage, stdout);
        return 0;
      } else if (a == "--out") {
        out = value();
      } else if (a == "--source") {
        const std::string v = value();
        if (v == "auto") s.source = mppi::sysid::RealSource::kAuto;
        else if (v == "dart") s.source = mppi::sysid::RealSource::kDartJetracer;
        else if (v == "eth") s.source = mppi::sysid::RealSource::kEthRccar;
        else throw mppi::Error("--source expects auto, dart or eth, got '" + v + "'");
      } else if (a == "--smoothing") {
        s.smoothing_half_window = std::stoi(value());
      } else if (a == "--list") {
        for (const auto& m : mppi::sysid::zip_members(value())) std::printf("%s\n", m.c_str());
        return 0;
      } else if (!a.empty() && a[0] == '-') {
        throw mppi::Error("unknown option " + a);
      } else if (input.empty()) {
        input = a;
      } else {
        throw mppi::Error("more than one input given");
      }
    }
    if (input.empty()) throw mppi::Error("no input given");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-fit convert: %s\n%s", e.what(), kConvertUsage);
    return 2;
  }
  try {
    if (input.rfind("real/", 0) == 0) {
      const std::size_t z = input.find(".zip:");
      input = z == std::string::npos ? mppi::sim::data_file(input)
                                     : mppi::sim::data_file(input.substr(0, z + 4)) + input.substr(z + 4);
    }
    const mppi::sim::Recording rec = mppi::sysid::convert_real_file(input, s);
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
