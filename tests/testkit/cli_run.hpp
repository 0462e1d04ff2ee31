// Hosted tests: running a subcommand's entry point in-process, and a scratch folder.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <string>
#include <utility>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/json.hpp"

namespace hivecal::test {

/// Runs an entry point with the given arguments (after the command name).
template <typename Main>
int run(Main entry, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return entry(static_cast<int>(argv.size()), argv.data());
}

/// A text file a command wrote (a result, a prediction), whole; a gtest failure if unreadable.
inline std::string read_text_file(const std::string& file) {
  std::string text;
  EXPECT_TRUE(port::read_whole_file(file, port::kMaxTextInputBytes, &text).ok()) << file;
  return text;
}

/// A JSON file a command wrote (a result, a report's data), parsed; a gtest failure otherwise.
inline textio::JsonValue read_json_file(const std::string& file) {
  textio::JsonValue root;
  EXPECT_TRUE(textio::parse_json(read_text_file(file), &root).ok()) << file;
  return root;
}

/// A command line the entry point must refuse: the options added and a part of its message.
struct Refusal {
  std::vector<std::string> options;  ///< added to the common arguments
  std::string message;               ///< what stderr must contain
};

/// Runs `entry` with `common` + each refusal's options: each must exit with the usage code and
/// print its message (a gtest failure names the options otherwise).
template <typename Main>
void expect_refusals(Main entry, const std::vector<std::string>& common, const std::vector<Refusal>& refusals);

/// The same, with what the entry point wrote to stderr into *err.
template <typename Main>
int run_capturing_stderr(Main entry, std::vector<std::string> args, std::string* err) {
  ::testing::internal::CaptureStderr();
  const int code = run(entry, std::move(args));
  *err = ::testing::internal::GetCapturedStderr();
  return code;
}

template <typename Main>
void expect_refusals(Main entry, const std::vector<std::string>& common, const std::vector<Refusal>& refusals) {
  for (const Refusal& refusal : refusals) {
    std::vector<std::string> args = common;
    args.insert(args.end(), refusal.options.begin(), refusal.options.end());
    std::string err;
    const int code = run_capturing_stderr(entry, args, &err);
    std::string shown;
    for (const std::string& o : refusal.options) shown += o + " ";
    EXPECT_EQ(code, cli::kExitUsage) << shown;
    EXPECT_NE(err.find(refusal.message), std::string::npos) << shown << ": " << err;
  }
}

}  // namespace hivecal::test
