// Readers and writers of the fixed-column CSV formats of docs/formats.md
// (shared/spec/io-formats.md): paired samples, poses to predict, predicted positions. The
// robot and tracker logs (hivecal's and other tools') are read by textio/logs.hpp; both read
// text through textio/delimited.hpp (port::InputFile underneath). Every error names the file
// and line; nothing is half-read silently.
#pragma once

#include <string>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/port/error.hpp"
#include "textio/delimited.hpp"

namespace hivecal::textio {

/// Stated noise of a pendant's TCP position: its 0.01 mm rounding [m].
constexpr double kDefaultPositionSigma_m = 1e-5;
/// Stated noise of a pendant's TCP rotation vector: its 0.001 rad rounding [rad].
constexpr double kDefaultAngleSigma_rad = 1e-3;

/// What the three orientation columns rx, ry, rz hold.
enum class OrientationForm {
  rotation_vector,  ///< axis x angle of the tool frame in the tracker frame (a UR pendant's)
  euler_xyz,        ///< intrinsic X-Y-Z Euler angles: R = Rx(rx) Ry(ry) Rz(rz) (a Leica T-Mac export's)
};

/// How a measured orientation (`rx,ry,rz` columns: the tool frame's rotation vector in the
/// tracker frame) enters: each such row becomes three samples of its joints, target 1 the
/// point, targets 2 and 3 the point moved by the lever along the measured frame's x and y
/// axes (virtual reflectors whose tool points are estimated like real ones, docs/formats.md).
/// The lever weighs orientation against position: a virtual point's noise from the angle is
/// lever x angle noise, equal to the position noise at lever = position / angle noise
/// (noise_lever_m: with the joints' reading noise, which moves the point far more than it
/// turns the tool).
struct OrientationInput {
  double position_sigma_m = kDefaultPositionSigma_m;  ///< stated noise of the measured positions [m]
  double angle_sigma_rad = kDefaultAngleSigma_rad;    ///< stated noise of the measured orientations [rad]
  double lever_m = -1.0;  ///< lever [m]; < 0: from the noise (noise_lever_m); 0: rx, ry, rz checked, not used
  OrientationForm form = OrientationForm::rotation_vector;  ///< what rx, ry, rz hold
  /// The arm whose joint-reading noise the lever from the noise takes in (its nominal geometry
  /// and tool point suffice); null: position_sigma_m / angle_sigma_rad alone.
  const RobotModel* arm = nullptr;
  /// Noise of the joint readings, in the same step units as the two sigmas [rad]; 0: the
  /// resolution the joint columns are written in (a UR pendant's 0.01 deg; a log's full digits: ~0).
  double joint_sigma_rad = 0.0;
  /// The lever before the joints' noise [m] (0: orientation not used).
  double lever() const { return lever_m < 0.0 ? position_sigma_m / angle_sigma_rad : lever_m; }
};

/// What read_samples_csv found beside the samples: the orientation columns' use and the joints'
/// written resolution.
struct OrientationRead {
  std::size_t poses = 0;         ///< rows whose orientation became targets 2 and 3 [-]
  double lever_m = 0.0;          ///< the lever used [m] (0 when no row was used)
  double joint_sigma_rad = 0.0;  ///< the joint-reading noise the lever took in [rad] (0: none)
  /// The resolution the joint columns are written in: the finest place value of a last digit
  /// among their fields (a UR pendant's 0.01 deg; a log's full digits: ~1e-16) [rad]
  double joint_resolution_rad = 0.0;
  /// Every row's rx, ry, rz are the same numbers (at least two rows): the columns say the tool
  /// never turned, which the joints may contradict (a constant written for a missing reading).
  bool orientation_constant = false;
};

/// Per-axis variance of the tool point from joints read with noise sigma_q: sigma_q^2 |J|^2 / 3,
/// J = d tool point / d q of `arm` (central differences), |J|^2 its squared Frobenius norm
/// averaged over `poses`; 0 without poses [m^2].
double joint_position_variance_m2(double joint_sigma_rad, const RobotModel& arm, Span<const JointVector> poses);

/// The lever [m] at which a virtual point's noise from the measured orientation equals its
/// position noise, the joints' reading noise sigma_q propagated through `arm` at `poses`: per
/// axis, the position's sigma_p^2 + sigma_q^2 |J|^2 / 3 (J = d tool point / d q, |J|^2 its squared
/// Frobenius norm averaged over the poses) against the angle's sigma_a^2 + 2 sigma_q^2 (each
/// joint turns the tool about its unit axis: 6 sigma_q^2 over three axes). sigma_q = 0 or no
/// pose: sigma_p / sigma_a.
double noise_lever_m(double position_sigma_m, double angle_sigma_rad, double joint_sigma_rad, const RobotModel& arm,
                     Span<const JointVector> poses);

/// The joints of `model` as text inputs carry them (InputUnits::joints): its joint count and
/// which joints are prismatic.
InputJoints input_joints(const RobotModel& model);

/// Reads paired static samples (`q1..qN,x,y,z`: N the arm's joints, `units.joints`, a file with
/// more or fewer joint columns refused naming both counts; optionally `target` after z: the reflector,
/// 1 .. kMaxTargets, 1 when absent; optionally `rx,ry,rz` after them: a measured orientation,
/// see OrientationInput, not together with `target`) into a dataset; reports a full dataset as
/// an error. The joints of a UR-shaped arm may be named as a UR pendant writes them (`Base`,
/// `Shoulder`, `Elbow`, `Wrist 1..3`). Columns without a bracket unit are in `units` (SI when not
/// declared; a prismatic joint's a length); joints and rotation vectors beyond one turn, a
/// prismatic joint beyond 100 m and points beyond 100 m are refused with the likely
/// cause (delimited.hpp). `lines`, when given, receives the 1-based file line of each sample
/// added, in order (a row with an orientation: its line three times). `found`, when given,
/// says how the orientation was used.
port::Error read_samples_csv(const std::string& path, DatasetBase* dataset, const InputUnits& units = {},
                             std::vector<std::size_t>* lines = nullptr, const OrientationInput& orientation = {},
                             OrientationRead* found = nullptr);
/// Starts the tool points of targets 2 and 3 of `start` where `read`'s orientation put them if
/// the tool frame were the flange frame (tool + lever along x, along y); nothing when no
/// orientation was used. The job estimates them (any flange-to-tool rotation).
void start_orientation_targets(const OrientationRead& read, RobotModel* start);

/// Reads poses to predict (`q1..qN`, optionally preceded by `t`), joints, units and checks as above.
port::Error read_joints_csv(const std::string& path, std::vector<JointVector>* poses, const InputUnits& units = {});

/// Reads joint limits: header `lower,upper` (rad, or the unit in brackets, or `units`' angle
/// unit), exactly one row per joint of `units.joints`, lower < upper, each within two turns (4
/// pi rad); a prismatic joint's row in m (within 100 m; the file's angle unit must be rad).
port::Error read_joint_limits_csv(const std::string& path, JointVector* lower_rad, JointVector* upper_rad,
                                  const InputUnits& units = {});

/// "q1,q2,...,qN": the joint columns of an arm of N = `joints` joints.
std::string joint_header(int joints);
/// `q1..qN` rows (N = `joints`) with round-trip precision (the poses-to-predict format).
std::string format_joints_csv(Span<const JointVector> poses_rad, int joints);
/// `x,y,z` rows with round-trip precision, in metres; with `length_unit` "mm" the header is
/// `x [mm],y [mm],z [mm]` and the values are in millimetres (read back by the same reader).
std::string format_points_csv(const std::vector<Vec3>& points_m, const std::string& length_unit = "m");
/// format_points_csv with two columns after z: each point's 1-sigma per axis (`sigma_m`, in
/// millimetres `sigma [mm]`) and `extrapolated` (1 or 0); `sigma_m` and `extrapolated` hold
/// one entry per point.
std::string format_predictions_csv(const std::vector<Vec3>& points_m, const std::vector<double>& sigma_m,
                                   const std::vector<bool>& extrapolated, const std::string& length_unit = "m");
/// `q1..qN,x,y,z` rows (N = `joints`) with round-trip precision (`,target` 1-based when several
/// targets).
std::string format_samples_csv(Span<const Sample> samples, int joints);

}  // namespace hivecal::textio
