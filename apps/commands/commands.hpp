// The hivecal subcommands; each takes argv after its own name and returns an exit code.
#pragma once

#include "cli/options.hpp"

namespace hivecal::cli {

// Each subcommand's name, as typed after `hivecal` and shown in its messages.
inline constexpr const char* kPredictCommand = "predict";
inline constexpr const char* kCalibrateCommand = "calibrate";
inline constexpr const char* kReportCommand = "report";
inline constexpr const char* kValidateCommand = "validate";
inline constexpr const char* kPlanCommand = "plan";
inline constexpr const char* kExportCommand = "export";
inline constexpr const char* kCheckRobotCommand = "check-robot";
inline constexpr const char* kIso9283Command = "iso9283";
inline constexpr const char* kDemoCommand = "demo";

int predict_main(int argc, char** argv);      ///< positions of poses from a calibration result
int calibrate_main(int argc, char** argv);    ///< geometry from tracker data: tables, result, report
int report_main(int argc, char** argv);       ///< the HTML report again from a result file
int validate_main(int argc, char** argv);     ///< a calibration against a reference geometry on fresh poses
int plan_main(int argc, char** argv);         ///< which poses to measure, in which order, and a URScript program
int export_main(int argc, char** argv);       ///< a calibration as URDF or a robot description
int check_robot_main(int argc, char** argv);  ///< what hivecal reads from a robot file
int iso9283_main(int argc, char** argv);      ///< ISO 9283 pose accuracy and repeatability of measured reaches
int demo_main(int argc, char** argv);         ///< small simulated check of the core library

}  // namespace hivecal::cli
