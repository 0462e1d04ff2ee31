// How the commands that read measured samples (calibrate, validate) read them: the reader
// options they share (units and --columns, the measured orientation, the stated noise, the
// joints' reading noise), parsed in one place, and the session configuration they give.
#pragma once

#include <string>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/model/kinematics.hpp"
#include "streams/session.hpp"
#include "textio/csv.hpp"
#include "textio/delimited.hpp"

namespace hivecal::cli {

/// The reader options' values.
struct SampleReaderSettings {
  textio::InputUnits units;  ///< --length-unit, --angle-unit, --columns of text inputs
  textio::OrientationInput
      orientation;               ///< --position-sigma-m (--tracker-sigma-um), --angle-sigma-rad, --orientation-*
  double joint_sigma_rad = 0.0;  ///< --joint-sigma-rad / --joint-sigma-deg: joint reading noise (0: off) [rad]
};

/// The reader options, in their --help order (the unit options and --columns last).
std::vector<OptionSpec> sample_reader_option_specs();

/// The reader options into *settings; a usage error names the option and what it must be.
Error sample_reader_settings_from_options(const Options& options, SampleReaderSettings* settings);

/// The session configuration of paired samples read with `settings`: `arm` (with its tool
/// point) weighs the joints' reading noise in a measured orientation's lever.
streams::SessionConfig sample_session_config(const SampleReaderSettings& settings, const RobotModel& arm);

}  // namespace hivecal::cli
