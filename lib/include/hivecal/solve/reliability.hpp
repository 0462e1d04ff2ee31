// Internal reliability of a least-squares fit and its blunder test (data snooping: Baarda's
// w-test with the redundancy numbers of the fit, Pope's studentized form when the noise is
// estimated from the data). The unit of a test is a pose: its samples at equal joints, every
// reflector together, so a blunder of one reading cannot hide in its neighbours. Method and
// figures: docs/robust.md, "Blunders".
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"

namespace hivecal {

/// Samples of one tested unit at most (a pose measured with every reflector); a longer run
/// of samples at equal joints is tested in parts of this size [-].
inline constexpr int kMaxUnitSamples = kMaxTargets;
/// Rows of one tested unit at most [-].
inline constexpr int kMaxUnitRows = 3 * kMaxUnitSamples;

/// Settings of the blunder test.
struct BlunderTestOptions {
  /// Significance for the whole set: the chance that a set without a blunder loses a pose.
  /// Each of the n units is tested at alpha / n (Bonferroni) [-].
  double alpha = 1e-3;
  /// Stated noise of the measured points per axis (Leica AT960-class at a few metres): the
  /// test's sigma when the fit leaves too little redundancy to estimate it, or when the fit's
  /// own sigma is below it (noise-free or rounded readings) [m].
  double tracker_sigma_m = 1e-5;
  /// Units with a redundancy number below this are uncontrolled: a blunder there moves the
  /// fit instead of showing in the residual, so they are reported and never removed [-].
  double min_redundancy = 0.1;
};

/// Where the test's sigma came from.
enum class SigmaSource : std::uint8_t {
  data,     ///< the fit's residuals: each fitted unit against the others' (studentized), F distribution
  tracker,  ///< BlunderTestOptions::tracker_sigma_m (too little redundancy, or a fit finer than it), chi-square
};

/// Lower-case name of a sigma source ("data", "tracker").
const char* sigma_source_name(SigmaSource source);

/// The test of one unit.
struct UnitTest {
  std::uint32_t index = 0;     ///< Sample::index of its first sample [-]
  std::uint32_t position = 0;  ///< position of its first sample in its span (fitted or predicted) [-]
  std::uint32_t samples = 0;   ///< samples in the unit [-]
  bool fitted = false;         ///< in the fit (w-test on its redundancy), else predicted by it
  bool controlled = false;     ///< tested: predicted, or fitted with redundancy >= min_redundancy
  double redundancy =
      0.0;         ///< r = 1 - trace(H_uu) / rows: the share of a blunder its residual shows (predicted: 1) [-]
  double w = 0.0;  ///< sqrt(e^T Q^-1 e) / sigma, Q = I - H_uu (fitted) or I + H_uu (predicted) [-]
  /// w above which the unit is a blunder at the stated significance; for a pose of several
  /// readings tested on the data's sigma, with their correlation pooled over the fitted poses
  /// (BlunderTestSummary::pooled_correlation) [-]
  double critical_w = 0.0;
  double residual_m = 0.0;  ///< largest 3-D residual of its samples [m]
  double mdb_m = 0.0;       ///< minimal detectable bias (power 80 %): sigma sqrt(lambda0 / r); 0 when uncontrolled [m]

  bool rejected() const { return controlled && w > critical_w; }  ///< a blunder by the test
};

/// Receives each unit's test, in span order (fitted first, then predicted).
class UnitTestVisitor {
 public:
  virtual void on_unit(const UnitTest& test) = 0;

 protected:
  UnitTestVisitor() = default;
  UnitTestVisitor(const UnitTestVisitor&) = default;
  UnitTestVisitor& operator=(const UnitTestVisitor&) = default;
  ~UnitTestVisitor() = default;
};

/// What the whole test found.
struct BlunderTestSummary {
  SigmaSource sigma_source = SigmaSource::data;  ///< where sigma came from
  double sigma_m = 0.0;                          ///< sigma per axis the test used [m]
  double fit_sigma_m = 0.0;      ///< the fit's own residual sigma per axis, sqrt(SSR / dof) (0 without dof) [m]
  double dof = 0.0;              ///< the fit's redundancy 3 N - p [-]
  std::size_t units = 0;         ///< units tested (fitted and predicted) [-]
  std::size_t fitted_units = 0;  ///< units in the fit [-]
  std::size_t uncontrolled = 0;  ///< fitted units below min_redundancy [-]
  std::size_t rejected = 0;      ///< controlled units above their critical w [-]
  /// The readings of one pose were tested with their correlation pooled over the fitted poses
  /// (several readings per pose, the data's sigma, at least kMinPooledPoses poses).
  bool pooled_correlation = false;
};

/// Fitted poses a correlation between two readings of a pose is pooled over at least: below it,
/// its standard error (~1/sqrt(n)) passes 0.18 and the readings are tested as independent [-].
inline constexpr std::size_t kMinPooledPoses = 30;

/// Scratch of the test (~24 kB): in the caller's memory plan, not on a small stack.
struct ReliabilityWorkspace {
  NormalEquations normal;               ///< the fit's normal equations at its point
  NormalMatrix scaled;                  ///< their column-scaled matrix (kept block), then unused
  KeptCholesky factor;                  ///< its Cholesky factor over the estimated parameters
  TargetBlock blocks[kMaxTargets - 1];  ///< the other targets' eliminated tool points
  /// A unit's scaled rows, Schur-reduced, one per column over the factored parameters (factor.index).
  Eigen::Matrix<double, kFullParamCount, kMaxUnitRows> rows;
  Eigen::Matrix<double, kFullParamCount, kMaxUnitRows> solved;  ///< the same through the inverse normal matrix
  Eigen::Matrix<double, kMaxUnitRows, kMaxUnitRows> hat;        ///< the unit's hat block H_uu, then I -+ H_uu factored
  Eigen::Matrix<double, kMaxUnitRows, kMaxUnitRows>
      correlation;  ///< the readings' pooled correlation (row k: reading k / 3, axis k % 3)
  Eigen::Matrix<double, kMaxUnitRows, 3> tool_rows;    ///< its rows' own tool Jacobian t (other targets)
  Eigen::Matrix<double, kMaxUnitRows, 3> tool_solved;  ///< D^-1 t^T per row
  double residual_m[kMaxUnitRows] = {};                ///< its residual rows [m]
  FullJacobian jacobian;                               ///< one sample's rows
  SampleRowsContext rows_context;                      ///< the tested model's, for every sample's rows
  FullParams row;                                      ///< one row of the Jacobian, Schur-reduced
};

/// Tests the units of `fitted` (the samples a least-squares fit at (model, base) used, with the
/// parameters of `estimated`; kOtherTargetTools when the other targets' tool points were
/// estimated too) and of `predicted` (samples it did not use) for blunders; `loss`'s joint
/// noise whitens as the fit did (its Huber threshold is not used). Each unit goes to
/// `visitor` (may be null), the totals to *summary. Errors: dataset_empty (no fitted
/// sample), non_finite_input, singular_system (the estimated parameters are not determined
/// by `fitted`), invalid_argument (options).
Status test_for_blunders(const RobotModel& model, const RigidTransform& base, Span<const Sample> fitted,
                         Span<const Sample> predicted, ParamMask estimated, const PointLoss& loss,
                         const BlunderTestOptions& options, ReliabilityWorkspace* workspace, UnitTestVisitor* visitor,
                         BlunderTestSummary* summary);

/// End of the unit that starts at `begin` in `samples`: with several targets the run of
/// samples at equal joints (at most kMaxUnitSamples), else the sample alone [-].
std::size_t unit_end(Span<const Sample> samples, std::size_t begin, bool grouped);

/// Units (poses, see unit_end) of `samples` [-].
std::size_t count_units(Span<const Sample> samples, bool grouped);

}  // namespace hivecal
