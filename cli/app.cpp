#include "cli/app.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>

namespace mppi::cli {

void configure(CLI::App& app) {
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast)->always_capture_default();
  app.get_formatter()->column_width(34);
}

void parse_args(CLI::App& app, std::vector<std::string> args, const std::function<void()>& after_parse) {
  std::reverse(args.begin(), args.end());  // CLI11 takes a vector last argument first
  app.parse(args);
  if (after_parse) after_parse();
}

int parse(CLI::App& app, int argc, char** argv, const std::function<void()>& after_parse) {
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  try {
    parse_args(app, std::move(args), after_parse);
    return -1;
  } catch (const CLI::CallForHelp&) {
    // The help of the (sub)command that was asked: CLI11 finds it from the parsed state.
    return app.exit(CLI::CallForHelp());
  } catch (const CLI::CallForAllHelp&) {
    return app.exit(CLI::CallForAllHelp());
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s\nRun with --help for more information.\n", app.get_name().c_str(), e.what());
    return kUsageExit;
  }
}

CLI::ValidationError usage_error(const std::string& flag, const std::string& what) {
  return CLI::ValidationError(flag, what);
}

}  // namespace mppi::cli
