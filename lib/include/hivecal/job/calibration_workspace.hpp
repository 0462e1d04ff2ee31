// The memory of a calibration job (calibration.hpp, the job's one entry): its phases (the
// population stages' cost and solver, LM's workspace, the blunder search's scratch) built one
// at a time in one arena, fixed at compile time (CalibrationWorkspace) or the caller's at run
// time (CalibrationWorkspaceView). docs/architecture.md, "The calibration job".
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>

#include "hivecal/core/span.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/job/calibration_options.hpp"
#include "hivecal/job/calibration_result.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/solve/population_stage.hpp"
#include "hivecal/solve/reliability.hpp"

namespace hivecal {

/// Scratch of the blunder search: one predicted point and one residual per sample.
struct ResidualScratch {
  Span<Vec3> predicted_m;   ///< tool points of the start geometry in the base frame [m]
  Span<double> residual_m;  ///< residual norms [m]
};

/// Capacity-erased workspace: the phases of a job (population cost + solver, LM workspace)
/// are built one at a time in one arena, and the stage traces outlive them.
class CalibrationWorkspaceBase {
 public:
  CalibrationWorkspaceBase(const CalibrationWorkspaceBase&) = delete;
  CalibrationWorkspaceBase& operator=(const CalibrationWorkspaceBase&) = delete;

  /// The objects of a population phase.
  struct PopulationPhase {
    Paper6CostBase* cost = nullptr;  ///< paper-6 cost with room for the training samples
    AbcSolverBase* abc = nullptr;    ///< set by open_abc()
    GsaSolverBase* gsa = nullptr;    ///< set by open_gsa()
    /// The GSA stage (calibrate_paper6_gsa), set with `gsa`: a workspace without GSA never
    /// references its code (the firmware's flash).
    decltype(&calibrate_paper6_gsa) run_gsa = nullptr;
  };
  /// Ends any open phase, builds a cost and an ABC solver in the arena.
  virtual PopulationPhase open_abc() = 0;
  /// Ends any open phase, builds a cost and a GSA solver in the arena (both null: the workspace
  /// has no room for GSA).
  virtual PopulationPhase open_gsa() = 0;
  /// Ends any open phase, builds an LM workspace (joint trig storage attached if the type has it).
  virtual LmWorkspace* open_lm() = 0;
  /// An LM workspace with a result of its own.
  struct LmScratch {
    LmWorkspace* lm = nullptr;   ///< as open_lm()'s
    LmResult* result = nullptr;  ///< where a fit that is not the job's goes (the blunder search's refits)
  };
  /// Ends any open phase, builds open_lm()'s workspace and a result beside it in the arena: the
  /// job's result keeps its final fit.
  virtual LmScratch open_lm_scratch() = 0;
  /// Ends the open phase (its objects are destroyed).
  virtual void close() = 0;
  /// The trace of stage `index` (< kMaxCalibrationStages).
  virtual TraceBase& trace(std::size_t index) = 0;
  /// Ends any open phase, builds the blunder search's scratch in the arena: one predicted
  /// point and one residual per sample, for up to the workspace's sample count.
  virtual ResidualScratch open_residuals() = 0;
  /// The blunder search's lists: 0 the set aside, 1 the last test's.
  virtual CalibrationOutlierList& outlier_list(std::size_t which) = 0;
  /// Ends any open phase, builds the w-test's scratch in the arena.
  virtual ReliabilityWorkspace* open_reliability() = 0;
  /// Room for the positions of a hybrid's spanning subset (empty: none, every sample is searched).
  virtual Span<std::uint32_t> subset_room() = 0;
  /// Where the w-test's removals are undone from: (position, end of the fitted part) per removed pose.
  std::uint32_t (&snoop_moves())[kMaxCalibrationOutliers][2] { return snoop_moves_; }
  /// Where an LM stage keeps the geometry it starts from while it reruns (dropped or not
  /// significant parameters put back): in the workspace, not on the stack under LM (a model
  /// with its compliance is 584 B, and the firmware's stack peak is inside LM).
  RobotModel& lm_start() { return lm_start_; }
  /// Where a joint-term stage keeps the previous fit's errors on the blocked folds while it fits
  /// again (BlockedFoldCheck): not on the stack under LM.
  BlockedFoldErrors& previous_fold_errors() { return previous_fold_errors_; }

 protected:
  CalibrationWorkspaceBase() = default;
  ~CalibrationWorkspaceBase() = default;

 private:
  RobotModel lm_start_;
  BlockedFoldErrors previous_fold_errors_;
  std::uint32_t snoop_moves_[kMaxCalibrationOutliers][2] = {};
};

namespace detail {
/// Joint trig storage for LM, or none (Samples = 0).
template <std::size_t Samples>
struct JointTrigStorage {
  JointTrig values[Samples];
  Span<JointTrig> view() { return Span<JointTrig>(values, Samples); }
};
template <>
struct JointTrigStorage<0> {
  Span<JointTrig> view() { return Span<JointTrig>(); }
};
/// Target blocks for LM's normal equations (several targets), or none (Blocks = 0).
template <std::size_t Blocks>
struct TargetBlockStorage {
  TargetBlock values[Blocks];
  Span<TargetBlock> view() { return Span<TargetBlock>(values, Blocks); }
};
template <>
struct TargetBlockStorage<0> {
  Span<TargetBlock> view() { return Span<TargetBlock>(); }
};
template <std::size_t A, std::size_t B>
inline constexpr std::size_t max_of = A > B ? A : B;
/// Room for a spanning subset's positions, or none (Count = 0).
/// GSA's phase: the cost and a solver of `Population` agents, or nothing (Population = 0).
template <typename Cost, std::size_t Population, std::size_t Lengths>
struct GsaPhaseStorage {
  Cost cost;
  GsaSolver<Population, Lengths> solver;
};
template <typename Cost, std::size_t Lengths>
struct GsaPhaseStorage<Cost, 0, Lengths> {};
template <std::size_t Count>
struct SubsetStorage {
  std::uint32_t values[Count];
  Span<std::uint32_t> view() { return Span<std::uint32_t>(values, Count); }
};
template <>
struct SubsetStorage<0> {
  Span<std::uint32_t> view() { return Span<std::uint32_t>(); }
};
}  // namespace detail

/// A workspace for jobs on up to `Samples` training samples and up to `MaxLinkLengths` link
/// lengths (6: UR arms, the firmware; kMaxLinkLengths: any arm): paper-6 cost with `CostScalar`
/// terms (double: exact; float: half the memory, the firmware's choice), ABC and GSA with up to
/// `Population` members, traces of `TraceCapacity` iterations per stage, and joint trig
/// storage for LM when `JointTrigSamples` > 0 (faster, same bits), and LM's blocks for the
/// tool points of up to `MaxTargets` reflectors (1: one reflector only, 3.6 kB less; the
/// firmware's choice), and room for a hybrid's spanning subset of `SubsetCapacity` samples
/// (4 B each; 0: a hybrid's population stage searches on every sample, as the paper's methods
/// do; by default none for up to kDefaultPopulationSubset samples, else room for up to
/// kMaxPopulationSubset), and GSA with up to `GsaPopulation` agents (0: no GSA phase, a job with GSA ends with
/// population_out_of_range; the firmware's choice, 7.2 kB less). Big: give it static storage.
template <std::size_t Samples, typename CostScalar = double, std::size_t Population = 150,
          std::size_t TraceCapacity = 300, std::size_t JointTrigSamples = 0,
          std::size_t MaxLinkLengths = kPaper6Dimension, std::size_t MaxTargets = kMaxTargets,
          std::size_t SubsetCapacity = (Samples <= kDefaultPopulationSubset ? 0
                                        : Samples < kMaxPopulationSubset    ? Samples
                                                                            : kMaxPopulationSubset),
          std::size_t GsaPopulation = Population>
class CalibrationWorkspace final : public CalibrationWorkspaceBase {
 public:
  using Cost = Paper6Cost<Samples, CostScalar, MaxLinkLengths>;  ///< the population stages' cost
  /// The ABC phase's objects.
  struct AbcPhase {
    Cost cost;
    AbcSolver<Population, MaxLinkLengths> solver;
  };
  /// The GSA phase's objects (none when GsaPopulation is 0).
  using GsaPhase = detail::GsaPhaseStorage<Cost, GsaPopulation, MaxLinkLengths>;
  /// The LM phase's objects.
  struct LmPhase {
    LmWorkspace lm;
    detail::JointTrigStorage<JointTrigSamples> joint_trig;
    detail::TargetBlockStorage<2 * (MaxTargets - 1)> target_blocks;
    LmResult scratch_result;  ///< open_lm_scratch()'s (4 kB on the firmware: the ABC phase is larger)
  };
  /// The blunder search's scratch.
  struct ResidualPhase {
    Vec3 predicted_m[Samples];
    double residual_m[Samples];
  };
  /// Bytes of the arena: the largest phase.
  static constexpr std::size_t kArenaBytes =
      detail::max_of<detail::max_of<detail::max_of<sizeof(AbcPhase), sizeof(GsaPhase)>, sizeof(LmPhase)>,
                     detail::max_of<sizeof(ResidualPhase), sizeof(ReliabilityWorkspace)>>;

  CalibrationWorkspace() = default;
  ~CalibrationWorkspace() { close(); }

  PopulationPhase open_abc() override {
    close();
    abc_ = new (arena_) AbcPhase();
    return PopulationPhase{&abc_->cost, &abc_->solver, nullptr};
  }
  PopulationPhase open_gsa() override {
    close();
    if constexpr (GsaPopulation == 0) {
      return PopulationPhase{};  // no room for GSA
    } else {
      gsa_ = new (arena_) GsaPhase();
      return PopulationPhase{&gsa_->cost, nullptr, &gsa_->solver, &calibrate_paper6_gsa};
    }
  }
  LmWorkspace* open_lm() override {
    close();
    lm_ = new (arena_) LmPhase();
    lm_->lm.joint_trig = lm_->joint_trig.view();
    lm_->lm.target_blocks = lm_->target_blocks.view();
    return &lm_->lm;
  }
  LmScratch open_lm_scratch() override {
    LmWorkspace* lm = open_lm();
    return LmScratch{lm, &lm_->scratch_result};
  }
  ResidualScratch open_residuals() override {
    close();
    residuals_ = new (arena_) ResidualPhase();
    return ResidualScratch{Span<Vec3>(residuals_->predicted_m, Samples), Span<double>(residuals_->residual_m, Samples)};
  }
  ReliabilityWorkspace* open_reliability() override {
    close();
    reliability_ = new (arena_) ReliabilityWorkspace();
    return reliability_;
  }
  void close() override {
    if (reliability_ != nullptr) reliability_->~ReliabilityWorkspace();
    reliability_ = nullptr;
    if (abc_ != nullptr) abc_->~AbcPhase();
    if (gsa_ != nullptr) gsa_->~GsaPhase();
    if (lm_ != nullptr) lm_->~LmPhase();
    if (residuals_ != nullptr) residuals_->~ResidualPhase();
    abc_ = nullptr;
    gsa_ = nullptr;
    lm_ = nullptr;
    residuals_ = nullptr;
  }
  TraceBase& trace(std::size_t index) override { return traces_[index]; }
  CalibrationOutlierList& outlier_list(std::size_t which) override { return outlier_lists_[which]; }
  Span<std::uint32_t> subset_room() override { return subset_.view(); }

 private:
  alignas(alignof(std::max_align_t)) unsigned char arena_[kArenaBytes];
  Trace<TraceCapacity> traces_[kMaxCalibrationStages];
  CalibrationOutlierList outlier_lists_[2];
  detail::SubsetStorage<SubsetCapacity> subset_;
  AbcPhase* abc_ = nullptr;  // the open phase (at most one is set), built in arena_
  GsaPhase* gsa_ = nullptr;
  LmPhase* lm_ = nullptr;
  ResidualPhase* residuals_ = nullptr;
  ReliabilityWorkspace* reliability_ = nullptr;
};

namespace detail {
/// `bytes` rounded up to a multiple of the arena's alignment.
constexpr std::size_t arena_round(std::size_t bytes) {
  return (bytes + alignof(std::max_align_t) - 1) / alignof(std::max_align_t) * alignof(std::max_align_t);
}
/// `count` value-initialised T built one by one at `at` (an array new may add a cookie); the
/// first of them (null when count is 0). `at` must be aligned for T.
template <typename T>
T* construct_array(unsigned char* at, std::size_t count) {
  T* first = nullptr;
  for (std::size_t i = 0; i < count; ++i) {
    T* made = new (at + i * sizeof(T)) T();
    if (i == 0) first = made;
  }
  return first;
}
}  // namespace detail

/// A workspace over the caller's arena for jobs on up to `samples` samples, a count chosen
/// at run time (a host program's: any set that fits in memory; the arena is
/// arena_bytes(samples), allocated where the caller likes). Otherwise the host's choices:
/// exact (double) paper-6 terms for any arm's link lengths, ABC and GSA with up to
/// `Population` members, traces of `TraceCapacity` iterations per stage, joint trig storage for
/// LM, every target, room for a spanning subset. The same bits as CalibrationWorkspace<samples,
/// double, Population, TraceCapacity, samples, kMaxLinkLengths>. Unusable until attach().
template <std::size_t Population = 150, std::size_t TraceCapacity = 300>
class CalibrationWorkspaceView final : public CalibrationWorkspaceBase {
  using Abc = AbcSolver<Population, kMaxLinkLengths>;
  using Gsa = GsaSolver<Population, kMaxLinkLengths>;
  static constexpr std::size_t kTargetBlocks = 2 * (kMaxTargets - 1);
  /// Most samples: every arena size below fits a std::size_t.
  static constexpr std::size_t kMaxSamples = std::size_t{1} << (sizeof(std::size_t) >= 8 ? 32 : 22);

  static constexpr std::size_t cost_values(std::size_t samples) {
    return paper6_storage_values(samples, kMaxLinkLengths);
  }
  static constexpr std::size_t population_bytes(std::size_t samples, std::size_t solver_bytes) {
    return detail::arena_round(solver_bytes) + detail::arena_round(sizeof(Paper6CostView)) +
           cost_values(samples) * sizeof(double);
  }
  static constexpr std::size_t lm_bytes(std::size_t samples) {
    return detail::arena_round(sizeof(LmWorkspace)) + detail::arena_round(sizeof(TargetBlock) * kTargetBlocks) +
           detail::arena_round(sizeof(LmResult)) + sizeof(JointTrig) * samples;
  }
  static constexpr std::size_t residual_bytes(std::size_t samples) {
    return detail::arena_round(sizeof(Vec3) * samples) + sizeof(double) * samples;
  }

 public:
  /// Bytes of arena a workspace for `samples` samples needs (the largest phase) [B].
  static constexpr std::size_t arena_bytes(std::size_t samples) {
    return std::max(std::max(population_bytes(samples, sizeof(Abc)), population_bytes(samples, sizeof(Gsa))),
                    std::max(std::max(lm_bytes(samples), residual_bytes(samples)), sizeof(ReliabilityWorkspace)));
  }

  CalibrationWorkspaceView() = default;
  ~CalibrationWorkspaceView() { close(); }

  /// Works in `arena` (aligned to std::max_align_t, at least arena_bytes(samples) bytes, to
  /// outlive the workspace or the next attach()) for up to `samples` samples. Errors:
  /// invalid_argument (no samples, too many, arena too small or misaligned; nothing changed).
  Status attach(Span<unsigned char> arena, std::size_t samples) {
    const bool aligned = reinterpret_cast<std::uintptr_t>(arena.data()) % alignof(std::max_align_t) == 0;
    if (samples == 0 || samples > kMaxSamples || !aligned || arena.size() < arena_bytes(samples)) {
      return Status::invalid_argument;
    }
    close();
    arena_ = arena.data();
    samples_ = samples;
    return Status::ok;
  }
  /// Samples the attached arena holds (0: not attached) [-].
  std::size_t samples() const { return samples_; }

  PopulationPhase open_abc() override {
    close();
    if (arena_ == nullptr) return PopulationPhase{};
    abc_ = new (arena_) Abc();
    return PopulationPhase{open_cost(sizeof(Abc)), abc_, nullptr};
  }
  PopulationPhase open_gsa() override {
    close();
    if (arena_ == nullptr) return PopulationPhase{};
    gsa_ = new (arena_) Gsa();
    return PopulationPhase{open_cost(sizeof(Gsa)), nullptr, gsa_, &calibrate_paper6_gsa};
  }
  LmWorkspace* open_lm() override {
    close();
    if (arena_ == nullptr) return nullptr;
    lm_ = new (arena_) LmWorkspace();
    unsigned char* at = arena_ + detail::arena_round(sizeof(LmWorkspace));
    TargetBlock* blocks = detail::construct_array<TargetBlock>(at, kTargetBlocks);
    lm_->target_blocks = Span<TargetBlock>(blocks, kTargetBlocks);
    at += detail::arena_round(sizeof(TargetBlock) * kTargetBlocks);
    lm_result_ = new (at) LmResult();
    at += detail::arena_round(sizeof(LmResult));
    lm_->joint_trig = Span<JointTrig>(detail::construct_array<JointTrig>(at, samples_), samples_);
    return lm_;
  }
  LmScratch open_lm_scratch() override {
    LmWorkspace* lm = open_lm();
    return LmScratch{lm, lm == nullptr ? nullptr : lm_result_};
  }
  ResidualScratch open_residuals() override {
    close();
    if (arena_ == nullptr) return ResidualScratch{};
    Vec3* predicted = detail::construct_array<Vec3>(arena_, samples_);
    double* residual = detail::construct_array<double>(arena_ + detail::arena_round(sizeof(Vec3) * samples_), samples_);
    return ResidualScratch{Span<Vec3>(predicted, samples_), Span<double>(residual, samples_)};
  }
  ReliabilityWorkspace* open_reliability() override {
    close();
    if (arena_ == nullptr) return nullptr;
    reliability_ = new (arena_) ReliabilityWorkspace();
    return reliability_;
  }
  void close() override {
    if (cost_ != nullptr) cost_->~Paper6CostView();
    if (abc_ != nullptr) abc_->~Abc();
    if (gsa_ != nullptr) gsa_->~Gsa();
    if (lm_ != nullptr) lm_->~LmWorkspace();
    if (lm_result_ != nullptr) lm_result_->~LmResult();
    if (reliability_ != nullptr) reliability_->~ReliabilityWorkspace();
    cost_ = nullptr;
    abc_ = nullptr;
    gsa_ = nullptr;
    lm_ = nullptr;
    lm_result_ = nullptr;
    reliability_ = nullptr;
  }
  TraceBase& trace(std::size_t index) override { return traces_[index]; }
  CalibrationOutlierList& outlier_list(std::size_t which) override { return outlier_lists_[which]; }
  Span<std::uint32_t> subset_room() override { return Span<std::uint32_t>(subset_); }

 private:
  /// The population phase's cost after its solver of `solver_bytes`, over the rest of the phase.
  Paper6CostBase* open_cost(std::size_t solver_bytes) {
    unsigned char* at = arena_ + detail::arena_round(solver_bytes);
    const std::size_t count = cost_values(samples_);
    // Left uninitialised here: the cost zeroes its storage itself. (An array new of a type
    // with a trivial destructor adds no cookie.)
    double* values = new (at + detail::arena_round(sizeof(Paper6CostView))) double[count];
    cost_ = new (at) Paper6CostView(Span<double>(values, count), kMaxLinkLengths);
    return cost_;
  }

  unsigned char* arena_ = nullptr;  // the caller's
  std::size_t samples_ = 0;
  Trace<TraceCapacity> traces_[kMaxCalibrationStages];
  CalibrationOutlierList outlier_lists_[2];
  std::uint32_t subset_[kMaxPopulationSubset] = {};
  Paper6CostView* cost_ = nullptr;  // the open phase's objects, built in the arena
  Abc* abc_ = nullptr;
  Gsa* gsa_ = nullptr;
  LmWorkspace* lm_ = nullptr;
  LmResult* lm_result_ = nullptr;
  ReliabilityWorkspace* reliability_ = nullptr;
};

}  // namespace hivecal
