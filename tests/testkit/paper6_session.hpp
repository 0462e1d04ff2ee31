// A whole simulated paper-6 session for solver tests: dataset, 70/30 split, precomputed cost
// on the training part, search box and the least-squares reference MAE.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/solve/paper6_cost.hpp"
#include "testkit/paper6_data.hpp"

namespace hivecal::test {

/// Largest session the solver tests build.
inline constexpr std::size_t kMaxSessionSamples = 400;

struct Paper6Session {
  Dataset<kMaxSessionSamples> dataset;  ///< all poses, split 70/30
  Paper6Cost<kMaxSessionSamples> cost;  ///< on the training poses
  Paper6Cell cell;                      ///< nominal and true geometry
  LinkLengthBox box;                    ///< nominal +/- 2 mm
  double nominal_mae_m = 0.0;           ///< training MAE of the nominal lengths [m]
  double reference_mae_m = 0.0;         ///< training MAE of the least-squares lengths [m]

  /// Simulates `poses` tool-down poses (10 um noise) of an arm off as `kind` says.
  /// Returns false if any step failed.
  bool simulate(std::uint64_t seed, std::size_t poses, Paper6Truth kind) {
    Random random(seed);
    cell = paper6_cell(&random, kind);
    dataset.clear();
    fill_tool_down(cell, poses, 1e-5, &random, &dataset);
    if (dataset.size() != poses || dataset.split(kDefaultTrainFraction, seed) != Status::ok) return false;
    if (cost.build(cell.nominal, dataset.train()) != Status::ok) return false;
    if (link_length_box(cell.nominal, kPaper6DefaultHalfWidth_m, &box) != Status::ok) return false;
    nominal_mae_m = generic_mae(cell.nominal, link_lengths(cell.nominal).data(), dataset.train());
    reference_mae_m =
        generic_mae(cell.nominal, least_squares_lengths(cell.nominal, dataset.train()).data(), dataset.train());
    return nominal_mae_m > 0.0 && reference_mae_m > 0.0;
  }

  /// Test-set MAE [m] of lengths_m (base refitted on the training poses, as in the paper).
  double test_mae(const double* lengths_m) const {
    const RobotModel model = with_link_lengths(cell.nominal, link_length_set(cell.nominal), lengths_m);
    RigidTransform base;
    double mae_m = -1.0;
    if (fit_base_to_tracker(model, dataset.train(), &base) != Status::ok) return mae_m;
    (void)evaluate_cost(model, dataset.test(), CostKind::mean_abs_3d, BaseFrame::fixed, &base, &mae_m);
    return mae_m;
  }
};

/// One session object in static storage (~100 KiB), shared by a test file.
inline Paper6Session& shared_session() {
  static Paper6Session session;
  return session;
}

/// Median of a small array (sorted in place by insertion).
inline double median_of(double* values, std::size_t count) {
  for (std::size_t i = 1; i < count; ++i) {
    for (std::size_t j = i; j > 0 && values[j] < values[j - 1]; --j) {
      const double t = values[j];
      values[j] = values[j - 1];
      values[j - 1] = t;
    }
  }
  return count % 2 == 1 ? values[count / 2] : 0.5 * (values[count / 2 - 1] + values[count / 2]);
}

}  // namespace hivecal::test
