// Inputs of `hivecal calibrate`: settings from the command line and the dataset from
// paired samples, serial captures or CSV logs (the latter two through the stream path).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "json.hpp"

namespace hivecal::cli {

/// Dataset capacity of the command-line tool (samples).
inline constexpr std::size_t kCliDatasetCapacity = 8192;
using CliDataset = Dataset<kCliDatasetCapacity>;

/// Validated command-line settings.
struct CalibrateSettings {
  RobotType robot = RobotType::ur5;  ///< --robot-model
  Vec3 tool_m = Vec3(0.0, 0.0, 0.1695);  ///< --tool: nominal tool point in the flange frame [m]
  bool paper_params = false;         ///< --params paper
  std::string method = "abc+lm";     ///< --method
  std::uint64_t seed = 1;            ///< --seed
  double train_fraction = 0.7;       ///< --split
};

/// What the input stage found, for the terminal, the report and the JSON.
struct InputFacts {
  std::vector<std::string> info_lines;  ///< human-readable facts (inputs, clock, samples kept/dropped)
  bool has_stream = false;              ///< the dataset came from two streams
  double clock_offset_us = 0.0;         ///< t_robot - t_tracker at the reference instant [us]
  double clock_offset_sigma_us = 0.0;   ///< its 1-sigma [us]
  double clock_drift = 0.0;             ///< relative rate difference [-]
  double clock_drift_sigma = 0.0;       ///< its 1-sigma [-]
  std::uint64_t tracker_points = 0;     ///< tracker records seen
  std::uint64_t kept = 0;               ///< static samples kept
  std::vector<std::pair<std::string, std::uint64_t>> dropped;  ///< drop reason -> count
};

/// Checks the options; returns "" or what is wrong.
std::string settings_from_options(const Options& options, CalibrateSettings* settings);
/// Fills the dataset from --samples or --robot/--tracker; returns kExitOk or an exit code
/// after printing the problem.
int load_dataset(const Options& options, const CalibrateSettings& settings, bool progress, DatasetBase* dataset,
                 InputFacts* facts);
/// Adds "inputs" facts (clock, extraction counts) to the result JSON.
void write_input_facts(textio::JsonWriter& json, const InputFacts& facts);

}  // namespace hivecal::cli
