// Where each sample came from (streams::SessionFacts::sample_sources), so that a blunder the
// calibration job sets aside is reported at its file and line, or its tracker instant: one
// entry per sample, in the order of Sample::index.
#include <gtest/gtest.h>

#include <string>

#include "hivecal/model/dataset.hpp"
#include "streams/session.hpp"
#include "testkit/temp_dir.hpp"

namespace hivecal::sample_sources_test {
namespace {

TEST(SampleSources, PairedSamplesAreNamedByFileAndLine) {
  test::TempDir dir;
  const std::string path = dir.write("pairs.csv",
                                     "q1,q2,q3,q4,q5,q6,x,y,z\n"
                                     "0,0,0,0,0,0,1,2,3\n"
                                     "\n"
                                     "0.1,0,0,0,0,0,1,2,3\n"
                                     "0.2,0,0,0,0,0,1,2,3\n");
  static Dataset<16> dataset;
  dataset.clear();
  streams::SessionFacts facts;
  const port::Error error = streams::load_session({path, "", ""}, streams::SessionConfig{}, &dataset, &facts);
  ASSERT_TRUE(error.ok()) << error.message;
  ASSERT_EQ(dataset.size(), 3u);
  ASSERT_EQ(facts.sample_sources.size(), 3u);
  EXPECT_EQ(facts.sample_sources[0], path + ":2");
  EXPECT_EQ(facts.sample_sources[1], path + ":4");  // the blank line 3 holds no sample
  EXPECT_EQ(facts.sample_sources[2], path + ":5");
  for (const Sample& s : dataset.samples()) EXPECT_EQ(s.index, &s - dataset.samples().data());
}

TEST(SampleSources, StreamSamplesAreNamedByTheirTrackerInstant) {
  const std::string session = HIVECAL_FW_SESSION_DIR;
  static Dataset<1024> dataset;
  dataset.clear();
  streams::SessionConfig config;
  config.speed_model = nominal_model(RobotType::ur5);
  config.speed_model.tool_m = Vec3(0.0, 0.0, 0.1695);
  streams::SessionFacts facts;
  const port::Error error =
      streams::load_session({"", session + "/robot.cap", session + "/tracker.cap"}, config, &dataset, &facts);
  ASSERT_TRUE(error.ok()) << error.message;
  ASSERT_GT(dataset.size(), 100u);
  ASSERT_EQ(facts.sample_sources.size(), dataset.size());
  const std::string prefix = session + "/tracker.cap tracker point at t = ";
  for (const std::string& source : facts.sample_sources) EXPECT_EQ(source.rfind(prefix, 0), 0u) << source;
  EXPECT_NE(facts.sample_sources.front(), facts.sample_sources.back());
}

}  // namespace
}  // namespace hivecal::sample_sources_test
