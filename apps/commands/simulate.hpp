// `hivecal simulate`: a simulated UR + laser-tracker session written as capture files,
// CSV logs and ground truth, or served live on two pseudo-terminals (docs/streams.md).
#pragma once

namespace hivecal::sim {

/// Entry point of `hivecal simulate` (argv after the command name); returns the exit code.
inline constexpr const char* kSimulateCommand = "simulate";  ///< the subcommand's name
int simulate_main(int argc, char** argv);

}  // namespace hivecal::sim
