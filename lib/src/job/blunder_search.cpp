// The job's blunder search (calibration.hpp): the consensus screen with the start geometry,
// then data snooping on the final calibration (solve/reliability.hpp's w-test, one pose at a
// time). Method: docs/robust.md, "Blunders".
#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>

#include "hivecal/core/random.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/model/spanning_subset.hpp"

#include "job/blunder_search.hpp"

namespace hivecal::detail {

namespace {
/// Per-axis sigma from the median of 3-D residual norms: for isotropic Gaussian noise the norm
/// is Maxwell-distributed with median 1.5382 sigma (the MAD idea for norms).
constexpr double kMaxwellMedian = 1.5382;

/// The lower median of values[0 .. count) (reordered): the same value whatever the algorithm.
double lower_median(Span<double> values, std::size_t count) {
  double* begin = values.data();
  double* middle = begin + (count - 1) / 2;
  std::nth_element(begin, middle, begin + count);
  return *middle;
}

/// Offers a flagged sample to the set-aside list being built: at most `limit`, the largest
/// residuals kept when more are flagged (ties: the lower index); by decreasing residual.
void offer(CalibrationOutlierList* list, const CalibrationOutlier& item) {
  auto before = [](const CalibrationOutlier& a, const CalibrationOutlier& b) {
    return a.residual_m > b.residual_m || (a.residual_m == b.residual_m && a.index < b.index);
  };
  CalibrationOutlier* items = list->items;
  if (list->count == list->limit && (list->limit == 0 || !before(item, items[list->count - 1]))) return;
  std::size_t k = list->count < list->limit ? list->count++ : list->count - 1;
  for (; k > 0 && before(item, items[k - 1]); --k) items[k] = items[k - 1];
  items[k] = item;
}

/// Sorts a built list by index and fills its `indices`.
void finish(CalibrationOutlierList* list) {
  for (std::size_t i = 1; i < list->count; ++i) {
    const CalibrationOutlier moving = list->items[i];
    std::size_t k = i;
    for (; k > 0 && list->items[k - 1].index > moving.index; --k) list->items[k] = list->items[k - 1];
    list->items[k] = moving;
  }
  for (std::size_t i = 0; i < list->count; ++i) list->indices[i] = list->items[i].index;
}

}  // namespace

Span<const std::uint32_t> index_span(const CalibrationOutlierList& list) {
  return Span<const std::uint32_t>(list.indices, list.count);
}

bool same_indices(const CalibrationOutlierList& a, const CalibrationOutlierList& b) {
  if (a.count != b.count) return false;
  for (std::size_t i = 0; i < a.count; ++i) {
    if (a.indices[i] != b.indices[i]) return false;
  }
  return true;
}

void keep_common(const CalibrationOutlierList& other, CalibrationOutlierList* list) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < list->count; ++i) {
    bool common = false;
    for (std::size_t k = 0; k < other.count; ++k) common = common || other.indices[k] == list->indices[i];
    if (!common) continue;
    list->items[kept] = list->items[i];
    list->indices[kept++] = list->indices[i];
  }
  list->count = kept;
}

namespace {

/// At most this share of the samples is ever set aside: a blunder is a minority.
std::size_t outlier_limit(std::size_t samples) {
  const std::size_t half = samples / 2 > 0 ? samples / 2 - 1 : 0;  // strictly fewer than half
  return half < kMaxCalibrationOutliers ? half : kMaxCalibrationOutliers;
}

/// Residual norms of `samples` under (model, base) into residual_m; the median over the first
/// `median_count` of them (the kept samples) into *median_m. The scratch holds the residuals
/// of its capacity only: samples beyond it are tested, but not part of the median.
void residuals_of(const RobotModel& model, const RigidTransform& base, Span<const Sample> samples,
                  std::size_t median_count, ResidualScratch scratch, double* median_m) {
  const std::size_t n = std::min(median_count, scratch.residual_m.size());
  for (std::size_t i = 0; i < n; ++i) {
    scratch.residual_m[i] = (base.apply(fk_sample_point(model, samples[i])) - samples[i].point_m).norm();
  }
  *median_m = n > 0 ? lower_median(scratch.residual_m, n) : 0.0;
}

/// The factor that turns the median residual of a least-squares fit of `parameters`
/// parameters into a noise estimate: the fit shrinks its own samples' residuals by about
/// sqrt((3 N - p) / 3 N) (few samples, many parameters: far below the noise). 0 without
/// redundancy (3 N <= p): such a fit cannot tell a blunder.
double fit_sigma_factor(std::size_t samples, int parameters) {
  const double equations = 3.0 * static_cast<double>(samples);
  if (equations <= static_cast<double>(parameters)) return 0.0;
  return std::sqrt(equations / (equations - static_cast<double>(parameters)));
}

/// Flags every stored sample (kept and set aside) whose residual under (model, base) exceeds
/// max(k sigma, floor), sigma = factor * median residual of the kept ones / 1.5382. Returns
/// false, with nothing flagged, when factor is 0 (no redundancy).
bool flag_outliers(const RobotModel& model, const RigidTransform& base, const DatasetBase& dataset,
                   const CalibrationOptions& o, double floor_m, double factor, ResidualScratch scratch,
                   CalibrationOutlierList* list, double* threshold_m) {
  list->count = 0;
  if (!(factor > 0.0)) {
    *threshold_m = 0.0;
    finish(list);
    return false;
  }
  double median_m = 0.0;
  residuals_of(model, base, dataset.samples(), dataset.size(), scratch, &median_m);
  const double sigma_m = factor * median_m / kMaxwellMedian;
  *threshold_m = std::fmax(o.outlier_k * sigma_m, floor_m);
  list->limit = outlier_limit(dataset.size() + dataset.set_aside().size());
  for (Span<const Sample> part : {dataset.samples(), dataset.set_aside()}) {
    for (const Sample& s : part) {
      const double r = (base.apply(fk_sample_point(model, s)) - s.point_m).norm();
      if (r > *threshold_m) offer(list, CalibrationOutlier{s.index, r});
    }
  }
  finish(list);
  return true;
}

}  // namespace

/// Consensus screen with the start geometry: the base fitted on random point triples (seeded,
/// deterministic), the one with the least median residual over all samples kept (LMedS, robust
/// to almost half the samples being wrong), and the samples far from it flagged. Errors:
/// degenerate_geometry when no triple spans a plane (the base frame is not determined).
[[gnu::noinline]] Status screen(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& o,
                                CalibrationWorkspaceBase& workspace, CalibrationOutlierList* list) {
  dataset->set_aside(Span<const std::uint32_t>());
  const Span<const Sample> samples = dataset->samples();
  const std::size_t n = samples.size();
  // Several targets: the start model does not know the other reflectors' tool points, so the
  // start geometry cannot predict their samples; the w-test of the calibration (which
  // estimates them) is the only blunder search then.
  if (target_count(samples) > 1) {
    list->count = 0;
    return n < 3 ? Status::too_few_samples : Status::ok;
  }
  ResidualScratch scratch = workspace.open_residuals();
  const std::size_t m = std::min(n, scratch.predicted_m.size());
  for (std::size_t i = 0; i < m; ++i) scratch.predicted_m[i] = fk_tool_point(start, samples[i].q_rad);
  Random random(o.seed ^ 0x6c6d656473ULL);  // its own stream: the split's draws stay as they were
  double best_median_m = 0.0;
  RigidTransform best;
  bool found = false;
  if (o.base_known) {  // nothing to find by consensus: the base is given
    best = o.known_base_to_tracker;
    found = m >= 1;
  }
  for (std::size_t trial = 0; !o.base_known && m >= 3 && trial < o.consensus_trials; ++trial) {
    const auto a = static_cast<std::size_t>(random.below(m));
    const auto b = static_cast<std::size_t>(random.below(m));
    const auto c = static_cast<std::size_t>(random.below(m));
    if (a == b || b == c || a == c) continue;
    RigidFitAccumulator fit;
    for (std::size_t k : {a, b, c}) fit.add(scratch.predicted_m[k], samples[k].point_m);
    RigidTransform base;
    if (fit.solve(&base) != Status::ok) continue;
    for (std::size_t i = 0; i < m; ++i) {
      scratch.residual_m[i] = (base.apply(scratch.predicted_m[i]) - samples[i].point_m).norm();
    }
    const double median_m = lower_median(scratch.residual_m, m);
    if (!found || median_m < best_median_m) {
      best_median_m = median_m;
      best = base;
      found = true;
    }
  }
  workspace.close();
  if (!found) return n < 3 ? Status::too_few_samples : Status::degenerate_geometry;
  double threshold_m = 0.0;
  scratch = workspace.open_residuals();
  // The consensus base fits its triple exactly, so on a small set the median leans towards
  // those zeros: Rousseeuw and Leroy's finite-sample factor 1 + 5 / (n - 3) for LMedS, then a
  // least-squares refit on the samples it accepts and the test again (reweighted LS).
  const double lmeds_factor = o.base_known ? 1.0 : n > 3 ? 1.0 + 5.0 / static_cast<double>(n - 3) : 0.0;
  flag_outliers(start, best, *dataset, o, o.screen_floor_m, lmeds_factor, scratch, list, &threshold_m);
  RigidFitAccumulator refit;
  for (std::size_t i = 0; i < m; ++i) {
    bool flagged = false;
    for (std::uint32_t index : index_span(*list)) flagged = flagged || samples[i].index == index;
    if (!flagged) refit.add(scratch.predicted_m[i], samples[i].point_m);
  }
  RigidTransform refined;
  if (!o.base_known && refit.solve(&refined) == Status::ok) {
    flag_outliers(start, refined, *dataset, o, o.screen_floor_m, fit_sigma_factor(n, kBaseParamCount), scratch, list,
                  &threshold_m);
  }
  workspace.close();
  return Status::ok;
}

namespace {

/// Poses of `units` that may fail the test as blunders: max_blunder_share of them, at least
/// one; more is the model's error, not the data's.
std::size_t share_limit(std::size_t units, const CalibrationOptions& o) {
  const auto share = static_cast<std::size_t>(o.max_blunder_share * static_cast<double>(units));
  return std::min<std::size_t>(share > 0 ? share : 1, kMaxCalibrationOutliers);
}

}  // namespace

/// Training poses the w-test may remove: max_blunder_share of them, at least one.
std::size_t blunder_limit(const DatasetBase& dataset, const CalibrationOptions& o) {
  return share_limit(count_units(dataset.train(), target_count(dataset.samples()) > 1), o);
}

std::size_t test_blunder_limit(const DatasetBase& dataset, const CalibrationOptions& o) {
  return share_limit(count_units(dataset.test(), target_count(dataset.samples()) > 1), o);
}

namespace {

/// Where the split's test poses lie in the predicted span: [first, end) [-].
struct PositionRange {
  std::size_t first = 0;
  std::size_t end = 0;
  bool holds(std::size_t position) const { return position >= first && position < end; }
};

/// Keeps the controlled fitted unit that exceeds its threshold most (w / critical_w), offers
/// every rejected predicted unit's samples to the list, and counts the test poses (`test`)
/// that fail.
class SnoopVisitor final : public UnitTestVisitor {
 public:
  SnoopVisitor(Span<const Sample> predicted, CalibrationOutlierList* list, PositionRange test = {})
      : predicted_(predicted), list_(list), test_(test) {}
  void on_unit(const UnitTest& t) override {
    if (!t.rejected()) return;
    if (t.fitted) {
      if (t.w / t.critical_w > worst_ratio_) {
        worst_ratio_ = t.w / t.critical_w;
        worst_ = t;
      }
      return;
    }
    if (test_.holds(t.position)) {
      ++failing_test_poses_;
      largest_test_w_ = std::fmax(largest_test_w_, t.w);
    }
    for (std::uint32_t k = 0; k < t.samples; ++k) {
      offer(list_, CalibrationOutlier{predicted_[t.position + k].index, t.residual_m, t.w, t.critical_w});
    }
  }
  bool has_worst() const { return worst_ratio_ > 1.0; }
  const UnitTest& worst() const { return worst_; }
  std::size_t failing_test_poses() const { return failing_test_poses_; }
  double largest_test_w() const { return largest_test_w_; }

 private:
  Span<const Sample> predicted_;
  CalibrationOutlierList* list_;
  PositionRange test_;
  UnitTest worst_;
  double worst_ratio_ = 1.0;
  std::size_t failing_test_poses_ = 0;
  double largest_test_w_ = 0.0;
};

/// Whether a sample of `part` has this index.
bool holds_index(Span<const Sample> part, std::uint32_t index) {
  for (const Sample& s : part) {
    if (s.index == index) return true;
  }
  return false;
}

/// Takes off a list being built the samples of `test` (the split's test poses) and those of
/// `aside` (set aside by the screen or an earlier run) that fail no worse than a test pose
/// (w <= largest_test_w): the test cannot tell them from the model's error.
void drop_held_out(Span<const Sample> test, Span<const Sample> aside, double largest_test_w,
                   CalibrationOutlierList* list) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < list->count; ++i) {
    const CalibrationOutlier& item = list->items[i];
    const bool drop = holds_index(test, item.index) || (item.w <= largest_test_w && holds_index(aside, item.index));
    if (!drop) list->items[kept++] = item;
  }
  list->count = kept;
}

}  // namespace

LmPrior job_lm_prior(const RobotModel& nominal, const LmPriorTolerances& tolerances) {
  return lm_prior(nominal, tolerances);
}

/// The loss the w-test whitens with: LM's joint noise, no Huber weights.
PointLoss blunder_test_loss(const CalibrationOptions& o) {
  return PointLoss{0.0, o.lm.joint_sigma_rad > 0.0 ? o.lm.joint_sigma_rad / o.lm.position_sigma_m : 0.0};
}

namespace {

/// One w-test of the fit (model, base) on `fitted`, predicting `predicted`.
Status run_blunder_test(CalibrationWorkspaceBase& workspace, const CalibrationOptions& o, const RobotModel& model,
                        const RigidTransform& base, Span<const Sample> fitted, Span<const Sample> predicted,
                        ParamMask estimated, UnitTestVisitor* visitor, BlunderTestSummary* summary) {
  ReliabilityWorkspace* ws = workspace.open_reliability();
  const Status status = test_for_blunders(model, base, fitted, predicted, estimated, blunder_test_loss(o),
                                          o.blunder_test, ws, visitor, summary);
  workspace.close();
  return status;
}

/// Relative cost decrease at which a refit stops. A refit only decides which pose the next test
/// looks at (the job runs the set again from the start for its result): stopped when a step
/// lowers the cost by less than 1e-10 of it, its parameters are within about sqrt(1e-10 dof)
/// sigma of the optimum (delta^T N delta ~ 1e-10 SSR), 0.002 sigma for 10^4 poses, and a pose's
/// w moves by less. LM's default 1e-12 spent up to 9 iterations, each a pass over the set, on
/// rounding noise.
constexpr double kRefitCostTolerance = 1e-10;

/// LM again on `fitted` from (workspace.lm_start(), *base) with the parameters of `estimated`,
/// the result back into both; its details go to the LM phase's scratch result, not the job's.
[[gnu::noinline]] Status refit(CalibrationWorkspaceBase& workspace, const CalibrationOptions& o,
                               const RobotModel& nominal, Span<const Sample> fitted, ParamMask estimated,
                               RigidTransform* base) {
  LmOptions lm = o.lm;
  lm.prior = job_lm_prior(nominal, o.prior);
  lm.params = LmParamSet::custom;
  lm.custom_mask = estimated & ~kOtherTargetTools;
  lm.other_target_tools = (estimated & kOtherTargetTools) != 0;
  lm.loss = LmLoss::squared;
  lm.cost_tolerance = std::fmax(lm.cost_tolerance, kRefitCostTolerance);
  const RigidTransform start_base = *base;
  const CalibrationWorkspaceBase::LmScratch scratch = workspace.open_lm_scratch();
  Status status =
      calibrate_lm(workspace.lm_start(), &start_base, fitted, lm, scratch.lm, scratch.result, nullptr, nullptr);
  if (status == Status::ok || status == Status::not_converged) {
    workspace.lm_start() = scratch.result->model;
    *base = scratch.result->base_to_tracker;
    status = Status::ok;
  }
  workspace.close();
  return status;
}

/// Moves the removed poses back where they were (latest first): the split as the run left it.
void undo_removals(DatasetBase* dataset, CalibrationWorkspaceBase& workspace, std::size_t removed, std::size_t fitted) {
  const std::uint32_t(&moves)[kMaxCalibrationOutliers][2] = workspace.snoop_moves();
  while (removed > 0) {
    --removed;
    const std::size_t position = moves[removed][0];
    const std::size_t end = moves[removed][1];
    const std::size_t count = end - fitted;
    for (std::size_t k = 0; k < count; ++k) dataset->swap_samples(position + k, end - count + k);
    fitted = end;
  }
}

}  // namespace

/// Data snooping on the final calibration: the training pose whose w exceeds its threshold
/// most is moved behind the fitted samples and the fit repeated (LM, the same parameters), one
/// pose at a time, until none does; then the removed, test and set-aside samples are tested
/// as predictions of that fit and those that fail fill *found. More removals than
/// blunder_limit: the model, not the data, is wrong; the removals are undone and only the
/// samples set aside before (the screen's) are tested. The removals are undone at the end: the
/// dataset is in the run's order again. *summary: the first test (the final calibration on its
/// training poses).
[[gnu::noinline]] BlunderVerdict search_blunders(DatasetBase* dataset, const CalibrationOptions& o,
                                                 const RobotModel& nominal, CalibrationWorkspaceBase& workspace,
                                                 const CalibrationResult& r, CalibrationOutlierList* found,
                                                 BlunderTestSummary* summary) {
  found->count = 0;
  found->limit = kMaxCalibrationOutliers;
  const CalibrationStage& final_stage = r.stages[r.stage_count - 1];
  const ParamMask estimated = calibration_estimated_mask(r);
  const std::size_t train = dataset->train().size();
  const std::size_t stored = dataset->size() + dataset->set_aside().size();
  const Span<const Sample> all(dataset->samples().data(), stored);
  const std::size_t limit = blunder_limit(*dataset, o);
  RobotModel& model = workspace.lm_start();  // the point of the search (not on the stack under LM)
  model = final_stage.model;
  RigidTransform base = final_stage.base_to_tracker;
  std::size_t fitted = train;
  std::size_t removed = 0;
  bool model_error = false;
  for (bool first = true;; first = false) {
    SnoopVisitor visitor(Span<const Sample>(), found);
    BlunderTestSummary pass;
    const Status tested = run_blunder_test(workspace, o, model, base, all.subspan(0, fitted), Span<const Sample>(),
                                           estimated, &visitor, &pass);
    if (tested != Status::ok) {
      if (first) return BlunderVerdict::not_searched;
      break;
    }
    if (first) *summary = pass;
    if (!visitor.has_worst()) break;
    if (removed == limit) {
      model_error = true;
      break;
    }
    const UnitTest& worst = visitor.worst();
    workspace.snoop_moves()[removed][0] = worst.position;
    workspace.snoop_moves()[removed][1] = static_cast<std::uint32_t>(fitted);
    for (std::uint32_t k = worst.samples; k > 0; --k) dataset->swap_samples(worst.position + k - 1, --fitted);
    ++removed;
    if (refit(workspace, o, nominal, all.subspan(0, fitted), estimated, &base) != Status::ok) break;
  }
  if (model_error) {
    undo_removals(dataset, workspace, removed, fitted);
    removed = 0;
    fitted = train;
    model = final_stage.model;
    base = final_stage.base_to_tracker;
  }
  const std::size_t predicted_from = model_error ? dataset->size() : fitted;
  const Span<const Sample> predicted = all.subspan(predicted_from, stored - predicted_from);
  const PositionRange test{train - std::min(train, predicted_from), dataset->size() - predicted_from};
  SnoopVisitor visitor(predicted, found, test);
  BlunderTestSummary pass;
  run_blunder_test(workspace, o, model, base, all.subspan(0, fitted), predicted, estimated, &visitor, &pass);
  // The test poses obey the training poses' rule: more failing than a blunder explains is a fit
  // that does not carry to poses it did not see (too few poses for its parameters, unmodelled
  // effects), not bad readings; set aside, they would shrink the next run's set, whose fit
  // predicts its own test poses no better, run after run. A pose set aside before stays aside
  // only if it fails worse than every test pose.
  const bool prediction_error = visitor.failing_test_poses() > test_blunder_limit(*dataset, o);
  if (prediction_error) drop_held_out(dataset->test(), dataset->set_aside(), visitor.largest_test_w(), found);
  // The samples back in the run's order: what is reported of the run is summed in it.
  undo_removals(dataset, workspace, removed, fitted);
  finish(found);
  if (model_error) return BlunderVerdict::model_error;
  if (prediction_error) return BlunderVerdict::prediction_error;
  return found->count == kMaxCalibrationOutliers ? BlunderVerdict::list_full : BlunderVerdict::clean;
}

}  // namespace hivecal::detail
