#pragma once
// The recording a diagnosis works on is the one calibration and estimation work on:
// sysid::PreparedRecording (sysid/prepared_recording.hpp), screened, cut into continuous pieces
// and split into segments there. Its names, in the diagnosis's namespace.
#include "sysid/prepared_recording.hpp"

namespace mppi::diagnose {

using sysid::concat;
using sysid::kChannelNames;
using sysid::kChannels;
using sysid::kChannelUnits;
using sysid::load_any;
using sysid::load_recording;
using sysid::make_segments;
using sysid::make_split;
using sysid::prepare;
using sysid::PreparedRecording;
using sysid::ScreenColumn;
using sysid::ScreenFlag;
using sysid::ScreenOptions;
using sysid::screen_columns;
using sysid::screened_rows;
using sysid::Segment;
using sysid::slice_rows;
using sysid::Split;

}  // namespace mppi::diagnose
