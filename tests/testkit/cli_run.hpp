// Hosted tests: running a subcommand's entry point in-process, and a scratch folder.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <string>
#include <utility>
#include <vector>

#include "testkit/temp_dir.hpp"

namespace hivecal::test {

/// Runs an entry point with the given arguments (after the command name).
template <typename Main>
int run(Main entry, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return entry(static_cast<int>(argv.size()), argv.data());
}

/// The same, with what the entry point wrote to stderr into *err.
template <typename Main>
int run_capturing_stderr(Main entry, std::vector<std::string> args, std::string* err) {
  ::testing::internal::CaptureStderr();
  const int code = run(entry, std::move(args));
  *err = ::testing::internal::GetCapturedStderr();
  return code;
}

}  // namespace hivecal::test
