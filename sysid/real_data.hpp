#pragma once
// Converters from the shipped real recordings (data/real/*.zip, copied from ../shared/data/real
// with their READMEs) into the project's recording format (docs/RECORDING_FORMAT.md,
// sim/recording.hpp). Conventions handled (see docs/ESTIMATION.md "Real data"):
//
// DART JetRacer (data/real/dart_jetracer.zip), 14-column Vicon files:
//   t        = vicon time - first vicon time [s] (rows with a non-increasing stamp are dropped)
//   x, y     = Vicon reference point moved 0.022 m back along the heading to the CoM
//              (reference 0.115 m ahead of the rear axle, CoM 0.093 m ahead of it)
//   yaw      = unwrapped Vicon yaw
//   vx, vy, yaw_rate = derivative of a local quadratic least-squares fit of the Vicon pose over
//              +-`smoothing_half_window` samples, world velocity rotated by -yaw into the body frame
//   steer    = `steering` command (positive left: checked, corr. 0.96 with the yaw rate)
//   throttle = `throttle` command, 0 where `safety_value` is 0 (as the authors do)
//   extras   = ax, ay (IMU), wheel_speed (encoder), imu_yaw_rate, safety  (missing before the
//              first sensor packet; 10 Hz values zero-order-held on the 100 Hz grid, as shipped)
//   10-column files (Jan 2024, no Vicon): t from the sensor clock, x, y, yaw, vy missing,
//   vx = encoder speed, yaw_rate = IMU yaw rate.
// ETH LAS-group RC car (data/real/eth_lasgroup_rccar.zip):
//   t = t_nominal_s (uniform 1/30 s: the source stored no timestamps), x, y = x_m, y_m,
//   yaw = unwrapped theta_rad, (vx, vy) = world velocity rotated by -yaw, yaw_rate = omega_radps
//   with |omega| > 20 rad/s glitches set missing, steer/throttle = steer_cmd/throttle_cmd.
#include <functional>
#include <string>
#include <vector>

#include "sim/recording.hpp"

namespace mppi::sysid {

enum class RealSource { kAuto, kDartJetracer, kEthRccar };

struct RealConvertSettings {
  RealSource source = RealSource::kAuto;  // kAuto: recognised from the header row
  int smoothing_half_window = 10;         // DART: samples each side of the pose fit (100 Hz)
  double cog_offset_m = 0.022;            // DART: Vicon point ahead of the CoM along the heading
  double eth_omega_outlier_radps = 20.0;  // ETH: |yaw rate| above this is set missing

  bool is_valid(std::string* why) const;
};

// Reads a text file, or one member of a zip archive written "archive.zip:member.csv".
// Throws mppi::Error naming the file (and member) when it cannot be read.
std::string read_text_or_zip_member(const std::string& spec);
// The member names of a zip archive (throws mppi::Error if it cannot be opened).
std::vector<std::string> zip_members(const std::string& zip_path);

// Converts one raw recording (`text` = the whole CSV, `source_name` names it in messages and
// the metadata). Throws mppi::Error "<source>:<line>: column <c> (<name>): <problem>" for a
// malformed raw file, or when the header is neither source's layout.
sim::Recording convert_real_recording(const std::string& text, const std::string& source_name,
                                      const RealConvertSettings& settings = {});
// Same from a path or "archive.zip:member".
sim::Recording convert_real_file(const std::string& spec, const RealConvertSettings& settings = {});

// A recording in the project format, or a raw shipped recording converted on the fly
// (recognised by its header); `spec` as for convert_real_file. Errors name file, line, column.
// A file whose name ends in an extension given to register_recording_reader is read by that
// reader; a ".bag" with no reader registered is refused, saying the build has no rosbag support.
sim::Recording load_any_recording(const std::string& spec);

// Readers for recordings in containers this library does not parse itself (a rosbag, read by
// sysid/rosbag/ where the build has librosbag), chosen by the file name's ending (e.g. ".bag").
// A program registers them at start-up; a later registration for the same ending replaces it.
using RecordingFileReader = std::function<sim::Recording(const std::string& path)>;
void register_recording_reader(const std::string& extension, RecordingFileReader reader);

// Writes a Recording (any columns; required ones first as in the reader) to `path` in the
// project format, metadata lines included. Throws mppi::Error if it cannot be written.
void write_recording(const sim::Recording& rec, const std::string& path);

// Rows [begin, end) of a recording (same columns and metadata), e.g. a fit / held-out split.
sim::Recording slice_recording(const sim::Recording& rec, std::size_t begin, std::size_t end);
// The first row with t >= t_s (rows() if none).
std::size_t row_at_time(const sim::Recording& rec, double t_s);

}  // namespace mppi::sysid
