#include "mppi_fit_bag.hpp"

#include "sysid/real_data.hpp"
#ifdef MPPI_HAVE_ROSBAG
#include "sysid/rosbag/bag_recording.hpp"
#endif

FitBagOptions& fit_bag_options() {
  static FitBagOptions options;
  return options;
}

void add_bag_options(CLI::App* cmd) {
  FitBagOptions& o = fit_bag_options();
  cmd->add_option("--topic-map", o.topic_map_file,
                  "rosbag input: which topics hold the drive (YAML of KEY: VALUE; docs/ROSBAG.md); default "
                  "AutoRally's /pose_estimate, /chassisState, /chassisCommand, /wheelSpeeds")
      ->type_name("FILE.yaml");
  cmd->add_option("--topic", o.topics, "rosbag input: KEY=VALUE[,KEY=VALUE...] over the topic map, e.g. "
                                       "pose=/odom,command=/cmd (docs/ROSBAG.md)")
      ->type_name("KEY=VALUE");
}

void register_bag_reader() {
#ifdef MPPI_HAVE_ROSBAG
  mppi::sysid::register_recording_reader(".bag", [](const std::string& path) {
    mppi::sysid::bag::BagTopicMap map;
    const FitBagOptions& o = fit_bag_options();
    if (!o.topic_map_file.empty()) map.apply_yaml_file(o.topic_map_file);
    for (const auto& t : o.topics) map.apply_pairs(t);
    return mppi::sysid::bag::read_bag_recording(path, map);
  });
#endif
}
