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

namespace hivecal::textio::textio_inputs_test {
namespace {

const std::string kHeader = "q1,q2,q3,q4,q5,q6\n";

TEST(TextInputs, NulByteInARowNamesFileAndLine) {
  const test::TempDir dir("hivecal_textio_inputs");
  const std::string path =
      dir.write("nul.csv", kHeader + "0,0,0,0,0,0\n" + std::string("0,0,0\0,0,0,0\n", 13) + "0,0,0,0,0,0\n");
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
}  // namespace hivecal::textio::textio_inputs_test

namespace hivecal::textio::textio_inputs_test {
namespace {

// A lab's export as it is: ';' separated, decimal commas, named columns in another order,
// extra columns (a spreadsheet-mangled timestamp among them), ROS joint names.
const std::string kLabExport =
    "Timestamp;Goal x;measurement_x;shoulder_pan_joint;shoulder_lift_joint;elbow_joint;wrist_1_joint;"
    "wrist_2_joint;wrist_3_joint;measurement_y;measurement_z;measurement_std_x\n"
    "2,02011E+13;0,4;383,76294;0,1;-1,5;1,2;-0,5;1,25;0;-3240,8734;201,93157;0,031\n"
    "2,02011E+13;0,4;-0,50720828;-0,908775;-0,052173;-1,92746;-1,16213;-2,05921;-0,000837151;-3343,1516;-426,95;0,01\n";

TEST(TextInputs, ALabExportReadsAsItIsWithNamedColumnsAndDecimalCommas) {
  const test::TempDir dir("hivecal_textio_export");
  const std::string path = dir.write("export.csv", kLabExport);
  InputUnits units;
  units.length = "mm";
  units.columns = {{"x", "measurement_x", ""}, {"y", "measurement_y", ""}, {"z", "measurement_z", ""}};
  Dataset<8> dataset;
  std::vector<std::size_t> lines;
  const port::Error error = read_samples_csv(path, &dataset, units, &lines);
  ASSERT_TRUE(error.ok()) << error.message;
  ASSERT_EQ(dataset.size(), 2u);
  const Sample& second = dataset.samples()[1];
  EXPECT_EQ(second.q_rad(0), -0.908775);
  EXPECT_EQ(second.q_rad(5), -0.000837151);
  EXPECT_EQ(second.point_m(0), -0.50720828 * 1e-3);
  EXPECT_EQ(second.point_m(1), -3343.1516 * 1e-3);
  EXPECT_EQ(second.point_m(2), -426.95 * 1e-3);
  EXPECT_EQ(lines, (std::vector<std::size_t>{2, 3}));
}

TEST(TextInputs, AnExportWithoutItsColumnsNamedSaysWhichAreMissing) {
  const test::TempDir dir("hivecal_textio_export");
  const std::string path = dir.write("export.csv", kLabExport);
  Dataset<8> dataset;
  InputUnits units;
  units.length = "mm";
  port::Error error = read_samples_csv(path, &dataset, units);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_NE(error.message.find("not found: x, y, z; name them with --columns"), std::string::npos) << error.message;
  units.columns = {{"x", "measurement_x", ""}, {"y", "measurement_y", ""}, {"z", "no_such_column", ""}};
  dataset.clear();
  error = read_samples_csv(path, &dataset, units);
  EXPECT_EQ(error.fault, port::Fault::usage);  // the option names a column the file lacks
  EXPECT_NE(error.message.find("--columns 'z=no_such_column': no column 'no_such_column' in the header of"),
            std::string::npos)
      << error.message;
  // Without a length unit the millimetres are refused with the hint, as for any text input.
  units.length.clear();
  units.columns.back().header = "measurement_z";
  dataset.clear();
  error = read_samples_csv(path, &dataset, units);
  EXPECT_NE(error.message.find("--length-unit mm"), std::string::npos) << error.message;
}

TEST(TextInputs, ACommaSeparatedFileStillRefusesDecimalCommas) {
  // With ',' as the separator a decimal comma cannot be told from a field boundary.
  const test::TempDir dir("hivecal_textio_export");
  const std::string path = dir.write("c.csv", "q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,\"1,5\",0,0\n");
  Dataset<8> dataset;
  EXPECT_FALSE(read_samples_csv(path, &dataset).ok());
}

}  // namespace
}  // namespace hivecal::textio::textio_inputs_test
