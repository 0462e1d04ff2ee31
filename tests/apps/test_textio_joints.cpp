// Text inputs carry the robot model's joints (issue 53): q1..qN of an arm of N joints, a file
// with more or fewer joint columns than the model refused naming both counts (never cut),
// --columns qK for K up to the arm's, joint limits one row per joint (a slide's in metres), and
// the writers' q1..qN.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/csv.hpp"
#include "textio/delimited.hpp"

namespace hivecal::textio_joints_test {
namespace {

/// The text-input joints of a test arm of other than six joints.
textio::InputUnits units_of(test::ManyJointArm arm) {
  textio::InputUnits units;
  units.joints = textio::input_joints(test::many_joint_arm_model(arm));
  return units;
}

/// --columns text into `units`; a gtest failure names the problem.
void set_columns(const std::string& text, textio::InputUnits* units) {
  EXPECT_EQ(textio::parse_column_aliases(text, &units->columns), "") << text;
}

// A seven-joint arm's samples and poses are written q1..q7 and read back to the same bits.
TEST(TextJoints, SevenJointSamplesAndPosesRoundTrip) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir;
  Random random(3);
  const RobotModel arm = test::many_joint_arm_model(test::ManyJointArm::iiwa14);
  static Dataset<16> written;
  written.clear();
  test::fill_many_joint_arm(test::ManyJointArm::iiwa14, arm, test::example_base_to_tracker(), 12, 1e-5, &random,
                            &written);
  const std::string text = textio::format_samples_csv(written.samples(), 7);
  EXPECT_EQ(text.substr(0, text.find('\n')), "q1,q2,q3,q4,q5,q6,q7,x,y,z");
  static Dataset<16> read_back;
  read_back.clear();
  const port::Error read =
      textio::read_samples_csv(dir.write("s.csv", text), &read_back, units_of(test::ManyJointArm::iiwa14));
  ASSERT_TRUE(read.ok()) << read.message;
  ASSERT_EQ(read_back.size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) {
    EXPECT_EQ(read_back.samples()[i].q_rad, written.samples()[i].q_rad);
    EXPECT_EQ(read_back.samples()[i].point_m, written.samples()[i].point_m);
  }
  std::vector<JointVector> poses;
  for (const Sample& s : written.samples()) poses.push_back(s.q_rad);
  const std::string joints = textio::format_joints_csv(Span<const JointVector>(poses.data(), poses.size()), 7);
  EXPECT_EQ(joints.substr(0, joints.find('\n')), "q1,q2,q3,q4,q5,q6,q7");
  std::vector<JointVector> poses_back;
  ASSERT_TRUE(
      textio::read_joints_csv(dir.write("j.csv", joints), &poses_back, units_of(test::ManyJointArm::iiwa14)).ok());
  ASSERT_EQ(poses_back.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(poses_back[i], poses[i]);
}

// A file of seven joint columns read for a six-joint model is refused naming both counts (it
// used to drop q7 and fit a UR5 to a WAM), and six joint columns for a seven-joint model too.
TEST(TextJoints, AFileOfAnotherJointCountIsRefusedNamingBoth) {
  const test::TempDir dir;
  const std::string seven = dir.write("seven.csv", "q1,q2,q3,q4,q5,q6,q7,x,y,z\n0,0,0,0,0,0,0.5,1,2,3\n");
  static Dataset<4> dataset;
  dataset.clear();
  port::Error error = textio::read_samples_csv(seven, &dataset);  // six joints by default
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_EQ(error.message, seven +
                               ": its header has joint columns up to q7, but the robot model has 6 joints (q1..q6): "
                               "the joints of another arm? (--robot-model names the arm)");
  EXPECT_EQ(dataset.size(), 0u);
  std::vector<JointVector> poses;
  error = textio::read_joints_csv(dir.write("p.csv", "t,q1,q2,q3,q4,q5,q6,q7\n0,0,0,0,0,0,0,0\n"), &poses);
  EXPECT_NE(error.message.find("up to q7, but the robot model has 6 joints"), std::string::npos) << error.message;
  if (kMaxJoints < 7) return;
  const std::string six = dir.write("six.csv", "q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,1,2,3\n");
  error = textio::read_samples_csv(six, &dataset, units_of(test::ManyJointArm::iiwa14));
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_EQ(error.message, six +
                               ": its header has 6 joint columns (q1..q6), but the robot model has 7 joints (q1..q7): "
                               "the joints of another arm? (--robot-model names the arm)");
  error = textio::read_samples_csv(seven, &dataset, units_of(test::ManyJointArm::iiwa14));
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(dataset.samples()[0].q_rad(6), 0.5);
}

// A lab's export names its joints joint_1 .. joint_7: --columns q7=joint_7 reads the seventh
// for a seven-joint model; naming q1..q6 of it for a six-joint model leaves joint_7, which is
// refused rather than dropped, and --columns q7 for six joints is the option's fault.
TEST(TextJoints, ColumnsNameEveryJointOfTheArmAndNoMore) {
  const test::TempDir dir;
  const std::string path = dir.write(
      "grid.csv",
      "x_t,y_t,z_t,joint_1,joint_2,joint_3,joint_4,joint_5,joint_6,joint_7\n500,-300,2,10,-20,30,-40,50,-60,70\n");
  const std::string six_joints =
      "x=x_t[mm],y=y_t[mm],z=z_t[mm],q1=joint_1[deg],q2=joint_2[deg],q3=joint_3[deg],"
      "q4=joint_4[deg],q5=joint_5[deg],q6=joint_6[deg]";
  static Dataset<4> dataset;
  dataset.clear();
  textio::InputUnits six;
  set_columns(six_joints, &six);
  port::Error error = textio::read_samples_csv(path, &dataset, six);
  EXPECT_EQ(error.fault, port::Fault::input);
  EXPECT_EQ(error.message, path +
                               ": its header has a column 'joint_7' after --columns' q6=joint_6, but the robot model "
                               "has 6 joints (q1..q6): the joints of another arm? (--robot-model names the arm)");
  textio::InputUnits too_many;
  set_columns(six_joints + ",q7=joint_7[deg]", &too_many);
  error = textio::read_samples_csv(path, &dataset, too_many);
  EXPECT_EQ(error.fault, port::Fault::usage);
  EXPECT_EQ(error.message, "--columns 'q7=joint_7[deg]': the robot model has 6 joints (q1..q6)");
  // "joint_16" holds no joint 6: nothing is predicted from it.
  textio::InputUnits other_names;
  set_columns("q1=a,q2=b,q3=c,q4=d,q5=e,q6=joint_16", &other_names);
  std::vector<JointVector> poses;
  EXPECT_TRUE(
      textio::read_joints_csv(dir.write("o.csv", "a,b,c,d,e,joint_16,joint_17\n0,0,0,0,0,0,0\n"), &poses, other_names)
          .ok());
  if (kMaxJoints < 7) return;
  textio::InputUnits seven = units_of(test::ManyJointArm::iiwa14);
  set_columns(six_joints + ",q7=joint_7[deg]", &seven);
  error = textio::read_samples_csv(path, &dataset, seven);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(dataset.samples()[0].q_rad(6), 70.0 * math::kRadPerDeg);
  EXPECT_EQ(dataset.samples()[0].point_m, Vec3(0.5, -0.3, 0.002));
}

// A prismatic joint's column is a length: --length-unit and a header unit scale it, a value
// beyond 100 m is millimetres; UR pendant names mean a UR's six joints only.
TEST(TextJoints, APrismaticJointIsALengthAndUrNamesAreAUrs) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir;
  static Dataset<4> dataset;
  dataset.clear();
  textio::InputUnits rail = units_of(test::ManyJointArm::rail_ur10);
  const std::string header = "q1,q2,q3,q4,q5,q6,q7,x,y,z\n";
  port::Error error =
      textio::read_samples_csv(dir.write("mm.csv", header + "1250,0,0,0,0,0,0,1,2,3\n"), &dataset, rail);
  EXPECT_NE(error.message.find("mm.csv:2: prismatic joint q1 = 1250 looks like millimetres: use --length-unit mm"),
            std::string::npos)
      << error.message;
  rail.length = "mm";
  error = textio::read_samples_csv(dir.write("mm.csv", header + "1250,0,0,0,0,0,0.5,1000,2000,3000\n"), &dataset, rail);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(dataset.samples()[0].q_rad(0), 1.25);  // the slide in m
  EXPECT_EQ(dataset.samples()[0].q_rad(6), 0.5);   // a revolute joint still in rad
  const std::string pendant = "Base,Shoulder,Elbow,Wrist 1,Wrist 2,Wrist 3,x,y,z\n0,0,0,0,0,0,1,2,3\n";
  dataset.clear();
  EXPECT_TRUE(textio::read_samples_csv(dir.write("ur.csv", pendant), &dataset).ok());
  error = textio::read_samples_csv(dir.write("ur.csv", pendant), &dataset, units_of(test::ManyJointArm::iiwa14));
  EXPECT_NE(error.message.find("unexpected header"), std::string::npos) << error.message;
}

// Joint limits are one row per joint of the arm: seven for a seven-joint arm, each count refused
// naming the model's; a slide's row in metres, not in the file's angle unit.
TEST(TextJoints, JointLimitsAreOneRowPerJoint) {
  const test::TempDir dir;
  JointVector lower;
  JointVector upper;
  std::string seven_rows = "lower,upper\n";
  for (int j = 0; j < 7; ++j) seven_rows += "-2,2\n";
  port::Error error = textio::read_joint_limits_csv(dir.write("l7.csv", seven_rows), &lower, &upper);
  EXPECT_NE(error.message.find(":8: more than 6 rows (one per joint: the robot model has 6 joints)"), std::string::npos)
      << error.message;
  if (kMaxJoints < 7) return;
  error = textio::read_joint_limits_csv(dir.write("l7.csv", seven_rows), &lower, &upper,
                                        units_of(test::ManyJointArm::iiwa14));
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(upper(6), 2.0);
  error = textio::read_joint_limits_csv(dir.write("l6.csv", "lower,upper\n-2,2\n-2,2\n-2,2\n-2,2\n-2,2\n-2,2\n"),
                                        &lower, &upper, units_of(test::ManyJointArm::iiwa14));
  EXPECT_NE(error.message.find("l6.csv: 6 rows, expected 7 (one per joint: the robot model has 7 joints)"),
            std::string::npos)
      << error.message;
  const textio::InputUnits rail = units_of(test::ManyJointArm::rail_ur10);
  std::string slide_rows = "lower,upper\n0,1.5\n";
  for (int j = 1; j < 7; ++j) slide_rows += "-3,3\n";
  error = textio::read_joint_limits_csv(dir.write("rail.csv", slide_rows), &lower, &upper, rail);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(upper(0), 1.5);
  std::string degrees = "lower [deg],upper [deg]\n0,1.5\n";
  for (int j = 1; j < 7; ++j) degrees += "-170,170\n";
  error = textio::read_joint_limits_csv(dir.write("deg.csv", degrees), &lower, &upper, rail);
  EXPECT_NE(error.message.find("joint 1 is prismatic: its limits are in m"), std::string::npos) << error.message;
  error = textio::read_joint_limits_csv(dir.write("far.csv", "lower,upper\n0,1500\n" + slide_rows.substr(18)), &lower,
                                        &upper, rail);
  EXPECT_NE(error.message.find("joint 1 is prismatic: a limit beyond 100 m: millimetres?"), std::string::npos)
      << error.message;
}

}  // namespace
}  // namespace hivecal::textio_joints_test
