// `hivecal iso9283`'s grouping of the reaches into poses (apps/commands/iso9283.hpp): the same
// poses as comparing every sample with every pose, in work linear in the samples (issue 54 H5:
// 100k poses took 36 s, 10^6 rows 15-30 min).
#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

#include "commands/iso9283.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"

namespace hivecal::iso9283_command_test {
namespace {

/// The grouping by definition: a sample joins the latest pose whose first reach is the same
/// point, else starts one (every sample against every pose).
std::vector<cli::PoseReaches> group_by_definition(const std::vector<Sample>& samples) {
  std::vector<cli::PoseReaches> poses;
  for (const Sample& s : samples) {
    cli::PoseReaches* pose = nullptr;
    for (cli::PoseReaches& p : poses)
      if (same_point(p.first, s)) pose = &p;
    if (pose == nullptr) {
      poses.push_back(cli::PoseReaches{s, 0, {}});
      pose = &poses.back();
    }
    pose->measured_m.push_back(s.point_m);
  }
  return poses;
}

Sample sample_at(const JointVector& q_rad, std::size_t index, int target) {
  Sample s;
  s.q_rad = q_rad;
  s.point_m = Vec3(static_cast<double>(index), 0.0, 0.0);  // tells the reaches apart
  s.index = static_cast<std::uint32_t>(index);
  s.target = target;
  return s;
}

// Reaches jittered up to 1.3x the tolerance (some are poses of their own, some match two
// poses), poses on and around the cells' edges, two targets: the same poses, first reaches
// and reaches in the same order as by definition.
TEST(Iso9283Grouping, SamePosesAsEverySampleAgainstEveryPose) {
  Random random(54);
  std::vector<JointVector> commands;
  for (int k = 0; k < 40; ++k) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) {
      // Half the poses on a multiple of the cell width (4 tolerances) or a tolerance beside it.
      const double edge = 4.0 * kSamePoseTolerance_rad * static_cast<double>(random.next() % 2000) - 4.0;
      q(j) = k % 2 == 0
                 ? edge + kSamePoseTolerance_rad * static_cast<double>(random.next() % 3) - kSamePoseTolerance_rad
                 : random.uniform(-3.0, 3.0);
    }
    commands.push_back(q);
  }
  // Near neighbours: poses within two tolerances of another, so that a reach can match both.
  for (int k = 0; k < 10; ++k) {
    JointVector q = commands[static_cast<std::size_t>(k)];
    q(k % kSixJoints) += 1.5 * kSamePoseTolerance_rad;
    commands.push_back(q);
  }
  std::vector<Sample> samples;
  for (int cycle = 0; cycle < 6; ++cycle) {
    for (const JointVector& command : commands) {
      JointVector q = command;
      for (int j = 0; j < kSixJoints; ++j) q(j) += random.uniform(-1.3, 1.3) * kSamePoseTolerance_rad;
      samples.push_back(sample_at(q, samples.size(), cycle % 3 == 2 ? 1 : 0));
    }
  }
  const std::vector<cli::PoseReaches> expected = group_by_definition(samples);
  const std::vector<cli::PoseReaches> grouped =
      cli::group_reaches(Span<const Sample>(samples.data(), samples.size()), {}, kSixJoints);
  ASSERT_GT(expected.size(), commands.size() * 2);  // the jitter made poses of their own
  ASSERT_EQ(grouped.size(), expected.size());
  for (std::size_t p = 0; p < expected.size(); ++p) {
    EXPECT_EQ(grouped[p].first.index, expected[p].first.index) << p;
    ASSERT_EQ(grouped[p].measured_m.size(), expected[p].measured_m.size()) << p;
    for (std::size_t r = 0; r < expected[p].measured_m.size(); ++r)
      EXPECT_EQ(grouped[p].measured_m[r], expected[p].measured_m[r]) << p << " " << r;
  }
}

// 20,000 poses reached three times (60,000 samples): every sample against every pose makes
// ~10^9 comparisons; the cells make a few per sample.
TEST(Iso9283Grouping, WorkIsLinearInTheSamples) {
  Random random(9283);
  std::vector<JointVector> commands(20000);
  for (JointVector& q : commands)
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-3.0, 3.0);
  std::vector<Sample> samples;
  for (int cycle = 0; cycle < 3; ++cycle)
    for (const JointVector& q : commands) samples.push_back(sample_at(q, samples.size(), 0));
  std::size_t comparisons = 0;
  const std::vector<cli::PoseReaches> grouped =
      cli::group_reaches(Span<const Sample>(samples.data(), samples.size()), {}, kSixJoints, &comparisons);
  ASSERT_EQ(grouped.size(), commands.size());
  for (const cli::PoseReaches& pose : grouped) EXPECT_EQ(pose.measured_m.size(), 3u);
  EXPECT_LE(comparisons, 2 * samples.size());
}

// A seven-joint arm's poses that differ in the seventh joint alone are told apart by its cells
// too: the work stays linear (cells of six joints put them all in one).
TEST(Iso9283Grouping, TheCellsHoldEveryJointOfTheArm) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  Random random(7);
  std::vector<JointVector> commands(3000, JointVector::Zero());
  for (JointVector& q : commands) q(6) = random.uniform(-3.0, 3.0);
  std::vector<Sample> samples;
  for (int cycle = 0; cycle < 3; ++cycle)
    for (const JointVector& q : commands) samples.push_back(sample_at(q, samples.size(), 0));
  std::size_t comparisons = 0;
  const std::vector<cli::PoseReaches> grouped =
      cli::group_reaches(Span<const Sample>(samples.data(), samples.size()), {}, 7, &comparisons);
  const std::vector<cli::PoseReaches> expected = group_by_definition(samples);
  ASSERT_EQ(grouped.size(), expected.size());
  for (std::size_t p = 0; p < expected.size(); ++p) EXPECT_EQ(grouped[p].first.index, expected[p].first.index) << p;
  EXPECT_LE(comparisons, 2 * samples.size());
}

}  // namespace
}  // namespace hivecal::iso9283_command_test
