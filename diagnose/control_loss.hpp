#pragma once
// Rows where the car is out of control (spinning, sliding sideways): their errors are the largest
// of a recording and no effect of the library is a model of them, so a least-squares fit that
// includes them bends every candidate towards them.
#include <cstddef>
#include <vector>

#include "diagnose/data.hpp"

namespace mppi::diagnose {

struct ControlLossOptions {
  // |angle between velocity and heading| above this is a spin (0: off). Controlled drifts and
  // powerslides stay below it (AutoRally's peak about 40 deg, drifting cars about 50).
  double max_body_slip_deg = 60.0;
  double min_speed_mps = 1.0;       // below this the slip angle means nothing
  double guard_s = 0.5;             // rows this close to a spin count with it (its onset, its recovery)
  // The diagnosis leaves these rows out of the selection only where less than this share of the
  // training rows are lost control (where more are, the spins are most of the data) and what is
  // left holds at least min_segments_left fit segments: twice the selection's minimum of six
  // (three to fit, three to validate), so that its folds and resamples still have data.
  double max_share_left_out = 0.5;
  int min_segments_left = 12;
};

// 1 for each row within guard_s of a row whose body slip (folded, so that reversing is not a
// slip of 180 deg) exceeds max_body_slip_deg at more than min_speed_mps. Throws mppi::Error for
// options out of range (a slip limit outside [0, 90] deg, a negative or non-finite speed or guard).
std::vector<char> control_loss_rows(const PreparedRecording& d, const ControlLossOptions& o = {});

}  // namespace mppi::diagnose
