// Capture calibration image: reads a robot and a tracker capture from the host through
// semihosting (two passes: clock sync, sample extraction; lib's capture_dataset.hpp), runs
// lib's calibration job on them (calibrate(): split, baseline, ABC on the paper-6 cost and/or
// LM on the full model, validation; tests/testkit/golden_capture_job.hpp) and prints the
// results and their digest.
//
//   capture_job <robot.cap> <tracker.cap> golden          the paper's job (ABC 20 x 30, LM);
//                                                          exit 1 unless the digest is
//                                                          kCaptureJobGoldenDigest
//   capture_job <robot.cap> <tracker.cap> lm              the LM-only job; exit 1 unless the
//                                                          digest is kLmJobGoldenDigest
//   capture_job <robot.cap> <tracker.cap> compliance      the LM-only job with compliance (LM, then
//                                                          LM+compliance); exit 1 unless the
//                                                          digest is kComplianceJobGoldenDigest
//   capture_job <robot.cap> <tracker.cap> <SN> <cycles> [clock|extraction|abc|lm|compliance]
//                                                          ABC + LM with any ABC budget, or
//                                                          stopping after a pass, or ABC alone,
//                                                          or LM alone, or LM then LM+compliance;
//                                                          prints the digest
//
// Paths are as QEMU sees them (absolute, or relative to its working directory; no commas).
#include <cstdint>
#include <cstring>

#include "baremetal/board.h"
#include "harness.hpp"
#include "testkit/golden_capture_job.hpp"

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

class SemihostingCaptures final : public CaptureSource {
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

// Static: the workspace (dataset + phase arena) and the report are far too big for a stack, and
// the job's options would take a tenth of it for the whole run.
test::CaptureJobWorkspace workspace;
test::CaptureJobReport report;
test::CaptureJobConfig job_config;
char command_line[256];

/// The settings a command line asks for; false if it is not understood.
bool parse_config(char** words, int count, test::CaptureJobConfig* config, std::uint64_t* golden) {
  *golden = 0;
  if (count == 3 && std::strcmp(words[2], "golden") == 0) {
    *config = test::golden_capture_job_config();
    *golden = test::kCaptureJobGoldenDigest;
    return true;
  }
  if (count == 3 && std::strcmp(words[2], "lm") == 0) {
    *config = test::golden_lm_job_config();
    *golden = test::kLmJobGoldenDigest;
    return true;
  }
  if (count == 3 && std::strcmp(words[2], "compliance") == 0) {
    *config = test::golden_compliance_job_config();
    *golden = test::kComplianceJobGoldenDigest;
    return true;
  }
  if (count != 4 && count != 5) return false;
  *config = test::golden_capture_job_config();
  config->calibration.abc_food_sources = parse_size(words[2]);
  config->calibration.abc_cycles = parse_size(words[3]);
  if (count == 5) {
    const char* stop = words[4];
    if (std::strcmp(stop, "clock") == 0) config->stop_after = test::JobStop::clock;
    if (std::strcmp(stop, "extraction") == 0) config->stop_after = test::JobStop::extraction;
    if (std::strcmp(stop, "abc") == 0) config->calibration.method = CalibrationMethod::abc;
    if (std::strcmp(stop, "lm") == 0) config->calibration.method = CalibrationMethod::lm;
    if (std::strcmp(stop, "compliance") == 0) {
      config->calibration.method = CalibrationMethod::lm;
      config->calibration.compliance.enabled = true;
    }
  }
  return true;
}

void print_results(const test::CaptureJobConfig& config, Status status) {
  const CalibrationResult& c = report.calibration;
  const CalibrationStage* abc = test::find_stage(c, CalibrationSolver::abc);
  const CalibrationStage* final_stage = c.final_stage();
  line("robot joint states: ", report.capture.decoding.robot_decoder.joint_states);
  line("tracker points: ", report.capture.decoding.tracker_decoder.tracker_points);
  line("clock offset at reference [us]: ", report.capture.clock.offset_at_reference_us);
  line("clock drift: ", report.capture.clock.drift);
  line("clock drift sigma: ", report.capture.clock.sigma_drift);
  line("clock offset at reference sigma [us]: ", report.capture.clock.sigma_offset_at_reference_us);
  line("samples kept: ", static_cast<std::uint64_t>(report.samples));
  line("training samples: ", static_cast<std::uint64_t>(c.train_count));
  print("method: ");
  print(calibration_method_name(config.calibration.method));
  print("\n");
  if (abc != nullptr) {
    line("ABC food sources: ", static_cast<std::uint64_t>(config.calibration.abc_food_sources));
    line("ABC cycles: ", static_cast<std::uint64_t>(config.calibration.abc_cycles));
    line("ABC evaluations: ", abc->evaluations);
    line("ABC best training MAE [m]: ", abc->best_cost_m);
  }
  if (c.has_lm) {
    line("LM iterations: ", static_cast<std::uint64_t>(c.lm.iterations));
    line("LM parameters estimated: ", static_cast<std::uint64_t>(c.lm.identifiability.kept_count()));
    line("LM RMS [m]: ", c.lm.rms_m);
  }
  line("test MAE nominal [m]: ", c.baseline.test.mae(ErrorAxis::norm_3d));
  if (final_stage != nullptr && final_stage->compliance && c.stage_count > 1) {  // LM, then LM+compliance
    line("test MAE LM [m]: ", c.stages[c.stage_count - 2].test.mae(ErrorAxis::norm_3d));
  }
  if (final_stage != nullptr) line("test MAE calibrated [m]: ", final_stage->test.mae(ErrorAxis::norm_3d));
  print("capture pass: ");
  print_unsigned(static_cast<std::uint64_t>(report.capture.pass));
  print(" (2 = done), job step: ");
  print(calibration_step_name(c.step));
  print(", status: ");
  print(status_message(status));
  print("\ncapture job digest: ");
  print_hex(report.digest);
  print("\n");
}

void print_memory() {
  line("static: dataset [bytes]: ", static_cast<std::uint64_t>(sizeof workspace.dataset));
  line("static: arena [bytes]: ", static_cast<std::uint64_t>(sizeof workspace.arena));
  line("  capture workspace (clock estimator | sample extractor) [bytes]: ",
       static_cast<std::uint64_t>(sizeof(test::JobCaptureWorkspace)));
  line("  calibration workspace [bytes]: ", static_cast<std::uint64_t>(sizeof(test::JobCalibrationWorkspace)));
  line("    ABC phase: Paper6Cost<512, float> + AbcSolver<150, 6> [bytes]: ",
       static_cast<std::uint64_t>(sizeof(test::JobCalibrationWorkspace::AbcPhase)));
  line("    LM phase: LmWorkspace [bytes]: ",
       static_cast<std::uint64_t>(sizeof(test::JobCalibrationWorkspace::LmPhase)));
  line("static: report incl. CalibrationResult [bytes]: ", static_cast<std::uint64_t>(sizeof report));
  print("stack high-water: ");
  print_unsigned(board_stack_used_bytes());
  print(" of ");
  print_unsigned(board_stack_size_bytes());
  print(" bytes\n");
}

}  // namespace
}  // namespace hivecal

int main() {
  using namespace hivecal;
  std::strncpy(command_line, board_command_line(), sizeof command_line - 1);
  char* words[5] = {};
  const int count = split_words(command_line, words, 5);
  std::uint64_t golden = 0;
  if (!parse_config(words, count, &job_config, &golden)) {
    print(
        "usage: capture_job <robot.cap> <tracker.cap> golden | lm | compliance | <food sources> <cycles> "
        "[clock|extraction|abc|lm|compliance]\n");
    return 1;
  }
  SemihostingCaptures captures(words[0], words[1]);
  const Status status = test::run_capture_job(captures, job_config, &workspace, &report);
  print_results(job_config, status);
  print_memory();
  if (status != Status::ok) return 1;
  if (golden != 0) {
    const bool same = report.digest == golden;
    print(same ? "digest matches the host's\n" : "DIGEST DIFFERS from the golden ");
    if (!same) {
      print_hex(golden);
      print("\n");
    }
    return same ? 0 : 1;
  }
  return 0;
}
