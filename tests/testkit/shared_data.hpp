// Reference data kept outside the repository (real-controller readings, real sessions): the
// folder HIVECAL_TEST_DATA_DIR (CMake cache, default ../shared/data beside the checkout). It is
// optional: a test that needs a file of it skips, naming the file, when the file is absent.
#pragma once

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <string>

namespace hivecal::test {

/// `relative` under the reference data folder (a path, whether or not the file exists).
inline std::string shared_data_path(const std::string& relative) {
  return std::string(HIVECAL_TEST_DATA_DIR) + "/" + relative;
}

/// Whether `path` names an existing file or folder.
inline bool path_exists(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0;
}

}  // namespace hivecal::test

/// Skips the current test (it does not fail) unless `relative` exists under the reference data.
#define HIVECAL_SKIP_WITHOUT_SHARED_DATA(relative)                                                                 \
  do {                                                                                                             \
    const std::string hivecal_needed_ = ::hivecal::test::shared_data_path(relative);                               \
    if (!::hivecal::test::path_exists(hivecal_needed_)) GTEST_SKIP() << "needs " << hivecal_needed_ << ": absent"; \
  } while (0)
