// Text inputs against careless and hostile files (issue 13): a NUL byte or an over-long line
// is an error naming file:line, never a dropped or merged row; devices and FIFOs are refused
// at once; what a message quotes from the file is escaped and cut.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"
#include "textio/delimited.hpp"
#include "textio/logs.hpp"

namespace hivecal::textio {
namespace {


const std::string kHeader = "q1,q2,q3,q4,q5,q6\n";

TEST(TextInputs, NulByteInARowNamesFileAndLine) {
  const test::TempDir dir("hivecal_textio_inputs");
  const std::string path = dir.write("nul.csv", kHeader + "0,0,0,0,0,0\n" + std::string("0,0,0\0,0,0,0\n", 13) +
                                                   "0,0,0,0,0,0\n");
  std::vector<JointVector> poses;
  const port::Error error = read_joints_csv(path, &poses);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_NE(error.message.find("nul.csv:3: binary byte 0x00"), std::string::npos) << error.message;
}

TEST(TextInputs, OverLongLineIsAnErrorNotACut) {
  const test::TempDir dir("hivecal_textio_inputs");
  const std::string path = dir.write("long.csv", kHeader + std::string(kMaxLineBytes + 10, '1') + "\n");
  std::vector<JointVector> poses;
  const port::Error error = read_joints_csv(path, &poses);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_NE(error.message.find("long.csv:2: line longer than"), std::string::npos) << error.message;
}

TEST(TextInputs, HugeAndBinaryFieldsAreEscapedAndCutInTheMessage) {
  const test::TempDir dir("hivecal_textio_inputs");
  const std::string path = dir.write("junk.csv", kHeader + "0,0,0,0,0," + std::string(50000, 'a') + "\xff\xfe\n");
  std::vector<JointVector> poses;
  const port::Error error = read_joints_csv(path, &poses);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_LT(error.message.size(), 300u) << error.message.substr(0, 300);
  EXPECT_NE(error.message.find("...[50002 bytes]"), std::string::npos) << error.message;
  const std::string binary = dir.write("bin.csv", kHeader + "0,0,0,0,0,\x1b[31m\x01\n");
  EXPECT_NE(read_joints_csv(binary, &poses).message.find("bin.csv:2: binary byte 0x1b"), std::string::npos);
}

TEST(TextInputs, DevicesAndFifosAreRefusedAtOnce) {
  const test::TempDir dir("hivecal_textio_inputs");
  std::vector<JointVector> poses;
  EXPECT_EQ(read_joints_csv("/dev/zero", &poses).fault, port::Fault::input);
  const std::string fifo = dir.path() + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(read_joints_csv(fifo, &poses).fault, port::Fault::input);  // no writer: would block if opened
  EXPECT_EQ(detect_stream_file(fifo), StreamFileKind::capture);        // and the capture reader refuses it
}

}  // namespace
}  // namespace hivecal::textio
