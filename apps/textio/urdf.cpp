#include "textio/urdf.hpp"

#include <cmath>

#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

RigidTransform rotation_only(const Mat3& rotation) {
  return RigidTransform{rotation, Vec3::Zero()};
}

/// Tz(d) Tx(a) Rx(alpha): the fixed part of a standard-DH row after its joint.
RigidTransform row_after_joint(const DhJoint& joint) {
  return RigidTransform{rotation_x(joint.alpha_rad), Vec3(joint.a_m, 0.0, joint.d_m)};
}

std::string triple(const Vec3& v) {
  const Vec3 plain = v + Vec3::Zero();  // -0 reads as 0
  return format_double(plain.x()) + " " + format_double(plain.y()) + " " + format_double(plain.z());
}

std::string origin_element(const RigidTransform& transform) {
  const UrdfOrigin origin = urdf_origin(transform);
  return "    <origin xyz=\"" + triple(origin.xyz_m) + "\" rpy=\"" + triple(origin.rpy_rad) + "\"/>\n";
}

std::string link(const std::string& name) {
  return "  <link name=\"" + name + "\"/>\n";
}

std::string fixed_joint(const std::string& name, const std::string& parent, const std::string& child,
                        const RigidTransform& origin) {
  return "  <joint name=\"" + name + "\" type=\"fixed\">\n    <parent link=\"" + parent + "\"/>\n    <child link=\"" +
         child + "\"/>\n" + origin_element(origin) + "  </joint>\n";
}

/// Joint `number` (1-based) of the arm: revolute (turning about z of its origin) or prismatic
/// (sliding along it), with the description's limits or the placeholders.
std::string movable_joint(int number, const std::string& parent, const RigidTransform& origin, const UrdfLimits& limits,
                          const RobotDescription& robot) {
  const std::string n = std::to_string(number);
  const bool slides = joint_type(robot.model, number - 1) == JointType::prismatic;
  double lower = slides ? limits.lower_m : limits.lower_rad;
  double upper = slides ? limits.upper_m : limits.upper_rad;
  if (robot.has_joint_limits) {  // the description's own
    lower = robot.lower_rad(number - 1);
    upper = robot.upper_rad(number - 1);
  }
  return "  <joint name=\"joint_" + n + "\" type=\"" + (slides ? "prismatic" : "revolute") +
         "\">\n    <parent link=\"" + parent + "\"/>\n    <child link=\"link_" + n + "\"/>\n" + origin_element(origin) +
         "    <axis xyz=\"0 0 1\"/>\n    <limit lower=\"" + format_double(lower) + "\" upper=\"" +
         format_double(upper) + "\" effort=\"" + format_double(slides ? limits.effort_n : limits.effort_nm) +
         "\" velocity=\"" + format_double(slides ? limits.velocity_m_s : limits.velocity_rad_s) + "\"/>\n  </joint>\n";
}

/// A name safe inside an XML attribute (the robot's name is free text).
std::string xml_name(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const bool plain =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.';
    out += plain ? c : '_';
  }
  return out.empty() ? std::string("robot") : out;
}

}  // namespace

UrdfOrigin urdf_origin(const RigidTransform& transform) {
  const Mat3& r = transform.rotation;
  UrdfOrigin origin;
  origin.xyz_m = transform.translation_m;
  const double cos_pitch = std::sqrt(r(0, 0) * r(0, 0) + r(1, 0) * r(1, 0));
  const double pitch = std::atan2(-r(2, 0), cos_pitch);
  if (cos_pitch > 1e-9) {
    origin.rpy_rad = Vec3(std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0)));
  } else {
    // Gimbal lock: only yaw - roll (pitch = +pi/2) or yaw + roll (pitch = -pi/2) is defined.
    origin.rpy_rad = Vec3(0.0, pitch, std::atan2(-r(0, 1), r(1, 1)));
  }
  return origin;
}

RigidTransform urdf_transform(const UrdfOrigin& origin) {
  const Vec3& rpy = origin.rpy_rad;
  const Mat3 rotation = rotation_z(rpy.z()) * rotation_y(rpy.y()) * rotation_x(rpy.x());
  return RigidTransform{rotation, origin.xyz_m};
}

std::string format_urdf(const RobotDescription& robot, const RigidTransform* base_to_tracker,
                        const UrdfLimits& limits) {
  const RobotModel& model = robot.model;
  const bool modified = robot.convention == DhConvention::modified;
  const RigidTransform base_offset = modified ? robot.modified_base.transform() : RigidTransform{};
  std::string s =
      "<?xml version=\"1.0\"?>\n<!-- Written by hivecal export: the " +
      std::string(modified ? "modified" : "standard") + "-DH model as a serial chain" +
      (robot.has_joint_limits ? std::string("")
                              : std::string("; joint limits are placeholders (the description gives none)")) +
      ". -->\n"
      "<robot name=\"" +
      xml_name(robot.robot) + "\">\n" + link("base_link");
  for (int i = 1; i <= model.joint_count; ++i) s += link("link_" + std::to_string(i));
  s += link("flange");
  for (int k = 0; k < robot.target_count; ++k) s += link(k == 0 ? "tcp" : "tcp_" + std::to_string(k + 1));
  RigidTransform before_joint = base_offset;  // from the previous link to the next joint's frame
  std::string parent = "base_link";
  for (int i = 0; i < model.joint_count; ++i) {
    // Revolute: Rz(theta_offset) Rz(q) Tz(d) ...; prismatic: Rz(theta) Tz(q) Tz(d) ...: the
    // joint's motion between the same two fixed parts either way.
    const DhJoint& joint = model.joints[i];
    s += movable_joint(i + 1, parent, before_joint.then_after(rotation_only(rotation_z(joint.theta_offset_rad))),
                       limits, robot);
    before_joint = row_after_joint(joint);
    parent = "link_" + std::to_string(i + 1);
  }
  s += fixed_joint("flange_joint", parent, "flange", before_joint);
  for (int k = 0; k < robot.target_count; ++k) {
    const std::string suffix = k == 0 ? "" : "_" + std::to_string(k + 1);
    s += fixed_joint("tcp" + suffix + "_joint", "flange", "tcp" + suffix,
                     RigidTransform{Mat3::Identity(), target_tool(model, k)});
  }
  if (base_to_tracker != nullptr) {
    // The tracker's pose in base_link: (file base -> chain base) * (chain base -> tracker)^-1.
    s += link("tracker") +
         fixed_joint("tracker_joint", "base_link", "tracker", base_offset.then_after(base_to_tracker->inverse()));
  }
  return s + "</robot>\n";
}

}  // namespace hivecal::textio
