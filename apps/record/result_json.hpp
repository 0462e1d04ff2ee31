// The calibration result file, format "robot-calibration/1" (docs/formats.md): a robot
// description (textio/robot_description.hpp) with the fit's members. Every key a result adds
// to the description is spelled in this folder: here, and in report_json.cpp for the "report"
// member that `hivecal report` draws its page from.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/solve/prediction_uncertainty.hpp"
#include "report/report.hpp"
#include "streams/session.hpp"
#include "textio/json.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::record {

/// The parameter covariance and the calibration's domain a result carries (keys "covariance"
/// and "domain", docs/formats.md): predict's sigma_m and extrapolated columns.
struct CalibrationUncertainty {
  /// C = sigma_hat^2 (J^T W J)^-1 over `estimated` (parameter_covariance), kFullParamCount^2
  /// values in NormalMatrix's (column-major) order; empty: the file holds none [m^2, m rad, rad^2].
  std::vector<double> covariance;
  ParamMask estimated = 0;  ///< the parameters of `covariance` (kOtherTargetTools: targets 2.. eliminated)
  Vec3 other_tools_sigma_m[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};  ///< targets 2..'s own 1-sigma [m]
  double residual_sigma_m = 0.0;                                             ///< sigma_hat per axis [m]
  int residual_dof = 0;                                                      ///< its degrees of freedom [-]
  bool has_domain = false;                                                   ///< `domain` was computed / read
  CalibrationDomain domain;  ///< the training poses: joint ranges, tool orientation spread, typical sigma

  bool has_covariance() const { return !covariance.empty(); }  ///< the file holds a covariance
  /// The covariance as the library's matrix (zero without one).
  NormalMatrix covariance_matrix() const;
  /// Sets the covariance from the library's matrix.
  void set_covariance(const NormalMatrix& matrix);
};

/// What a result file must hold to predict positions, plus its accuracy figures.
struct CalibrationFile : textio::RobotDescription {
  /// Base of the standard-DH chain -> tracker frame: predicted = base_to_tracker * FK(model)
  /// (for a modified-DH file, the file's own base -> tracker times modified_base).
  RigidTransform base_to_tracker;
  bool has_metrics = false;  ///< metrics below were present / are to be written
  AccuracyReport metrics;    ///< train / test / overall error statistics [m]
  /// Standard deviation of each compliance coefficient (model.compliance's unit); 0: unknown,
  /// not written.
  double compliance_sigma[kMaxComplianceTerms] = {};
  CalibrationUncertainty uncertainty;  ///< "covariance" and "domain", when the file holds them
  std::string fitted;  ///< "fitted": what a registration fitted ("base", "frames"); "" for a calibration
};

/// A calibration run as result.json records it: the calibrated model and the facts of the run.
/// The pointers are the run's own results (not copied: the CalibrationResult is ~5 KB, the
/// cross-validation ~20 KB) and must outlive the record.
struct CalibrationRecord {
  CalibrationFile file;                          ///< calibrated model, base -> tracker, train/test metrics
  std::string method;                            ///< the final stage's name ("ABC+LM", "LM+compliance", ...)
  std::string params;                            ///< "paper" (the paper's six lengths) or "full"
  std::uint64_t seed = 1;                        ///< the job's seed [-]
  double split = 0.7;                            ///< share of the samples in training [-]
  AccuracyReport uncalibrated;                   ///< the start model's errors on the same samples [m]
  const CalibrationResult* result = nullptr;     ///< lib's result: outliers, significance, LM details
  const LmResult* final_lm = nullptr;            ///< the LM details when the final stage is LM, else null
  double joint_sigma_rad = 0.0;                  ///< --joint-sigma: joint reading noise, 0 when not given [rad]
  double joint_sigma_position_sigma_m = 0.0;     ///< the position sigma it was weighed against [m]
  bool controller_tcp = false;                   ///< base and tool known (the controller's TCP readings)
  UrCalibrationDeltas ur_deltas;                 ///< the model as UR calibration.conf deltas from the start
  bool ur_shape = true;                          ///< the arm has a UR's joints (has_ur_joints): ur_deltas written
  const streams::SessionFacts* facts = nullptr;  ///< input facts: clock, extraction, orientation, sources
  const CrossValidationResult* cv = nullptr;     ///< --cv's folds, else null
  /// Per fold of `cv`: the samples it held out, as ranges of what names them ("2-4, 7"); may be empty.
  std::vector<std::string> cv_held_out;
  std::string cv_held_out_of;                  ///< what those ranges count: "lines of FILE", or sample numbers
  std::vector<std::string> warnings;           ///< the fit's plausibility warnings
  const report::ReportData* report = nullptr;  ///< the tables and figures (key "report"), else not written
  // file.uncertainty: "covariance" and "domain", after "report", when it holds them
};

/// Writes the "covariance" and "domain" members of `uncertainty` (what it holds) with the
/// parameter names of `model`.
void write_uncertainty(textio::JsonWriter& json, const CalibrationUncertainty& uncertainty, const RobotModel& model);

/// The keys of an ErrorStats' axes in result.json, in ErrorStats' axis order.
inline constexpr const char* kErrorAxisKeys[kErrorAxisCount] = {"x", "y", "z", "3d"};

/// The key of an ErrorStats' sample count in result.json.
inline constexpr const char* kErrorCountKey = "count";
/// One per-axis statistic of an ErrorStats and its key in result.json.
struct ErrorStatsField {
  const char* key;                                ///< "mae_m", ...
  double (ErrorStats::*values)[kErrorAxisCount];  ///< its values, one per axis
};
/// The per-axis statistics of an ErrorStats in result.json, in the order they are written.
inline constexpr ErrorStatsField kErrorStatsFields[] = {
    {"mae_m", &ErrorStats::mae_m}, {"sigma_m", &ErrorStats::sigma_m}, {"max_m", &ErrorStats::max_m}};

/// Writes one w-test row's members: "source" (its file line or sample), "residual_m" [m], "w"
/// and "critical_w" [-] (a blunder set aside, by the calibration or by a registration).
void write_w_test_members(textio::JsonWriter& json, const std::string& source, double residual_m, double w,
                          double critical_w);

/// Writes one ErrorStats as {"count", "mae_m": {x, y, z, 3d}, "sigma_m": {...}, "max_m": {...}}.
void write_error_stats(textio::JsonWriter& json, const ErrorStats& stats);

/// The document of `file` (description, base_to_tracker, metrics when has_metrics);
/// `extra_members` may add keys to the top-level object (the simulator's truth file does).
std::string format_calibration_json(const CalibrationFile& file,
                                    const std::function<void(textio::JsonWriter&)>& extra_members = {});

/// result.json of a run: format_calibration_json of record.file and every member of the record.
std::string format_result_json(const CalibrationRecord& record);

/// Parses and validates a result document (six DH rows, finite numbers, a proper rigid
/// 4x4 transform within 1e-5, re-orthonormalised); errors name the key at fault.
port::Error parse_calibration_json(const std::string& text, const std::string& source_name, CalibrationFile* file);
/// Reads and parses a result file; `text` (optional) receives the file's text, for the keys
/// the caller reads itself (e.g. "report").
port::Error read_calibration_json(const std::string& path, CalibrationFile* file, std::string* text = nullptr);

}  // namespace hivecal::record
