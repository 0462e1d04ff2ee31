// The hivecal subcommands; each takes argv after its own name and returns an exit code.
#pragma once

namespace hivecal::cli {

int predict_main(int argc, char** argv);  ///< positions of poses from a calibration result

}  // namespace hivecal::cli
