// The --columns grammar (issue 52 item 8, issue 54 M5) and the separators of a decimal-comma
// file (issue 54 S10): a column may be a sum of the header's columns with a unit (a lab that
// writes target and difference, measured = target + difference), micrometres as µm, a
// malformed or misnamed --columns blamed on the option, thousands points in a file of decimal
// commas refused instead of read as decimals.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hivecal/core/math.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"
#include "textio/delimited.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio::column_specs_test {
namespace {

/// --columns text into aliases; a gtest failure names the problem.
std::vector<ColumnAlias> aliases(const std::string& text) {
  std::vector<ColumnAlias> parsed;
  const std::string problem = parse_column_aliases(text, &parsed);
  EXPECT_EQ(problem, "") << text;
  return parsed;
}

/// The problem parse_column_aliases finds in `text` ("" when none).
std::string problem_of(const std::string& text) {
  std::vector<ColumnAlias> parsed;
  return parse_column_aliases(text, &parsed);
}

// A target-and-difference export as a lab writes it: the commanded point and the measured
// point's difference from it, both in mm, the joints in degrees, named as the lab names them.
const std::string kTargetAndDifference =
    "step,x_t,y_t,z_t,x_dif,y_dif,z_dif,joint_1,joint_2,joint_3,joint_4,joint_5,joint_6,joint_7\n"
    "0,562.5,-307.25,0.375,8.5,-1.625,4.125,10,-20,30,-40,50,-60,7\n"
    "1,596.25,-308.5,-5.5,8.75,0.875,2.875,11,-21,31,-41,51,-61,7\n";

const char* const kSumSpec =
    "x=x_t+x_dif[mm],y=y_t + y_dif [mm],z=z_t-z_dif[mm],q1=joint_1[deg],q2=joint_2[deg],q3=joint_3[deg],"
    "q4=joint_4[deg],q5=joint_5[deg],q6=joint_6[deg],q7=joint_7[deg]";

/// The units of the seven-joint arm the export is of (revolute joints).
InputUnits seven_joints() {
  InputUnits units;
  units.joints.count = 7;
  return units;
}

TEST(ColumnSpecs, ASumOfColumnsWithAUnitIsTheMeasuredPoint) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir;
  const std::string path = dir.write("grid.csv", kTargetAndDifference);
  InputUnits units = seven_joints();
  units.columns = aliases(kSumSpec);
  ASSERT_EQ(units.columns.size(), 10u);
  EXPECT_EQ(units.columns[1].header, "y_t + y_dif");
  EXPECT_EQ(units.columns[1].unit, "mm");
  Dataset<8> dataset;
  const port::Error error = read_samples_csv(path, &dataset, units);
  ASSERT_TRUE(error.ok()) << error.message;
  ASSERT_EQ(dataset.size(), 2u);
  const Sample& second = dataset.samples()[1];
  EXPECT_EQ(second.point_m.x(), (596.25 + 8.75) * 1e-3);
  EXPECT_EQ(second.point_m.y(), (-308.5 + 0.875) * 1e-3);
  EXPECT_EQ(second.point_m.z(), (-5.5 - 2.875) * 1e-3);  // a minus term
  EXPECT_EQ(second.q_rad(0), 11.0 * math::kRadPerDeg);   // a plain joint spec with a unit still reads
  EXPECT_EQ(second.q_rad(5), -61.0 * math::kRadPerDeg);
  EXPECT_EQ(second.q_rad(6), 7.0 * math::kRadPerDeg);
}

TEST(ColumnSpecs, EveryReaderOfTheColumnSpecTakesSums) {
  // The poses to predict (predict, check-robot) read through the same spec: a joint may be a
  // sum too (a commanded angle and its measured error), and a leading minus flips a column.
  const test::TempDir dir;
  const std::string path = dir.write("poses.csv", "a;b;c;d;e;f;g\n1;0,5;2;3;4;5;6\n");
  InputUnits units;
  units.columns = aliases("q1=a+b[deg],q2=-c[deg],q3=d,q4=e,q5=f,q6=g-f");
  std::vector<JointVector> poses;
  const port::Error error = read_joints_csv(path, &poses, units);
  ASSERT_TRUE(error.ok()) << error.message;
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0](0), 1.5 * math::kRadPerDeg);
  EXPECT_EQ(poses[0](1), -2.0 * math::kRadPerDeg);
  EXPECT_EQ(poses[0](2), 3.0);
  EXPECT_EQ(poses[0](5), 1.0);
}

TEST(ColumnSpecs, AHeaderNameThatHoldsASignIsReadWhole) {
  const test::TempDir dir;
  const std::string path = dir.write("named.csv", "q1,q2,q3,q4,q5,q6,pos-x,y,z\n0,0,0,0,0,0,1,2,3\n");
  InputUnits units;
  units.columns = aliases("x=pos-x");
  Dataset<4> dataset;
  const port::Error error = read_samples_csv(path, &dataset, units);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(dataset.samples()[0].point_m.x(), 1.0);
}

TEST(ColumnSpecs, TheWamGridReadsAsTargetPlusDifference) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("wam-grid/3D_WAM_uncalibrated_grid_cleaned.csv");
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  InputUnits units = seven_joints();
  units.columns = aliases(kSumSpec);
  units.columns[2] = aliases("z=z_t+z_dif[mm]")[0];
  Dataset<256> dataset;
  const port::Error error =
      read_samples_csv(test::shared_data_path("wam-grid/3D_WAM_uncalibrated_grid_cleaned.csv"), &dataset, units);
  ASSERT_TRUE(error.ok()) << error.message;
  ASSERT_EQ(dataset.size(), 216u);
  // Row 0 as the file writes it: x_t 562.9645010692388, x_dif 8.896541930761146, joint_1 111.07183339675662.
  const Sample& first = dataset.samples()[0];
  EXPECT_EQ(first.point_m.x(), (562.9645010692388 + 8.896541930761146) * 1e-3);
  EXPECT_EQ(first.point_m.z(), (0.38066518057890003 + 4.139234819421) * 1e-3);
  EXPECT_EQ(first.q_rad(0), 111.07183339675662 * math::kRadPerDeg);
}

TEST(ColumnSpecs, MicrometresAreAcceptedAsMicroSignOrU) {
  for (const char* spec : {"x=px[\xC2\xB5m]", "x=px[um]", "x=px[\xCE\xBCm]"}) {
    const std::vector<ColumnAlias> parsed = aliases(spec);
    ASSERT_EQ(parsed.size(), 1u) << spec;
    EXPECT_EQ(parsed[0].unit, "um") << spec;
  }
  const test::TempDir dir;
  // The header's own unit, both spellings, and --columns' unit reading a header without one.
  const std::string path =
      dir.write("um.csv", "q1,q2,q3,q4,q5,q6,px,y [\xC2\xB5m],z (\xC2\xB5m)\n0,0,0,0,0,0,1000,2000,3000\n");
  InputUnits units;
  units.columns = aliases("x=px[\xC2\xB5m],y=y,z=z");
  Dataset<4> dataset;
  const port::Error error = read_samples_csv(path, &dataset, units);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(dataset.samples()[0].point_m, Vec3(1000e-6, 2000e-6, 3000e-6));
}

TEST(ColumnSpecs, AMalformedSpecIsBlamedOnTheOptionAndQuoted) {
  EXPECT_EQ(problem_of("x=measurement_x[mm"),
            "--columns: 'x=measurement_x[mm': a unit goes in one pair of brackets at the end, C=NAME[unit] (e.g. "
            "x=measurement_x[mm])");
  EXPECT_EQ(problem_of("x=a++b"),
            "--columns: 'x=a++b': a name is missing in the sum (C=NAME, or C=NAME+NAME-NAME..., e.g. "
            "x=x_t+x_dif[mm])");
  EXPECT_NE(problem_of("x=a+").find("--columns: 'x=a+': a name is missing in the sum"), std::string::npos);
  EXPECT_NE(problem_of("x=a[furlong]").find("--columns: 'x=a[furlong]': unknown unit '[furlong]'"), std::string::npos);
  EXPECT_NE(problem_of("w=a").find("--columns: 'w=a' is not C=NAME or C=NAME[unit]"), std::string::npos);
  EXPECT_EQ(problem_of("x=a,x=b"), "--columns names x twice");
  // A name the file does not have: the option is wrong, not the file (exit 2), and the file's
  // columns are listed.
  const test::TempDir dir;
  const std::string path = dir.write("grid.csv", kTargetAndDifference);
  InputUnits units;
  units.columns =
      aliases("x=x_t+x_diff[mm],y=y_t,z=z_t,q1=joint_1,q2=joint_2,q3=joint_3,q4=joint_4,q5=joint_5,q6=joint_6");
  Dataset<8> dataset;
  port::Error error = read_samples_csv(path, &dataset, units);
  EXPECT_EQ(error.fault, port::Fault::usage);
  EXPECT_EQ(error.message,
            "--columns 'x=x_t+x_diff[mm]': no column 'x_diff' in the header of " + path +
                " (its columns: step, x_t, y_t, z_t, x_dif, y_dif, z_dif, joint_1, joint_2, joint_3, joint_4, joint_5, "
                "joint_6, joint_7)");
  // Terms in two units by the header cannot be summed without saying which.
  const std::string mixed = dir.write("mixed.csv", "q1,q2,q3,q4,q5,q6,a [m],b [mm],y,z\n0,0,0,0,0,0,1,2,3,4\n");
  units.columns = aliases("x=a+b");
  dataset.clear();
  error = read_samples_csv(mixed, &dataset, units);
  EXPECT_NE(error.message.find("--columns 'x=a+b': its terms are in [m] and [mm] by the header: a sum needs one unit"),
            std::string::npos)
      << error.message;
}

TEST(ColumnSpecs, TheColumnsHintOnlyWhereTheOptionCanHelp) {
  const test::TempDir dir;
  const std::string joints = dir.write("j.csv", "a,b,c,d,e,f\n0,0,0,0,0,0\n");
  std::vector<JointVector> poses;
  InputUnits units;
  EXPECT_NE(read_joints_csv(joints, &poses, units).message.find("name them with --columns"), std::string::npos);
  units.columns_option = false;  // a command without --columns (plan, check-robot)
  const port::Error error = read_joints_csv(joints, &poses, units);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_EQ(error.message.find("--columns"), std::string::npos) << error.message;
  JointVector lower;
  JointVector upper;
  const std::string limits = dir.write("limits.csv", "low,high\n-1,1\n");
  const port::Error limit_error = read_joint_limits_csv(limits, &lower, &upper);
  EXPECT_NE(limit_error.message.find("unexpected header"), std::string::npos) << limit_error.message;
  EXPECT_EQ(limit_error.message.find("--columns"), std::string::npos) << limit_error.message;  // it names q1.., x..
}

TEST(DecimalCommas, ThousandsPointsInADecimalCommaFileAreRefusedNamingBothLines) {
  const test::TempDir dir;
  Dataset<8> dataset;
  const InputUnits mm{"mm", ""};
  // 2.568 means 2,568 mm in a file of decimal commas: read as 2.568 mm it would be 1000 times off.
  const std::string after =
      dir.write("after.csv", "q1;q2;q3;q4;q5;q6;x;y;z\n0;0;0;0;0;0;845,3;-12,5;1\n0;0;0;0;0;0;2.568;-1.024,5;7\n");
  port::Error error = read_samples_csv(after, &dataset, mm);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_EQ(error.message,
            after +
                ":3: the file writes decimal commas (line 2, column 'x': '845,3') and points in thousands "
                "positions (line 3, column 'x': '2.568'): a thousands separator, which would be read as a "
                "decimal point; export the numbers without thousands separators");
  // The other order: the thousands point first, the decimal comma later.
  const std::string before =
      dir.write("before.csv", "q1;q2;q3;q4;q5;q6;x;y;z\n0;0;0;0;0;0;1.250;3;1\n0;0;0;0;0;0;1;2;0,5\n");
  dataset.clear();
  error = read_samples_csv(before, &dataset, mm);
  EXPECT_NE(error.message.find("before.csv:3: the file writes decimal commas (line 3, column 'z': '0,5') and points in "
                               "thousands positions (line 2, column 'x': '1.250')"),
            std::string::npos)
      << error.message;
  // Without decimal commas a point is a decimal point (0.568, 2.568 and 12.5 alike), and a
  // comma-separated file cannot hold decimal commas at all.
  for (const char* text : {"q1;q2;q3;q4;q5;q6;x;y;z\n0;0;0;0;0;0;2.568;0.568;12.5\n",
                           "q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,2.568,1.024,3\n",
                           "q1;q2;q3;q4;q5;q6;x;y;z\n0;0;0;0;0;0;845,3;0.568;1\n"}) {
    dataset.clear();
    error = read_samples_csv(dir.write("fine.csv", text), &dataset, mm);
    EXPECT_TRUE(error.ok()) << text << ": " << error.message;
  }
}

}  // namespace
}  // namespace hivecal::textio::column_specs_test
