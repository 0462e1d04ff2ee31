// The input layer of a calibration session: load_session() turns what the user gave
// (paired samples, or a robot and a tracker stream, each a capture or a text log) into a
// dataset and the facts about it. `calibrate` and `extract` both load through it, and
// `record`'s captures are read back by it. Presentation (terminal lines, JSON) is the
// caller's.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/port/error.hpp"
#include "streams/stream_pipeline.hpp"
#include "textio/csv.hpp"

namespace hivecal::streams {

/// Where the data of a session is.
struct SessionSources {
  std::string samples;  ///< paired samples CSV q1..qN,x,y,z ('-': stdin), or "" for streams
  std::string robot;    ///< robot stream: capture, or a log of any tool (textio/logs.hpp), or a ROS 2 bag
  std::string tracker;  ///< tracker stream: capture, or hivecal's tracker log or a tracker export
};

/// How streams become samples.
struct SessionConfig {
  RobotModel
      speed_model;  ///< nominal geometry with the tool (tool speeds; the joints' noise in an orientation's lever)
  double max_speed_m_s = 0.0;              ///< quasi-static threshold [m/s]; 0: the library default
  ExtractionObserver* observer = nullptr;  ///< sees each tracker point kept or dropped (extraction pass); may be null
  double window_s = 0.0;                   ///< optional stability window [s]; 0: none (the paper's rule at the instant)
  bool progress = false;                   ///< "[decode] pass i/2" lines on stderr
  textio::RobotLogOptions
      log_options;  ///< joint names of ROS robot logs (UR driver names by default), units of text inputs
  textio::OrientationInput
      orientation;  ///< how measured orientations (rx, ry, rz of paired samples) become targets 2 and 3
};

/// The --joint-names value (six comma-separated names, or "" for the UR driver names) into
/// *log_options; Fault::usage otherwise.
port::Error joint_names_option(const std::string& value, textio::RobotLogOptions* log_options);

/// What the input stage found (for the terminal, the report and the JSON).
struct SessionFacts {
  std::vector<std::string> info_lines;  ///< human-readable facts (inputs, clock, samples kept/dropped)
  bool has_stream = false;              ///< the dataset came from two streams (run below is meaningful)
  CaptureRunReport run;                 ///< frames / rows, clock fit, extraction counts
  std::vector<std::pair<std::string, std::uint64_t>> dropped;  ///< drop reason -> count
  std::vector<std::string> sample_sources;  ///< where sample k (Sample::index) came from: "file:line" (paired samples)
  textio::OrientationRead orientation;  ///< paired samples: the rows whose measured orientation was used, and the lever
  textio::OrientationInput orientation_input;  ///< the stated sigmas and lever the input was read with
};

/// Where sample `index` (Sample::index) came from: "file:line" for paired samples, else
/// "sample N".
std::string sample_source(const SessionFacts& facts, std::uint32_t index);

/// "orientation used: N poses with rx, ry, rz, ..." for the console and the report; "" when
/// no measured orientation was used.
std::string orientation_line(const SessionFacts& facts);

/// Fills `dataset` from `sources`. Fault::input (with file and line where known) when a file
/// is missing, not a regular file, too large or malformed, when a stream holds no record,
/// when the clock relation cannot be found, or when the samples do not fit the dataset (a
/// truncated dataset is never used silently). Fault::usage for an incomplete choice of
/// sources. On a clock failure, facts->run already holds the frame counts.
port::Error load_session(const SessionSources& sources, const SessionConfig& config, DatasetBase* dataset,
                         SessionFacts* facts);

}  // namespace hivecal::streams
