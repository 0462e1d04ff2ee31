// The parameter covariance and the calibration's domain a result carries, and the domain
// statement that calibrate, validate, export and the report print (docs/robust.md,
// "Prediction uncertainty and the calibration's domain").
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/solve/prediction_uncertainty.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

/// The covariance of the parameters `estimated` at `model` / `base_to_tracker` over the
/// training samples `train` under `loss` and the fit's `prior` (lib's parameter_covariance: the
/// posterior when the fit held one), targets 2..'s own
/// sigmas beside it, and the domain of the training poses under it (calibration_domain).
/// Without a covariance (a fit without residual degrees of freedom, or not determined) the
/// domain holds the joint ranges and spread alone, and *note says why.
void compute_uncertainty(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> train,
                         const PointLoss& loss, const LmPrior& prior, ParamMask estimated,
                         const Vec3 (&other_tools_sigma_m)[kMaxTargets - 1],
                         record::CalibrationUncertainty* uncertainty, std::string* note);

/// When a prediction counts as extrapolated under `domain`, in words ("its sigma exceeds 3x the
/// training poses' typical 0.0215 mm, or the tool axis lies ...").
std::string extrapolation_rule(const CalibrationDomain& domain);

/// The domain statement: the training poses' joint ranges [deg], the tool axis's spread, the
/// predictions' typical 1-sigma there and when a prediction counts as extrapolated. Empty
/// without a domain. `joints`: the arm's joint count (the ranges of q1 .. q<joints>).
std::vector<std::string> domain_lines(const record::CalibrationUncertainty& uncertainty, int joints);

/// One predicted point, its 1-sigma and whether it is an extrapolation.
struct Prediction {
  Vec3 point_m = Vec3::Zero();  ///< in the chosen frame [m]
  double sigma_m = 0.0;         ///< 1-sigma per axis (prediction_sigma_m); 0 without a covariance [m]
  Extrapolation extrapolation;  ///< against the calibration's domain (none without one)
};

/// How many predictions were extrapolations, and for which reason (a pose may have several).
struct ExtrapolationCount {
  std::size_t poses = 0;      ///< predictions counted [-]
  std::size_t flagged = 0;    ///< extrapolated for any reason [-]
  std::size_t sigma = 0;      ///< its sigma beyond the multiple [-]
  std::size_t tool_axis = 0;  ///< the tool axis beyond the spread [-]
  std::size_t joint = 0;      ///< a term joint beyond its range [-]
  /// Counts one prediction.
  void add(const Extrapolation& e);
  /// "N of M poses extrapolated (sigma a, tool axis b, joint range c)".
  std::string text() const;
};

/// Predicts points through a calibration result: base_to_tracker * FK(q) * tool of a target
/// (PredictionFrame::tracker) or FK(q) * tool in the file's own base frame, with the sigma and
/// the extrapolation test when the result carries a covariance and a domain. The one place
/// predict and validate compute a prediction.
class Predictor {
 public:
  explicit Predictor(const record::CalibrationFile& calibration);
  /// Whether the predictions carry a sigma and an extrapolation test (covariance and domain).
  bool has_uncertainty() const { return has_uncertainty_; }
  /// The point of target `target` (0-based) at `q_rad`.
  Prediction operator()(const JointVector& q_rad, int target, PredictionFrame frame) const;

 private:
  const record::CalibrationFile& calibration_;
  std::unique_ptr<NormalMatrix> covariance_;  // 43 kB: on the heap
  bool has_uncertainty_ = false;
};

}  // namespace hivecal::cli
