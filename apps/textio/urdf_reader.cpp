// Reading a URDF serial arm into the library's DH model (docs/formats.md "URDF in").
#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "textio/delimited.hpp"
#include "textio/text_util.hpp"
#include "textio/urdf.hpp"

namespace hivecal::textio {
namespace {

// --- a small XML tag reader: what a URDF's joints and links need -------------------------

struct Tag {
  std::string name;                          ///< element name ("joint", "origin", ...)
  std::map<std::string, std::string> attrs;  ///< attributes as written
  int line = 0;                              ///< 1-based line of the '<'
  int depth = 0;                             ///< nesting depth of the element (robot: 0)
  bool closing = false;                      ///< </name>
};

/// The opening (and self-closing) tags of `text` with their depths; false with *what on
/// malformed markup.
bool read_tags(const std::string& text, std::vector<Tag>* tags, std::string* what) {
  int line = 1;
  int depth = 0;
  std::vector<std::pair<std::string, int>> open_tags;  // name and line of each open element
  std::size_t at = 0;
  auto count_lines = [&](std::size_t from, std::size_t to) {
    line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(from),
                                        text.begin() + static_cast<std::ptrdiff_t>(to), '\n'));
  };
  while (true) {
    const std::size_t open = text.find('<', at);
    if (open == std::string::npos) break;
    count_lines(at, open);
    const int tag_line = line;
    if (text.compare(open, 4, "<!--") == 0 || text.compare(open, 2, "<?") == 0 || text.compare(open, 2, "<!") == 0) {
      const char* end_mark = text.compare(open, 4, "<!--") == 0 ? "-->" : ">";
      const std::size_t end = text.find(end_mark, open);
      if (end == std::string::npos)
        return *what = std::to_string(tag_line) + ": unterminated comment or declaration", false;
      count_lines(open, end);
      at = end + std::string(end_mark).size();
      continue;
    }
    std::size_t close = open + 1;
    char quote = 0;
    for (; close < text.size(); ++close) {
      const char c = text[close];
      if (quote != 0) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        break;
      }
    }
    if (close >= text.size()) return *what = std::to_string(tag_line) + ": unterminated tag", false;
    std::string body = text.substr(open + 1, close - open - 1);
    count_lines(open, close);
    at = close + 1;
    Tag tag;
    tag.line = tag_line;
    tag.closing = !body.empty() && body[0] == '/';
    const bool self_closing = !body.empty() && body.back() == '/';
    if (tag.closing) body.erase(0, 1);
    if (self_closing) body.pop_back();
    std::size_t i = 0;
    while (i < body.size() && !std::isspace(static_cast<unsigned char>(body[i]))) tag.name += body[i++];
    while (i < body.size()) {
      while (i < body.size() && std::isspace(static_cast<unsigned char>(body[i]))) ++i;
      if (i >= body.size()) break;
      std::string key;
      while (i < body.size() && body[i] != '=' && !std::isspace(static_cast<unsigned char>(body[i]))) key += body[i++];
      while (i < body.size() && std::isspace(static_cast<unsigned char>(body[i]))) ++i;
      if (i >= body.size() || body[i] != '=')
        return *what = std::to_string(tag_line) + ": attribute '" + key + "' without a value", false;
      ++i;
      while (i < body.size() && std::isspace(static_cast<unsigned char>(body[i]))) ++i;
      if (i >= body.size() || (body[i] != '"' && body[i] != '\'')) {
        return *what = std::to_string(tag_line) + ": attribute '" + key + "' value not quoted", false;
      }
      const char q = body[i++];
      const std::size_t end = body.find(q, i);
      tag.attrs[key] = body.substr(i, end - i);
      i = end + 1;
    }
    if (tag.closing) {
      if (open_tags.empty() || open_tags.back().first != tag.name) {
        return *what = std::to_string(tag_line) + ": </" + tag.name + "> closes " +
                       (open_tags.empty()
                            ? std::string("nothing")
                            : "<" + open_tags.back().first + "> of line " + std::to_string(open_tags.back().second)),
               false;
      }
      open_tags.pop_back();
      --depth;
      continue;
    }
    tag.depth = depth;
    tags->push_back(tag);
    if (!self_closing) {
      ++depth;
      open_tags.emplace_back(tag.name, tag_line);
    }
  }
  if (!open_tags.empty()) {
    return *what = std::to_string(open_tags.back().second) + ": <" + open_tags.back().first + "> is never closed",
           false;
  }
  return true;
}

/// Three numbers of an attribute ("x y z"); `fallback` when absent.
bool read_triple(const Tag& tag, const char* key, const Vec3& fallback, Vec3* value, std::string* what) {
  const auto found = tag.attrs.find(key);
  if (found == tag.attrs.end()) {
    *value = fallback;
    return true;
  }
  std::vector<std::string> fields;
  std::string field;
  for (const char c : found->second + " ") {
    if (std::isspace(static_cast<unsigned char>(c))) {
      if (!field.empty()) fields.push_back(field);
      field.clear();
    } else {
      field += c;
    }
  }
  if (fields.size() != 3 || !parse_double(fields[0], &(*value)(0)) || !parse_double(fields[1], &(*value)(1)) ||
      !parse_double(fields[2], &(*value)(2)) || !std::isfinite(value->sum())) {
    *what = std::to_string(tag.line) + ": <" + tag.name + " " + key + "> must be three numbers, not '" + found->second +
            "'";
    return false;
  }
  return true;
}

// --- the kinematic tree ------------------------------------------------------------------

struct UrdfJoint {
  std::string name, type, parent, child;
  int line = 0;
  RigidTransform origin;      ///< parent link -> joint frame
  Vec3 axis = Vec3::UnitX();  ///< in the joint frame (URDF's default is x)
  bool has_limit = false;     ///< <limit lower upper> given
  double lower_rad = 0.0, upper_rad = 0.0;
  bool movable() const { return type == "revolute" || type == "continuous"; }
};

struct UrdfTree {
  std::string robot_name;
  std::vector<UrdfJoint> joints;                    ///< in file order
  std::vector<std::string> links;                   ///< in file order
  std::map<std::string, std::size_t> parent_joint;  ///< child link -> index in joints
};

bool read_tree(const std::vector<Tag>& tags, UrdfTree* tree, std::string* what) {
  if (tags.empty() || tags[0].name != "robot") return *what = " not a URDF: the document is no <robot>", false;
  tree->robot_name = tags[0].attrs.count("name") ? tags[0].attrs.at("name") : "";
  for (std::size_t i = 1; i < tags.size(); ++i) {
    const Tag& tag = tags[i];
    if (tag.depth != 1) continue;
    if (tag.name == "link") {
      tree->links.push_back(tag.attrs.count("name") ? tag.attrs.at("name") : "");
      continue;
    }
    if (tag.name != "joint") continue;
    UrdfJoint joint;
    joint.line = tag.line;
    joint.name = tag.attrs.count("name") ? tag.attrs.at("name") : "";
    joint.type = tag.attrs.count("type") ? tag.attrs.at("type") : "";
    const std::string who = std::to_string(tag.line) + ": joint '" + joint.name + "'";
    if (!joint.movable() && joint.type != "fixed") {
      return *what = who + " is " + (joint.type.empty() ? "without a type" : "'" + joint.type + "'") +
                     ": only revolute, continuous and fixed joints make a serial arm hivecal models",
             false;
    }
    for (std::size_t k = i + 1; k < tags.size() && tags[k].depth > 1; ++k) {
      const Tag& child = tags[k];
      if (child.depth != 2) continue;
      if (child.name == "parent") joint.parent = child.attrs.count("link") ? child.attrs.at("link") : "";
      if (child.name == "child") joint.child = child.attrs.count("link") ? child.attrs.at("link") : "";
      if (child.name == "origin") {
        UrdfOrigin origin;
        if (!read_triple(child, "xyz", Vec3::Zero(), &origin.xyz_m, what) ||
            !read_triple(child, "rpy", Vec3::Zero(), &origin.rpy_rad, what)) {
          return false;
        }
        joint.origin = urdf_transform(origin);
      }
      if (child.name == "limit" && joint.type == "revolute" && child.attrs.count("lower") &&
          child.attrs.count("upper")) {
        if (!parse_double(child.attrs.at("lower"), &joint.lower_rad) ||
            !parse_double(child.attrs.at("upper"), &joint.upper_rad) || !(joint.lower_rad < joint.upper_rad) ||
            !(std::fabs(joint.lower_rad) <= kMaxJointLimit_rad) ||
            !(std::fabs(joint.upper_rad) <= kMaxJointLimit_rad)) {
          return *what = std::to_string(child.line) + ": joint '" + joint.name +
                         "' <limit>: lower below upper, both numbers within two turns (4 pi rad)",
                 false;
        }
        joint.has_limit = true;
      }
      if (child.name == "axis") {
        if (!read_triple(child, "xyz", Vec3::UnitX(), &joint.axis, what)) return false;
        if (!(joint.axis.norm() > 1e-9)) return *what = who + ": its axis is zero", false;
        joint.axis.normalize();
      }
    }
    if (joint.parent.empty() || joint.child.empty()) return *what = who + " needs a parent and a child link", false;
    if (tree->parent_joint.count(joint.child) != 0) {
      return *what = who + ": link '" + joint.child + "' already has a parent joint (a loop, or not a tree)", false;
    }
    tree->parent_joint[joint.child] = tree->joints.size();
    tree->joints.push_back(joint);
  }
  return true;
}

/// The joints from the root to `link`, root first.
std::vector<const UrdfJoint*> path_to(const UrdfTree& tree, const std::string& link) {
  std::vector<const UrdfJoint*> path;
  for (std::string at = link; tree.parent_joint.count(at) != 0 && path.size() <= tree.joints.size();) {
    path.push_back(&tree.joints[tree.parent_joint.at(at)]);
    at = path.back()->parent;
  }
  std::reverse(path.begin(), path.end());
  return path;
}

/// Pose of `link` in the root frame at q = 0.
RigidTransform pose_at_zero(const UrdfTree& tree, const std::string& link) {
  RigidTransform pose;
  for (const UrdfJoint* joint : path_to(tree, link)) pose = pose.then_after(joint->origin);
  return pose;
}

/// Pose of `link` in the root frame at joints `q` (the arm's movable joints in chain order).
RigidTransform pose_at(const UrdfTree& tree, const std::string& link, const JointVector& q) {
  RigidTransform pose;
  int k = 0;
  for (const UrdfJoint* joint : path_to(tree, link)) {
    pose = pose.then_after(joint->origin);
    if (!joint->movable()) continue;
    const Eigen::AngleAxisd turn(q(k++), joint->axis);
    pose = pose.then_after(RigidTransform{turn.toRotationMatrix(), Vec3::Zero()});
  }
  return pose;
}

// --- DH frames from joint axes ------------------------------------------------------------

/// A DH frame: origin and axes in the root frame.
struct Frame {
  Vec3 origin = Vec3::Zero();
  Vec3 x = Vec3::UnitX();
  Vec3 z = Vec3::UnitZ();
};

double signed_angle(const Vec3& from, const Vec3& to, const Vec3& about) {
  return std::atan2(from.cross(to).dot(about), from.dot(to)) + 0.0;  // -0 reads as 0
}

/// Standard-DH row from `previous` (its z: this joint's axis) to the next joint's axis
/// (point, direction); *next receives the new frame.
DhJoint dh_row(const Frame& previous, const Vec3& next_point, const Vec3& next_axis, Frame* next) {
  constexpr double kTiny = 1e-12;
  const Vec3& u = previous.z;
  const Vec3& v = next_axis;
  Vec3 foot_a = previous.origin;  // on this joint's axis
  Vec3 foot_b;
  const double b = u.dot(v);
  const double denom = 1.0 - b * b;
  if (denom > kTiny) {  // skew or intersecting: the common normal
    const Vec3 w0 = previous.origin - next_point;
    const double d = u.dot(w0);
    const double e = v.dot(w0);
    foot_a = previous.origin + ((b * e - d) / denom) * u;
    foot_b = next_point + ((e - b * d) / denom) * v;
  } else {  // parallel: the normal through the previous origin (d = 0)
    foot_b = next_point + (previous.origin - next_point).dot(v) * v;
  }
  const Vec3 normal = foot_b - foot_a;
  next->z = v;
  if (normal.norm() > 1e-10) {
    next->x = normal.normalized();
  } else if (denom > kTiny) {
    next->x = u.cross(v).normalized();  // intersecting axes
  } else {
    next->x = previous.x;  // the same axis
  }
  // The normal's sign is free: the one nearer the previous x keeps a robot's own tables (UR's
  // negative link lengths with zero offsets) instead of turning them by pi.
  if (next->x.dot(previous.x) < 0.0) next->x = -next->x;
  next->origin = foot_b;
  DhJoint row;
  row.d_m = (foot_a - previous.origin).dot(u);
  row.a_m = normal.dot(next->x);
  row.theta_offset_rad = signed_angle(previous.x, next->x, u);
  row.alpha_rad = signed_angle(u, v, next->x);
  return row;
}

/// Frame 0 for joint 1's axis: the root frame, or Rx(alpha_0) Tx(a_0) of it (modified DH).
bool base_frame(const Vec3& point, const Vec3& axis, ModifiedDhBase* base, Frame* frame0, std::string* what) {
  constexpr double kTolerance = 1e-12;
  if (std::fabs(axis.x()) > kTolerance) {
    *what =
        "joint 1's axis is not perpendicular to the root link's x axis: a DH model has no general base "
        "transform (the tracker frame fit absorbs it; give the root a frame whose z or y-z plane holds joint 1)";
    return false;
  }
  const double along = std::fabs(axis.z()) >= std::fabs(axis.y()) ? -point.z() / axis.z() : -point.y() / axis.y();
  const Vec3 crossing = point + along * axis;  // where the axis meets the x-z or x-y plane
  if (std::fabs(crossing.y()) > 1e-10 || std::fabs(crossing.z()) > 1e-10) {
    *what = "joint 1's axis does not meet the root link's x axis: a DH model has no general base transform";
    return false;
  }
  base->alpha0_rad = std::atan2(-axis.y(), axis.z());
  base->a0_m = crossing.x();
  frame0->origin = Vec3(base->a0_m, 0.0, 0.0);
  frame0->x = Vec3::UnitX();
  frame0->z = axis;
  return true;
}

/// The links below `link` reached through fixed joints only that have no child: the tips.
void fixed_leaves(const UrdfTree& tree, const std::string& link, std::vector<std::string>* leaves) {
  bool has_child = false;
  for (const UrdfJoint& joint : tree.joints) {
    if (joint.parent != link) continue;
    has_child = true;
    fixed_leaves(tree, joint.child, leaves);
  }
  if (!has_child) leaves->push_back(link);
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// The links of the tool points: tcp (tcp_2, tcp_3), else tool0, else the only tip.
bool tool_links(const std::vector<std::string>& leaves, std::vector<std::string>* tools, std::string* what) {
  if (contains(leaves, "tcp")) {
    tools->push_back("tcp");
    for (const char* more : {"tcp_2", "tcp_3"})
      if (contains(leaves, more)) tools->push_back(more);
  } else if (contains(leaves, "tool0")) {
    tools->push_back("tool0");
  } else if (leaves.size() == 1) {
    tools->push_back(leaves[0]);
  } else {
    std::string names;
    for (const std::string& leaf : leaves) names += (names.empty() ? "" : ", ") + leaf;
    *what = "the arm ends in several links (" + names + "): name the tool link 'tcp' or 'tool0'";
    return false;
  }
  return true;
}

}  // namespace

port::Error parse_urdf_description(const std::string& text, const std::string& source_name,
                                   RobotDescription* description) {
  std::vector<Tag> tags;
  UrdfTree tree;
  std::string what;
  const auto refuse = [&](const std::string& why) { return port::Error::input(source_name + ":" + why); };
  if (!read_tags(text, &tags, &what) || !read_tree(tags, &tree, &what)) return refuse(what);
  // The arm: the movable joints on the path to the tips, exactly six, in one line.
  std::vector<const UrdfJoint*> movable;
  for (const UrdfJoint& joint : tree.joints)
    if (joint.movable()) movable.push_back(&joint);
  if (movable.size() != static_cast<std::size_t>(kSixJoints)) {
    return refuse(" " + std::to_string(movable.size()) +
                  " movable joints: hivecal models arms of exactly 6 revolute joints");
  }
  std::vector<const UrdfJoint*> chain;
  for (const UrdfJoint* joint : path_to(tree, movable.back()->child))
    if (joint->movable()) chain.push_back(joint);
  if (chain.size() != movable.size()) {
    return refuse(std::to_string(movable.back()->line) + ": the movable joints are not one serial chain (joint '" +
                  movable.back()->name + "' has only " + std::to_string(chain.size()) + " movable joints before it)");
  }
  std::vector<std::string> leaves;
  fixed_leaves(tree, chain.back()->child, &leaves);
  std::vector<std::string> tools;
  if (!tool_links(leaves, &tools, &what)) return refuse(" " + what);
  // Axes at q = 0 in the root frame, then the DH frames between them.
  ModifiedDhBase base;
  Frame frame;
  const RigidTransform joint1 = pose_at_zero(tree, chain[0]->parent).then_after(chain[0]->origin);
  if (!base_frame(joint1.translation_m, joint1.rotation * chain[0]->axis, &base, &frame, &what))
    return refuse(" " + what);
  RobotModel model;
  for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
    const RigidTransform next = pose_at_zero(tree, chain[i + 1]->parent).then_after(chain[i + 1]->origin);
    Frame following;
    model.joints[i] = dh_row(frame, next.translation_m, next.rotation * chain[i + 1]->axis, &following);
    frame = following;
  }
  // Frame 6 (the flange): at the 'flange' link when there is one, else the last joint's child.
  const std::string flange =
      contains(leaves, "flange") || tree.parent_joint.count("flange") ? "flange" : chain.back()->child;
  const RigidTransform flange_pose = pose_at_zero(tree, flange);
  Frame frame6;
  frame6.z = frame.z;
  const Vec3 offset = flange_pose.translation_m - frame.origin;
  DhJoint& last = model.joints[kSixJoints - 1];
  last.d_m = offset.dot(frame.z);
  const Vec3 radial = offset - last.d_m * frame.z;
  const Vec3 flange_x = flange_pose.rotation.col(0) - flange_pose.rotation.col(0).dot(frame.z) * frame.z;
  frame6.x = radial.norm() > 1e-10 ? radial.normalized() : (flange_x.norm() > 1e-6 ? flange_x.normalized() : frame.x);
  if (radial.norm() > 1e-10 && frame6.x.dot(frame.x) < 0.0) frame6.x = -frame6.x;  // as in dh_row
  last.a_m = radial.dot(frame6.x);
  last.theta_offset_rad = signed_angle(frame.x, frame6.x, frame.z);
  const Vec3 flange_z = flange_pose.rotation.col(2);
  last.alpha_rad = std::fabs(flange_z.dot(frame6.x)) < 1e-9 ? signed_angle(frame.z, flange_z, frame6.x) : 0.0;
  frame6.origin = frame.origin + last.d_m * frame.z + last.a_m * frame6.x;
  frame6.z = Eigen::AngleAxisd(last.alpha_rad, frame6.x).toRotationMatrix() * frame.z;
  Mat3 rotation6;
  rotation6.col(0) = frame6.x;
  rotation6.col(2) = frame6.z;
  rotation6.col(1) = frame6.z.cross(frame6.x);
  for (std::size_t k = 0; k < tools.size(); ++k) {
    target_tool(&model, static_cast<int>(k)) =
        rotation6.transpose() * (pose_at_zero(tree, tools[k]).translation_m - frame6.origin);
  }
  RobotDescription out;
  out.robot = tree.robot_name;
  out.model = model;
  out.target_count = static_cast<int>(tools.size());
  const bool offset_base = base.alpha0_rad != 0.0 || base.a0_m != 0.0;
  out.convention = offset_base ? DhConvention::modified : DhConvention::standard;
  out.modified_base = base;
  for (std::size_t k = 0; k < chain.size(); ++k) {  // a continuous joint (or one without <limit>) keeps +-2 pi
    if (!chain[k]->has_limit) continue;
    out.has_joint_limits = true;
    out.lower_rad(static_cast<Eigen::Index>(k)) = chain[k]->lower_rad;
    out.upper_rad(static_cast<Eigen::Index>(k)) = chain[k]->upper_rad;
  }
  // Exact or refused: the model's FK against the URDF's own on random poses.
  Random random(1);
  double worst_m = 0.0;
  for (int pose = 0; pose < 100; ++pose) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-3.0, 3.0);
    for (std::size_t k = 0; k < tools.size(); ++k) {
      const Vec3 urdf_point = pose_at(tree, tools[k], q).translation_m;
      const Vec3 dh_point = base.transform().apply(fk_target_point(model, q, static_cast<int>(k)));
      worst_m = std::fmax(worst_m, (urdf_point - dh_point).norm());
    }
  }
  if (!(worst_m <= 1e-9)) {
    char text_m[64];
    std::snprintf(text_m, sizeof text_m, "%.3g m", worst_m);
    return refuse(" its chain cannot be written as DH exactly: the DH model's tool points differ from the URDF's by " +
                  std::string(text_m));
  }
  *description = out;
  return port::Error{};
}

}  // namespace hivecal::textio
