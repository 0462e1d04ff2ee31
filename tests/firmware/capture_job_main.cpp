// Capture calibration image: reads a robot and a tracker capture from the host through
// semihosting (two passes), runs the whole job of tests/support/capture_job.hpp (clock sync,
// sample extraction, ABC on the paper-6 cost, LM on the full model, validation) and prints
// the results and their digest.
//
//   capture_job <robot.cap> <tracker.cap> golden          golden settings; exit 1 unless the
//                                                          digest is kCaptureJobGoldenDigest
//   capture_job <robot.cap> <tracker.cap> <SN> <cycles> [clock|extraction|abc]
//                                                          any ABC budget, optionally stopping
//                                                          after a stage; prints the digest
//
// Paths are as QEMU sees them (absolute, or relative to its working directory; no commas).
#include <cstdint>
#include <cstring>

#include "baremetal/board.h"
#include "capture_job.hpp"
#include "golden_capture_job.hpp"
#include "harness.hpp"

namespace hivecal {
namespace {

using fw::print;
using fw::print_double;
using fw::print_hex;
using fw::print_unsigned;

/// A host file read through semihosting.
class SemihostingReader final : public ByteReader {
 public:
  Status open(const char* path) {
    if (handle_ >= 0) return board_file_rewind(handle_) == 0 ? Status::ok : Status::read_failed;
    handle_ = board_file_open(path);
    return handle_ >= 0 ? Status::ok : Status::read_failed;
  }
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override {
    const long got = board_file_read(handle_, out, capacity);
    if (got < 0) return Status::read_failed;
    *count = static_cast<std::size_t>(got);
    return Status::ok;
  }

 private:
  int handle_ = -1;
};

class SemihostingCaptures final : public test::CaptureSource {
 public:
  SemihostingCaptures(const char* robot, const char* tracker) : robot_path_(robot), tracker_path_(tracker) {}
  Status open(ByteReader** robot, ByteReader** tracker) override {
    if (robot_.open(robot_path_) != Status::ok || tracker_.open(tracker_path_) != Status::ok) {
      return Status::read_failed;
    }
    *robot = &robot_;
    *tracker = &tracker_;
    return Status::ok;
  }

 private:
  const char* robot_path_;
  const char* tracker_path_;
  SemihostingReader robot_;
  SemihostingReader tracker_;
};

/// Splits the command line in place into at most `max` words.
int split_words(char* line, char** words, int max) {
  int n = 0;
  char* p = line;
  while (*p != '\0' && n < max) {
    while (*p == ' ') *p++ = '\0';
    if (*p == '\0') break;
    words[n++] = p;
    while (*p != '\0' && *p != ' ') ++p;
  }
  return n;
}

std::size_t parse_size(const char* text) {
  std::size_t v = 0;
  for (; *text >= '0' && *text <= '9'; ++text) v = v * 10 + static_cast<std::size_t>(*text - '0');
  return v;
}

void line(const char* label, double value) {
  print(label);
  print_double(value);
  print("\n");
}

void line(const char* label, std::uint64_t value) {
  print(label);
  print_unsigned(value);
  print("\n");
}

// Static: the workspace (dataset + phase arena) and the report are far too big for a stack.
test::CaptureJobWorkspace workspace;
test::CaptureJobReport report;
char command_line[256];

}  // namespace
}  // namespace hivecal

int main() {
  using namespace hivecal;
  std::strncpy(command_line, board_command_line(), sizeof command_line - 1);
  char* words[5] = {};
  const int count = split_words(command_line, words, 5);
  const bool golden = count == 3 && std::strcmp(words[2], "golden") == 0;
  if (!golden && count != 4 && count != 5) {
    print("usage: capture_job <robot.cap> <tracker.cap> golden | <food sources> <cycles> [clock|extraction|abc]\n");
    return 1;
  }
  test::CaptureJobConfig config = test::golden_capture_job_config();
  if (!golden) {
    config.food_sources = parse_size(words[2]);
    config.cycles = parse_size(words[3]);
    if (count == 5) {
      const char* stop = words[4];
      config.stop_after = std::strcmp(stop, "clock") == 0        ? test::JobStage::clock
                          : std::strcmp(stop, "extraction") == 0 ? test::JobStage::extraction
                          : std::strcmp(stop, "abc") == 0        ? test::JobStage::abc
                                                                 : test::JobStage::done;
    }
  }
  SemihostingCaptures captures(words[0], words[1]);
  const Status status = test::run_capture_job(captures, config, &workspace, &report);

  line("robot joint states: ", report.decoding.robot_decoder.joint_states);
  line("tracker points: ", report.decoding.tracker_decoder.tracker_points);
  line("clock offset at reference [us]: ", report.clock.offset_at_reference_us);
  line("clock drift: ", report.clock.drift);
  line("clock drift sigma: ", report.clock.sigma_drift);
  line("clock offset at reference sigma [us]: ", report.clock.sigma_offset_at_reference_us);
  line("samples kept: ", static_cast<std::uint64_t>(report.samples));
  line("training samples: ", static_cast<std::uint64_t>(report.train));
  line("ABC food sources: ", static_cast<std::uint64_t>(config.food_sources));
  line("ABC cycles: ", static_cast<std::uint64_t>(config.cycles));
  line("ABC evaluations: ", report.abc.evaluations);
  line("ABC best training MAE [m]: ", report.abc.best_cost_m);
  line("LM iterations: ", static_cast<std::uint64_t>(report.lm.iterations));
  line("LM parameters estimated: ", static_cast<std::uint64_t>(report.lm.identifiability.kept_count()));
  line("LM RMS [m]: ", report.lm.rms_m);
  line("test MAE nominal [m]: ", report.uncalibrated_test.mae_m[static_cast<int>(ErrorAxis::norm_3d)]);
  line("test MAE calibrated [m]: ", report.calibrated_test.mae_m[static_cast<int>(ErrorAxis::norm_3d)]);
  print("stage reached: ");
  print_unsigned(static_cast<std::uint64_t>(report.stage));
  print(" (5 = done), status: ");
  print(status_message(report.status));
  print("\ncapture job digest: ");
  print_hex(report.digest);
  print("\n");
  line("static: dataset [bytes]: ", static_cast<std::uint64_t>(sizeof workspace.dataset));
  line("static: phase arena [bytes]: ", static_cast<std::uint64_t>(sizeof workspace.arena));
  line("  clock estimator [bytes]: ", static_cast<std::uint64_t>(sizeof(test::JobClockEstimator)));
  line("  sample extractor [bytes]: ", static_cast<std::uint64_t>(sizeof(test::JobExtractor)));
  line("  ABC phase: Paper6Cost<512, float> + AbcSolver<150, 6> + Trace<300> [bytes]: ",
       static_cast<std::uint64_t>(sizeof(test::JobAbcPhase)));
  line("  LM workspace [bytes]: ", static_cast<std::uint64_t>(sizeof(LmWorkspace)));
  line("static: report incl. LmResult [bytes]: ", static_cast<std::uint64_t>(sizeof report));
  print("stack high-water: ");
  print_unsigned(board_stack_used_bytes());
  print(" of ");
  print_unsigned(board_stack_size_bytes());
  print(" bytes\n");
  if (status != Status::ok) return 1;
  if (report.stage != config.stop_after) return 1;
  if (golden) {
    const bool same = report.digest == test::kCaptureJobGoldenDigest;
    print(same ? "digest matches the host's\n" : "DIGEST DIFFERS from kCaptureJobGoldenDigest ");
    if (!same) {
      print_hex(test::kCaptureJobGoldenDigest);
      print("\n");
    }
    return same ? 0 : 1;
  }
  return 0;
}
