// Job options with small populations, so that the tests of the calibration job stay quick.
#pragma once

#include "hivecal/calibration.hpp"

namespace hivecal::test {

/// `method` with ABC 20 x 20 and GSA 20 x 20; everything else the command line's defaults.
inline CalibrationOptions quick_options(CalibrationMethod method) {
  CalibrationOptions options;
  options.method = method;
  options.abc_food_sources = 20;
  options.abc_cycles = 20;
  options.gsa_agents = 20;
  options.gsa_iterations = 20;
  return options;
}

}  // namespace hivecal::test
