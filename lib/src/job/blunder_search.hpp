// The job's blunder search, internal to the job (blunder_search.cpp): what calibrate() calls.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/calibration.hpp"

namespace hivecal::detail {

/// The positions of a finished outlier list (sorted), as a span.
Span<const std::uint32_t> index_span(const CalibrationOutlierList& list);

/// Whether two finished lists hold the same samples.
bool same_indices(const CalibrationOutlierList& a, const CalibrationOutlierList& b);

/// Keeps in the finished *list only the samples `other` (finished) holds too.
void keep_common(const CalibrationOutlierList& other, CalibrationOutlierList* list);

/// Consensus screen with the start geometry: the base fitted on random point triples (seeded,
/// deterministic), the one with the least median residual over all samples kept (LMedS), and
/// the samples far from it into *list. Errors: degenerate_geometry when no triple spans a
/// plane (the base frame is not determined).
Status screen(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& o,
              CalibrationWorkspaceBase& workspace, CalibrationOutlierList* list);

/// Training poses the w-test may remove: max_blunder_share of them, at least one [-].
std::size_t blunder_limit(const DatasetBase& dataset, const CalibrationOptions& o);

/// The split's test poses that may fail as predictions and be set aside: the same share [-].
std::size_t test_blunder_limit(const DatasetBase& dataset, const CalibrationOptions& o);

/// The loss the w-test whitens with: LM's joint noise, no Huber weights.
PointLoss blunder_test_loss(const CalibrationOptions& o);

/// Data snooping on the final calibration of `r` (one pose at a time, refitting), then the
/// removed, test and set-aside samples tested as predictions; those that fail into *found.
/// *summary: the first test (the final calibration on its training poses). The refits' details
/// stay in the workspace's LM phase (open_lm_scratch): `r` keeps the final calibration's. The
/// refits hold the job's prior around `nominal` (job_lm_prior).
BlunderVerdict search_blunders(DatasetBase* dataset, const CalibrationOptions& o, const RobotModel& nominal,
                               CalibrationWorkspaceBase& workspace, const CalibrationResult& r,
                               CalibrationOutlierList* found, BlunderTestSummary* summary);

/// The prior of the job around the start model `nominal` (the job's, with the given tool point)
/// with `tolerances`; none when they are all 0. A fit passes the options' (LM checks them against
/// the data itself); the folds and eliminations that predict from a fit pass the tolerances that
/// fit held (LmResult::prior_tolerances).
LmPrior job_lm_prior(const RobotModel& nominal, const LmPriorTolerances& tolerances);

}  // namespace hivecal::detail
