// The extraction's golden digest: the same bits on every target and -O level (the golden
// scope, tests/CMakeLists.txt, builds only the test_*golden*.cpp files).
#include <gtest/gtest.h>

#include <cstdio>

#include "hivecal/core/digest.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "sim/sim_model.hpp"
#include "testkit/sim_feed.hpp"

namespace hivecal::extraction_golden_test {
namespace {

using test::large_error_config;

// Golden digest: simulated session -> estimated clock -> extracted samples, hashed over
// the raw bits. Must be the same on every target (host -O0/-O3/native, aarch64, armhf).
constexpr std::uint64_t kExtractionGoldenDigest = 0x7acfa56177acf795ULL;

std::uint64_t extraction_digest() {
  const sim::Session session(large_error_config(25, 12, 150.0));
  static ClockEstimator<16384, 4096> estimator(make_clock_sync_config(session.truth().nominal));
  estimator.reset();
  test::feed_clock(session, &estimator);
  ClockFit fit;
  Digest digest;
  digest.add_u64(static_cast<std::uint64_t>(estimator.estimate(&fit)));
  for (double v : {fit.offset_us, fit.drift, fit.reference_tracker_us, fit.offset_at_reference_us,
                   fit.sigma_offset_at_reference_us, fit.sigma_drift, fit.speed_gain, fit.residual_rms_m})
    digest.add(v);
  static Dataset<> dataset;
  dataset.clear();
  static SampleExtractor<> extractor(make_extraction_config(session.truth().nominal), fit, &dataset);
  extractor.reset(make_extraction_config(session.truth().nominal), fit, &dataset);
  (void)test::feed_extractor(session, &extractor);
  for (const Sample& s : dataset.samples()) {
    digest.add(s.q_rad.head(kSixJoints));
    digest.add(s.point_m);
  }
  digest.add_u64(extractor.counts().kept);
  for (const std::uint64_t n : extractor.counts().dropped) digest.add_u64(n);
  return digest.value();
}

TEST(Golden, ExtractionDigestIsTheSameOnEveryTarget) {
  const std::uint64_t digest = extraction_digest();
  std::printf("extraction digest: 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kExtractionGoldenDigest);
}

}  // namespace
}  // namespace hivecal::extraction_golden_test
