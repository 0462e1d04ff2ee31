// Writes N paired samples (q1..q6,x,y,z) of a simulated UR5 with 0.1 mm / 0.1 mrad geometry
// errors, random joints and 10 um tracker noise, seen from the test kit's tracker frame: the
// large sets scripts/bench-large.sh times the job on.
//   make_samples N [SEED] > samples.csv
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hivecal/core/random.hpp"
#include "testkit/test_data.hpp"
#include "textio/csv.hpp"

int main(int argc, char** argv) {
  const long count = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 0;
  if (count <= 0 || count > 10000000) {
    std::fprintf(stderr, "usage: make_samples N [SEED]   (N in 1..10000000)\n");
    return 2;
  }
  const unsigned long long seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
  std::vector<hivecal::Sample> storage(static_cast<std::size_t>(count));
  hivecal::DatasetView dataset{hivecal::Span<hivecal::Sample>(storage.data(), storage.size())};
  hivecal::Random random(seed);
  const hivecal::RobotModel truth =
      hivecal::test::perturbed_model(hivecal::nominal_model(hivecal::RobotType::ur5), &random, 1e-4, 1e-4);
  hivecal::test::fill_dataset(truth, hivecal::test::example_base_to_tracker(), storage.size(), 10e-6, &random,
                              &dataset);
  const std::string text = hivecal::textio::format_samples_csv(dataset.samples(), hivecal::kSixJoints);
  return std::fwrite(text.data(), 1, text.size(), stdout) == text.size() ? 0 : 1;
}
