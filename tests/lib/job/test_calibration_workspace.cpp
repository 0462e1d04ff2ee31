// The job's workspace (job/calibration_workspace.hpp): a workspace sized at run time
// (CalibrationWorkspaceView over the caller's arena) and a dataset that grows
// (DatasetBase::grow) give the same bits as the fixed-capacity types, no heap in the library,
// and the errors of a bad arena.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/quick_job.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::calibration_workspace_test {
namespace {

constexpr std::size_t kSamples = 400;
using View = CalibrationWorkspaceView<20, 100>;
using Fixed = CalibrationWorkspace<kSamples, double, 20, 100, kSamples, kMaxLinkLengths>;

/// A dataset over pools of growing size, as a host program's would be over the heap: it
/// starts with room for 8 samples and doubles (here from static pools, no heap).
class PoolDataset final : public DatasetBase {
 public:
  PoolDataset() : DatasetBase(pool_a_, 8) {}
  int grown = 0;

 protected:
  bool grow(std::size_t needed) override {
    Sample* next = (grown % 2 == 0) ? pool_b_ : pool_a_;
    const std::size_t room = std::size_t{8} << (grown + 1);
    if (room < needed || room > kPool || !move_to(next, room)) return false;
    ++grown;
    return true;
  }

 private:
  static constexpr std::size_t kPool = 1024;
  Sample pool_a_[kPool];
  Sample pool_b_[kPool];
};

void fill(std::size_t count, DatasetBase* out) {
  Random random(11);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  out->clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), count, 10e-6, &random, out);
}

/// `bytes` bytes aligned to std::max_align_t inside *storage (resized to hold them).
unsigned char* aligned_room(std::vector<unsigned char>* storage, std::size_t bytes) {
  storage->assign(bytes + alignof(std::max_align_t), 0);
  const std::size_t misalignment = reinterpret_cast<std::uintptr_t>(storage->data()) % alignof(std::max_align_t);
  return storage->data() + (misalignment == 0 ? 0 : alignof(std::max_align_t) - misalignment);
}

bool same_bits(const CalibrationResult& a, const CalibrationResult& b) {
  if (a.stage_count != b.stage_count) return false;
  for (std::size_t k = 0; k < a.stage_count; ++k) {
    const ModelParams pa = to_params(a.stages[k].model);
    const ModelParams pb = to_params(b.stages[k].model);
    if (std::memcmp(pa.data(), pb.data(), sizeof(double) * model_param_count(kSixJoints)) != 0) return false;
    if (std::memcmp(&a.stages[k].test, &b.stages[k].test, sizeof(ErrorStats)) != 0) return false;
  }
  return true;
}

TEST(CalibrationWorkspaceView, HasTheBitsOfTheFixedWorkspaceWithoutHeap) {
  static Dataset<kSamples> dataset;
  static Fixed fixed;
  static View view;
  static CalibrationResult expected;
  static CalibrationResult result;
  std::vector<unsigned char> bytes;
  unsigned char* aligned = aligned_room(&bytes, View::arena_bytes(kSamples));
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = view.attach(Span<unsigned char>(aligned, View::arena_bytes(kSamples)), kSamples));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(view.samples(), kSamples);
  for (const CalibrationMethod method : {CalibrationMethod::abc_lm, CalibrationMethod::all}) {
    const CalibrationOptions options = test::quick_options(method);
    fill(kSamples, &dataset);  // 280 training samples: the hybrid searches on a subset
    ASSERT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &fixed, &expected), Status::ok);
    fill(kSamples, &dataset);
    EXPECT_NO_HEAP(status = calibrate(nominal_model(RobotType::ur5), &dataset, options, &view, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    EXPECT_TRUE(same_bits(expected, result)) << calibration_method_name(method);
    EXPECT_EQ(result.stages[0].searched_samples, method == CalibrationMethod::abc_lm ? kDefaultPopulationSubset : 280u);
  }
}

TEST(CalibrationWorkspaceView, RefusesABadArenaAndAnUnattachedOneFailsCleanly) {
  static View view;
  alignas(std::max_align_t) static unsigned char small[64];
  EXPECT_EQ(view.attach(Span<unsigned char>(small), 10), Status::invalid_argument);  // too small
  std::vector<unsigned char> bytes(View::arena_bytes(10) + 32);
  unsigned char* odd = bytes.data() + (reinterpret_cast<std::uintptr_t>(bytes.data()) % 2 == 0 ? 1 : 0);
  EXPECT_EQ(view.attach(Span<unsigned char>(odd, View::arena_bytes(10)), 10), Status::invalid_argument);  // misaligned
  EXPECT_EQ(view.attach(Span<unsigned char>(small), 0), Status::invalid_argument);                        // no samples
  EXPECT_EQ(view.samples(), 0u);
  EXPECT_EQ(view.open_abc().cost, nullptr);
  EXPECT_EQ(view.open_lm(), nullptr);
  EXPECT_EQ(view.open_lm_scratch().lm, nullptr);
  EXPECT_EQ(view.open_lm_scratch().result, nullptr);
  static Dataset<60> dataset;
  fill(60, &dataset);
  static CalibrationResult result;
  EXPECT_NE(calibrate(nominal_model(RobotType::ur5), &dataset, CalibrationOptions{}, &view, &result), Status::ok);
  // More samples than attached for: the population stage's cost says so instead of writing
  // past the arena (LM only computes the joint trig per pass and screens what fits).
  std::vector<unsigned char> room;
  unsigned char* aligned = aligned_room(&room, View::arena_bytes(16));
  ASSERT_EQ(view.attach(Span<unsigned char>(aligned, View::arena_bytes(16)), 16), Status::ok);
  CalibrationOptions options;
  options.method = CalibrationMethod::abc;
  options.abc_food_sources = 10;
  options.abc_cycles = 2;
  EXPECT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &view, &result), Status::dataset_full);
  options.method = CalibrationMethod::lm;
  EXPECT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &view, &result), Status::ok);
}

TEST(DatasetGrowth, ADatasetThatGrowsKeepsEverySampleAndItsSetAsideOnes) {
  static PoolDataset grown;
  static Dataset<600> fixed;
  fill(600, &fixed);
  for (const Sample& s : fixed.samples()) {
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = grown.add(s.q_rad, s.point_m, s.target));
    ASSERT_EQ(status, Status::ok);
  }
  EXPECT_EQ(grown.grown, 7);  // 8 -> 1024
  EXPECT_EQ(grown.capacity(), 1024u);
  ASSERT_EQ(grown.size(), 600u);
  for (std::size_t i = 0; i < 600; ++i) EXPECT_EQ(grown.samples()[i].point_m, fixed.samples()[i].point_m);
  const std::uint32_t aside[] = {3, 500};
  grown.set_aside(Span<const std::uint32_t>(aside));
  EXPECT_EQ(grown.size(), 598u);
  // Past the largest pool: dataset_full, nothing lost.
  for (std::size_t i = 600; i < 1024; ++i) ASSERT_EQ(grown.add(JointVector::Zero(), Vec3::Zero()), Status::ok);
  EXPECT_EQ(grown.add(JointVector::Zero(), Vec3::Zero()), Status::dataset_full);
  EXPECT_EQ(grown.size(), 1024u);  // add() brought the set-aside ones back
  static Sample storage[5];
  DatasetView view{Span<Sample>(storage)};
  EXPECT_EQ(view.capacity(), 5u);
  for (int i = 0; i < 5; ++i) ASSERT_EQ(view.add(JointVector::Constant(i), Vec3::Constant(i)), Status::ok);
  EXPECT_EQ(view.add(JointVector::Zero(), Vec3::Zero()), Status::dataset_full);
}

}  // namespace
}  // namespace hivecal::calibration_workspace_test
