// Hosted tests: running a subcommand's entry point in-process, and a scratch folder.
#pragma once

#include <stdlib.h>

#include <string>
#include <vector>

namespace hivecal::test {

/// Runs an entry point with the given arguments (after the command name).
template <typename Main>
int run(Main entry, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return entry(static_cast<int>(argv.size()), argv.data());
}

/// A fresh folder for one test's files (in the working directory).
inline std::string make_temp_dir(const char* prefix = "hivecal_cmd") {
  std::string pattern = std::string(prefix) + "_XXXXXX";
  return ::mkdtemp(pattern.data()) != nullptr ? pattern : std::string();
}

}  // namespace hivecal::test
