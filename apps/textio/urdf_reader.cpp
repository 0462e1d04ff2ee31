// Reading a URDF serial arm into the library's DH model (docs/formats.md "URDF in").
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "textio/delimited.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_kinematics.hpp"
#include "textio/urdf.hpp"

namespace hivecal::textio {
namespace {

// --- a streaming XML tag reader: what a URDF's joints and links need ------------------------
//
// One pass over the text, one tag at a time: nothing is kept of a tag once it is read, so the
// memory is the joints' (below) and a stack of open elements no deeper than kMaxXmlDepth.

/// Deepest element nesting read (a URDF nests five: robot, link, visual, geometry, mesh).
constexpr int kMaxXmlDepth = 64;

/// A refusal: the line at fault (0: none) and what is wrong.
struct Refusal {
  int line = 0;      ///< 1-based line of the document, 0 when the fault has none
  std::string what;  ///< the message after "file:line: "
};

bool refuse_at(int line, std::string what, Refusal* refusal) {
  *refusal = Refusal{line, std::move(what)};
  return false;
}

struct XmlAttribute {
  std::string_view key;    ///< as written
  std::string_view value;  ///< between the quotes, as written
};

/// One tag as read; the views point into the document.
struct XmlTag {
  std::string_view name;                 ///< element name ("joint", "origin", ...)
  std::vector<XmlAttribute> attributes;  ///< in the order written
  int line = 0;                          ///< 1-based line of the '<'
  int depth = 0;                         ///< nesting depth of the element (the root: 0)
  bool closing = false;                  ///< </name>
  bool self_closing = false;             ///< <name ... />

  /// The value of attribute `key`, or nullptr.
  const std::string_view* find(std::string_view key) const {
    for (const XmlAttribute& attribute : attributes)
      if (attribute.key == key) return &attribute.value;
    return nullptr;
  }
  /// The value of attribute `key`, or "".
  std::string_view get(std::string_view key) const {
    const std::string_view* value = find(key);
    return value == nullptr ? std::string_view() : *value;
  }
};

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/// The tags of a document in order, comments, declarations and text skipped.
class XmlTagReader {
 public:
  explicit XmlTagReader(std::string_view text) : text_(text) {}

  /// The next tag into *tag; false at the end of the document (refusal->what empty) or on
  /// malformed markup (*refusal names the line).
  bool next(XmlTag* tag, Refusal* refusal) {
    for (;;) {
      const std::size_t open = text_.find('<', at_);
      if (open == std::string_view::npos) {
        if (open_.empty()) return refuse_at(0, "", refusal);
        return refuse_at(open_.back().line, "<" + port::printable(open_.back().name) + "> is never closed", refusal);
      }
      advance_to(open);
      const std::string_view rest = text_.substr(open);
      const char* end_mark = rest.compare(0, 4, "<!--") == 0                                  ? "-->"
                             : rest.compare(0, 9, "<![CDATA[") == 0                           ? "]]>"
                             : rest.compare(0, 2, "<?") == 0 || rest.compare(0, 2, "<!") == 0 ? ">"
                                                                                              : nullptr;
      if (end_mark == nullptr) return read_tag(open, tag, refusal);
      const std::size_t end = text_.find(end_mark, open);
      if (end == std::string_view::npos) return refuse_at(line_, "unterminated comment or declaration", refusal);
      advance_to(end + std::string_view(end_mark).size());
    }
  }

 private:
  struct OpenElement {
    std::string_view name;
    int line;
  };

  /// Moves to `to`, counting the lines passed.
  void advance_to(std::size_t to) {
    line_ += static_cast<int>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(at_),
                                         text_.begin() + static_cast<std::ptrdiff_t>(to), '\n'));
    at_ = to;
  }

  /// The tag starting at `open` ('<').
  bool read_tag(std::size_t open, XmlTag* tag, Refusal* refusal) {
    const int tag_line = line_;
    std::size_t close = open + 1;
    for (char quote = 0; close < text_.size(); ++close) {
      const char c = text_[close];
      if (quote != 0) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        break;
      }
    }
    if (close >= text_.size()) return refuse_at(tag_line, "unterminated tag", refusal);
    std::string_view body = text_.substr(open + 1, close - open - 1);
    advance_to(close + 1);
    tag->line = tag_line;
    tag->closing = !body.empty() && body.front() == '/';
    tag->self_closing = !tag->closing && !body.empty() && body.back() == '/';
    if (tag->closing) body.remove_prefix(1);
    if (tag->self_closing) body.remove_suffix(1);
    std::size_t i = 0;
    while (i < body.size() && !is_blank(body[i])) ++i;
    tag->name = body.substr(0, i);
    if (!read_attributes(body.substr(i), tag, refusal)) return false;
    if (tag->closing) {
      if (open_.empty() || open_.back().name != tag->name) {
        return refuse_at(tag_line,
                         "</" + port::printable(tag->name) + "> closes " +
                             (open_.empty() ? std::string("nothing")
                                            : "<" + port::printable(open_.back().name) + "> of line " +
                                                  std::to_string(open_.back().line)),
                         refusal);
      }
      open_.pop_back();
      tag->depth = static_cast<int>(open_.size());
      return true;
    }
    tag->depth = static_cast<int>(open_.size());
    if (!tag->self_closing) {
      if (open_.size() >= static_cast<std::size_t>(kMaxXmlDepth)) {
        return refuse_at(tag_line, "elements nested deeper than " + std::to_string(kMaxXmlDepth) + ": not a URDF",
                         refusal);
      }
      open_.push_back(OpenElement{tag->name, tag_line});
    }
    return true;
  }

  /// key="value" pairs of a tag's body after its name.
  bool read_attributes(std::string_view body, XmlTag* tag, Refusal* refusal) const {
    tag->attributes.clear();
    std::size_t i = 0;
    const auto skip_blanks = [&] {
      while (i < body.size() && is_blank(body[i])) ++i;
    };
    for (;;) {
      skip_blanks();
      if (i >= body.size()) return true;
      const std::size_t key_start = i;
      while (i < body.size() && body[i] != '=' && !is_blank(body[i])) ++i;
      const std::string_view key = body.substr(key_start, i - key_start);
      skip_blanks();
      if (i >= body.size() || body[i] != '=')
        return refuse_at(tag->line, "attribute " + port::quoted(key) + " without a value", refusal);
      ++i;
      skip_blanks();
      if (i >= body.size() || (body[i] != '"' && body[i] != '\''))
        return refuse_at(tag->line, "attribute " + port::quoted(key) + " value not quoted", refusal);
      const char quote = body[i++];
      const std::size_t end = body.find(quote, i);  // found: the tag's end was searched outside quotes
      tag->attributes.push_back(XmlAttribute{key, body.substr(i, end - i)});
      i = end + 1;
    }
  }
  std::string_view text_;
  std::size_t at_ = 0;
  int line_ = 1;
  std::vector<OpenElement> open_;  ///< the elements open at at_, outermost first
};

/// Three numbers of an attribute ("x y z"); `fallback` when absent.
bool read_triple(const XmlTag& tag, const char* key, const Vec3& fallback, Vec3* value, Refusal* refusal) {
  const std::string_view* text = tag.find(key);
  if (text == nullptr) {
    *value = fallback;
    return true;
  }
  int count = 0;
  bool numbers = true;
  for (std::size_t i = 0; i < text->size();) {
    while (i < text->size() && is_blank((*text)[i])) ++i;
    if (i >= text->size()) break;
    const std::size_t start = i;
    while (i < text->size() && !is_blank((*text)[i])) ++i;
    if (count < 3) numbers = numbers && parse_double(text->substr(start, i - start), &(*value)(count));
    ++count;
  }
  if (count != 3 || !numbers || !std::isfinite(value->sum())) {
    return refuse_at(
        tag.line, "<" + port::printable(tag.name) + " " + key + "> must be three numbers, not " + port::quoted(*text),
        refusal);
  }
  return true;
}

// --- the kinematic tree ------------------------------------------------------------------

/// The joint types a serial arm is made of.
enum class UrdfJointType { revolute, continuous, prismatic, fixed };

struct UrdfJoint {
  std::string_view name, parent, child;  ///< as written (views into the document)
  UrdfJointType type = UrdfJointType::fixed;
  int line = 0;                  ///< line of <joint>
  RigidTransform origin;         ///< parent link -> joint frame
  Vec3 axis = Vec3::UnitX();     ///< in the joint frame (URDF's default is x)
  bool has_limit = false;        ///< <limit lower upper> given
  double lower = 0.0;            ///< lowest position [rad], a prismatic joint's [m]
  double upper = 0.0;            ///< highest position [rad], a prismatic joint's [m]
  int mimic_line = 0;            ///< line of its <mimic>, 0 without
  std::string_view mimic_joint;  ///< the joint its <mimic> follows
  bool movable() const { return type != UrdfJointType::fixed; }
  bool slides() const { return type == UrdfJointType::prismatic; }
};

constexpr std::size_t kNoJoint = static_cast<std::size_t>(-1);

/// A link as the joints see it (one table for every link: one look-up per name).
struct UrdfLink {
  int line = 0;                              ///< line of its <link>, 0 when only joints name it
  std::size_t parent_joint = kNoJoint;       ///< the joint it is the child of
  std::size_t first_child_joint = kNoJoint;  ///< a joint it is the parent of (more through next_sibling)
};

/// The joints of a URDF and how they hang together: the parent joint of each link and, for
/// walking down, the joints below each link as a list through next_sibling.
struct UrdfTree {
  std::string_view robot_name;
  std::vector<UrdfJoint> joints;                         ///< in file order
  std::unordered_map<std::string_view, UrdfLink> links;  ///< by name: every link a <link> or a joint names
  std::vector<std::size_t> next_sibling;  ///< per joint: the next joint of the same parent link, or kNoJoint

  /// The joint whose child `link` is, or kNoJoint.
  std::size_t parent_joint(std::string_view link) const {
    const auto found = links.find(link);
    return found == links.end() ? kNoJoint : found->second.parent_joint;
  }
  /// A joint whose parent `link` is, or kNoJoint.
  std::size_t first_child_joint(std::string_view link) const {
    const auto found = links.find(link);
    return found == links.end() ? kNoJoint : found->second.first_child_joint;
  }
};

bool read_joint_type(const XmlTag& tag, UrdfJoint* joint, Refusal* refusal) {
  const std::string_view type = tag.get("type");
  if (type == "revolute") {
    joint->type = UrdfJointType::revolute;
  } else if (type == "continuous") {
    joint->type = UrdfJointType::continuous;
  } else if (type == "prismatic") {
    joint->type = UrdfJointType::prismatic;
  } else if (type == "fixed") {
    joint->type = UrdfJointType::fixed;
  } else {
    const char* why = type == "floating" ? " (a free body, six degrees of freedom)"
                      : type == "planar" ? " (a motion in a plane, three degrees of freedom)"
                                         : "";
    return refuse_at(tag.line,
                     "joint " + port::quoted(joint->name) + " is " +
                         (type.empty() ? "without a type" : port::quoted(type)) + why +
                         ": only revolute, continuous, prismatic and fixed joints make a serial arm hivecal models",
                     refusal);
  }
  return true;
}

/// An element inside <joint> (depth 2) into *joint.
bool read_joint_element(const XmlTag& tag, UrdfJoint* joint, Refusal* refusal) {
  if (tag.name == "parent") joint->parent = tag.get("link");
  if (tag.name == "child") joint->child = tag.get("link");
  if (tag.name == "origin") {
    UrdfOrigin origin;
    if (!read_triple(tag, "xyz", Vec3::Zero(), &origin.xyz_m, refusal) ||
        !read_triple(tag, "rpy", Vec3::Zero(), &origin.rpy_rad, refusal)) {
      return false;
    }
    static const char* const kNames[2][3] = {{"x", "y", "z"}, {"roll", "pitch", "yaw"}};
    for (int axis = 0; axis < 3; ++axis) {  // the robot description's bounds
      for (int angle = 0; angle < 2; ++angle) {
        const std::string beyond = angle == 0 ? beyond_bound(origin.xyz_m(axis), ModelQuantity::length)
                                              : beyond_bound(origin.rpy_rad(axis), ModelQuantity::angle);
        if (beyond.empty()) continue;
        return refuse_at(tag.line,
                         "joint " + port::quoted(joint->name) + " <origin " + (angle == 0 ? "xyz" : "rpy") + ">, " +
                             kNames[angle][axis] + beyond,
                         refusal);
      }
    }
    joint->origin = urdf_transform(origin);
  }
  const bool limited = joint->type == UrdfJointType::revolute || joint->slides();  // continuous: none
  if (tag.name == "limit" && limited && tag.find("lower") != nullptr && tag.find("upper") != nullptr) {
    const double bound = joint->slides() ? kMaxJointTravel_m : kMaxJointLimit_rad;
    if (!parse_double(tag.get("lower"), &joint->lower) || !parse_double(tag.get("upper"), &joint->upper) ||
        !(joint->lower < joint->upper) || !(std::fabs(joint->lower) <= bound) || !(std::fabs(joint->upper) <= bound)) {
      return refuse_at(tag.line,
                       "joint " + port::quoted(joint->name) + " <limit>: lower below upper, both numbers within " +
                           (joint->slides() ? format_double(bound) + " m (a prismatic joint; millimetres?)"
                                            : std::string("two turns (4 pi rad)")),
                       refusal);
    }
    joint->has_limit = true;
  }
  if (tag.name == "mimic") {
    joint->mimic_line = tag.line;
    joint->mimic_joint = tag.get("joint");
  }
  if (tag.name == "axis") {
    if (!read_triple(tag, "xyz", Vec3::UnitX(), &joint->axis, refusal)) return false;
    if (!(joint->axis.norm() > 1e-9))
      return refuse_at(joint->line, "joint " + port::quoted(joint->name) + ": its axis is zero", refusal);
    joint->axis.normalize();
  }
  return true;
}

/// A joint read whole into the tree: its links named, not the same link, each link with one
/// parent joint.
bool add_joint(const UrdfJoint& joint, UrdfTree* tree, Refusal* refusal) {
  const std::string who = "joint " + port::quoted(joint.name);
  if (joint.parent.empty() || joint.child.empty())
    return refuse_at(joint.line, who + " needs a parent and a child link", refusal);
  if (joint.parent == joint.child) {
    return refuse_at(joint.line,
                     who + " has link " + port::quoted(joint.child) + " as its parent and its child: a loop", refusal);
  }
  const std::size_t index = tree->joints.size();
  UrdfLink& child = tree->links[joint.child];
  if (child.parent_joint != kNoJoint) {
    const UrdfJoint& first = tree->joints[child.parent_joint];
    return refuse_at(joint.line,
                     who + ": link " + port::quoted(joint.child) + " already has a parent joint, " +
                         port::quoted(first.name) + " of line " + std::to_string(first.line) +
                         " (a loop, or not a tree)",
                     refusal);
  }
  child.parent_joint = index;
  UrdfLink& parent = tree->links[joint.parent];
  tree->next_sibling.push_back(parent.first_child_joint);
  parent.first_child_joint = index;
  tree->joints.push_back(joint);
  return true;
}

/// *first_line (0: not yet) becomes `line`; a name given twice (links, joints) is refused.
bool unique_name(int* first_line, const char* kind, std::string_view name, int line, Refusal* refusal) {
  if (*first_line == 0) {
    *first_line = line;
    return true;
  }
  return refuse_at(line,
                   std::string("a second ") + kind + " named " + port::quoted(name) + " (the first at line " +
                       std::to_string(*first_line) + "): each " + kind + " needs a name of its own",
                   refusal);
}

/// The tree of the document's joints, read in one pass.
bool read_tree(std::string_view text, UrdfTree* tree, Refusal* refusal) {
  // Room for every joint and link at once: growing by doubling would hold up to three times
  // their size, and rehash the tables each time.
  const auto count = [&](std::string_view tag) {
    std::size_t n = 0;
    for (std::size_t at = text.find(tag); at != std::string_view::npos; at = text.find(tag, at + 1)) ++n;
    return n;
  };
  const std::size_t joint_tags = count("<joint");
  tree->joints.reserve(joint_tags);
  tree->next_sibling.reserve(joint_tags);
  tree->links.reserve(std::max(count("<link"), joint_tags + 1));
  std::unordered_map<std::string_view, int> joint_lines;  // the line of each joint name
  joint_lines.reserve(joint_tags);
  XmlTagReader reader(text);
  XmlTag tag;
  int root_line = 0;      // the <robot> element's
  bool in_joint = false;  // inside a <joint> of the robot
  UrdfJoint joint;
  while (reader.next(&tag, refusal)) {
    if (root_line == 0) {
      if (tag.name != "robot" || tag.closing) break;
      root_line = tag.line;
      tree->robot_name = tag.get("name");
    } else if (tag.depth == 0 && !tag.closing) {
      return refuse_at(tag.line,
                       "a second top-level element <" + port::printable(tag.name) + "> after the <robot> of line " +
                           std::to_string(root_line) + ": a URDF is one <robot> element (two files joined?)",
                       refusal);
    } else if (tag.depth == 1 && tag.name == "link" && !tag.closing) {
      if (!unique_name(&tree->links[tag.get("name")].line, "link", tag.get("name"), tag.line, refusal)) return false;
    } else if (tag.depth == 1 && tag.name == "joint" && !tag.closing) {
      joint = UrdfJoint();
      joint.line = tag.line;
      joint.name = tag.get("name");
      if (!unique_name(&joint_lines[joint.name], "joint", joint.name, tag.line, refusal) ||
          !read_joint_type(tag, &joint, refusal)) {
        return false;
      }
      in_joint = !tag.self_closing;
      if (tag.self_closing && !add_joint(joint, tree, refusal)) return false;
    } else if (in_joint && tag.depth == 1 && tag.closing) {
      in_joint = false;
      if (!add_joint(joint, tree, refusal)) return false;
    } else if (in_joint && tag.depth == 2 && !tag.closing) {
      if (!read_joint_element(tag, &joint, refusal)) return false;
    }
  }
  if (!refusal->what.empty()) return false;
  if (root_line == 0) return refuse_at(0, "not a URDF: the document is no <robot>", refusal);
  return true;
}

/// The joints from the root to `link`, root first; refused when the parents go round in a loop.
bool path_to_root(const UrdfTree& tree, std::string_view link, std::vector<const UrdfJoint*>* path, Refusal* refusal) {
  path->clear();
  for (std::size_t parent = tree.parent_joint(link); parent != kNoJoint;
       parent = tree.parent_joint(path->back()->parent)) {
    if (path->size() == tree.joints.size()) {
      return refuse_at(path->back()->line,
                       "the joints above link " + port::quoted(link) + " go round in a loop: no root link", refusal);
    }
    path->push_back(&tree.joints[parent]);
  }
  std::reverse(path->begin(), path->end());
  return true;
}

/// A movable joint of the arm with the fixed part of the chain before it.
struct ChainJoint {
  const UrdfJoint* joint = nullptr;
  RigidTransform
      before;  ///< the previous chain joint's frame after its motion (the root for the first) -> this joint's frame
};

/// The arm along `path` (root first, ending at its last movable joint): its movable joints, each
/// with the fixed joints before it folded into one transform.
void arm_chain(const std::vector<const UrdfJoint*>& path, std::vector<ChainJoint>* chain) {
  chain->clear();
  RigidTransform fixed;
  for (const UrdfJoint* joint : path) {
    fixed = fixed.then_after(joint->origin);
    if (!joint->movable()) continue;
    chain->push_back(ChainJoint{joint, fixed});
    fixed = RigidTransform{};
  }
}

/// What a joint at position `q` does to its child: a turn about its axis [rad], or a slide
/// along it [m].
RigidTransform joint_motion(const UrdfJoint& joint, double q) {
  if (joint.slides()) return RigidTransform{Mat3::Identity(), q * joint.axis};
  return RigidTransform{Eigen::AngleAxisd(q, joint.axis).toRotationMatrix(), Vec3::Zero()};
}

/// The frame of the last chain joint after its motion, in the root frame, at joints `q`.
RigidTransform chain_end_at(const std::vector<ChainJoint>& chain, const JointVector& q) {
  RigidTransform pose;
  for (std::size_t k = 0; k < chain.size(); ++k)
    pose = pose.then_after(chain[k].before).then_after(joint_motion(*chain[k].joint, q(static_cast<Eigen::Index>(k))));
  return pose;
}

/// The frame of chain joint k in the root frame at q = 0.
RigidTransform joint_frame_at_zero(const std::vector<ChainJoint>& chain, std::size_t k) {
  RigidTransform pose;
  for (std::size_t i = 0; i <= k; ++i) pose = pose.then_after(chain[i].before);
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

// --- the arm's end: tool links and the flange ------------------------------------------------

/// The links fixed below `link` (itself included): the tips (links with nothing below them)
/// that may carry a tool point, how many tips there are and the first few of their names, and
/// whether a 'flange' link is among them.
struct EndLinks {
  static constexpr std::size_t kShownTips = 4;  ///< tips named in a message
  std::vector<std::string_view> named_tips;     ///< tips named tcp, tcp_2, tcp_3 or tool0
  std::size_t tip_count = 0;                    ///< tips of any name
  std::vector<std::string_view> first_tips;     ///< the first tips met (up to kShownTips)
  bool has_flange = false;                      ///< a link 'flange' is among them
};

/// The links below `link`, walked without recursion (a stack of the joints still to visit).
void end_links(const UrdfTree& tree, std::string_view link, EndLinks* end) {
  std::vector<std::size_t> pending;
  for (std::string_view at = link;;) {
    end->has_flange = end->has_flange || at == "flange";
    const std::size_t below = tree.first_child_joint(at);
    if (below == kNoJoint) {
      ++end->tip_count;
      if (end->first_tips.size() < EndLinks::kShownTips) end->first_tips.push_back(at);
      for (const char* tool : {"tcp", "tcp_2", "tcp_3", "tool0"})
        if (at == tool) end->named_tips.push_back(at);
    } else {
      for (std::size_t j = below; j != kNoJoint; j = tree.next_sibling[j]) pending.push_back(j);
    }
    if (pending.empty()) return;
    at = tree.joints[pending.back()].child;
    pending.pop_back();
  }
}

/// The pose of `link` in the frame of `above`, a link above it (or itself), at q = 0.
RigidTransform pose_below(const UrdfTree& tree, std::string_view above, std::string_view link) {
  RigidTransform pose;
  for (std::string_view at = link; at != above;) {
    const UrdfJoint& joint = tree.joints[tree.parent_joint(at)];
    pose = joint.origin.then_after(pose);
    at = joint.parent;
  }
  return pose;
}

/// A link that carries a tool point: its name and its pose in the frame of the arm's last joint.
struct ToolLink {
  std::string_view name;
  RigidTransform pose;
};

/// The links of the tool points among the arm's tips: tcp (tcp_2, tcp_3), else tool0, else the only tip.
bool tool_links(const UrdfTree& tree, std::string_view arm_end, const EndLinks& end, std::vector<ToolLink>* tools,
                std::string* what) {
  const auto has = [&](std::string_view name) {
    return std::find(end.named_tips.begin(), end.named_tips.end(), name) != end.named_tips.end();
  };
  std::vector<std::string_view> names;
  if (has("tcp")) {
    for (const char* tool : {"tcp", "tcp_2", "tcp_3"})
      if (has(tool)) names.push_back(tool);
  } else if (has("tool0")) {
    names.push_back("tool0");
  } else if (end.tip_count == 1) {
    names.push_back(end.first_tips[0]);
  } else {
    std::string shown;
    for (const std::string_view tip : end.first_tips) shown += (shown.empty() ? "" : ", ") + port::quoted(tip);
    if (end.tip_count > end.first_tips.size())
      shown += " and " + std::to_string(end.tip_count - end.first_tips.size()) + " more";
    *what = "the arm ends in several links (" + shown + "): name the tool link 'tcp' or 'tool0'";
    return false;
  }
  for (const std::string_view name : names) tools->push_back(ToolLink{name, pose_below(tree, arm_end, name)});
  return true;
}

}  // namespace

port::Error parse_urdf_description(std::string_view text, const std::string& source_name,
                                   RobotDescription* description) {
  UrdfTree tree;
  Refusal refusal;
  const auto refuse = [&](const Refusal& why) {
    return port::Error::input(source_name + (why.line > 0 ? ":" + std::to_string(why.line) : std::string()) + ": " +
                              why.what);
  };
  const auto refuse_whole = [&](const std::string& why) { return refuse(Refusal{0, why}); };
  if (!read_tree(text, &tree, &refusal)) return refuse(refusal);
  // The arm: the movable joints on the path to the tips, 1 .. kMaxJoints of them, in one line.
  std::size_t movable_count = 0;
  const UrdfJoint* last_movable = nullptr;
  for (const UrdfJoint& joint : tree.joints) {
    if (!joint.movable()) continue;
    if (++movable_count > static_cast<std::size_t>(kMaxJoints)) {
      return refuse(Refusal{joint.line, "joint " + port::quoted(joint.name) + " is movable joint " +
                                            std::to_string(movable_count) + ": hivecal models arms of 1 to " +
                                            std::to_string(kMaxJoints) + " joints (this build's capacity)"});
    }
    last_movable = &joint;
  }
  if (last_movable == nullptr) {
    return refuse_whole("no movable joint: an arm has 1 to " + std::to_string(kMaxJoints) +
                        " revolute, continuous or prismatic joints");
  }
  std::vector<const UrdfJoint*> path;
  if (!path_to_root(tree, last_movable->child, &path, &refusal)) return refuse(refusal);
  std::vector<ChainJoint> chain;
  arm_chain(path, &chain);
  if (chain.size() != movable_count) {
    return refuse(Refusal{last_movable->line, "the movable joints are not one serial chain (joint " +
                                                  port::quoted(last_movable->name) + " has only " +
                                                  std::to_string(chain.size()) + " movable joints before it)"});
  }
  for (const ChainJoint& link : chain) {
    if (link.joint->mimic_line == 0) continue;
    return refuse(Refusal{link.joint->mimic_line, "joint " + port::quoted(link.joint->name) + " follows joint " +
                                                      port::quoted(link.joint->mimic_joint) +
                                                      " (<mimic>): each joint of the arm must move on its own"});
  }
  EndLinks end;
  end_links(tree, last_movable->child, &end);
  std::vector<ToolLink> tools;
  std::string what;
  if (!tool_links(tree, last_movable->child, end, &tools, &what)) return refuse_whole(what);
  // Axes at q = 0 in the root frame, then the DH frames between them.
  ModifiedDhBase base;
  Frame frame;
  // A slide moves along its direction wherever its line is drawn: joint 1's through the root's
  // origin (no base offset), a later one's through its joint frame.
  const RigidTransform joint1 = joint_frame_at_zero(chain, 0);
  const Vec3 joint1_point = chain[0].joint->slides() ? Vec3::Zero() : joint1.translation_m;
  if (!base_frame(joint1_point, joint1.rotation * chain[0].joint->axis, &base, &frame, &what))
    return refuse_whole(what);
  RobotModel model;
  model.joint_count = static_cast<int>(chain.size());
  for (std::size_t k = 0; k < chain.size(); ++k)
    if (chain[k].joint->slides()) set_joint_type(&model, static_cast<int>(k), JointType::prismatic);
  for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
    const RigidTransform next = joint_frame_at_zero(chain, i + 1);
    Frame following;
    model.joints[i] = dh_row(frame, next.translation_m, next.rotation * chain[i + 1].joint->axis, &following);
    frame = following;
  }
  // Frame n (the flange): at the 'flange' link fixed to the arm's end when there is one (a link
  // of that name elsewhere, a base's mounting flange, is not the arm's), else the last joint's child.
  const RigidTransform end_at_zero = joint_frame_at_zero(chain, chain.size() - 1);
  const RigidTransform flange_pose =
      end.has_flange ? end_at_zero.then_after(pose_below(tree, last_movable->child, "flange")) : end_at_zero;
  Frame frame_n;
  frame_n.z = frame.z;
  const Vec3 offset = flange_pose.translation_m - frame.origin;
  DhJoint& last = model.joints[chain.size() - 1];
  last.d_m = offset.dot(frame.z);
  const Vec3 radial = offset - last.d_m * frame.z;
  const Vec3 flange_x = flange_pose.rotation.col(0) - flange_pose.rotation.col(0).dot(frame.z) * frame.z;
  frame_n.x = radial.norm() > 1e-10 ? radial.normalized() : (flange_x.norm() > 1e-6 ? flange_x.normalized() : frame.x);
  if (radial.norm() > 1e-10 && frame_n.x.dot(frame.x) < 0.0) frame_n.x = -frame_n.x;  // as in dh_row
  last.a_m = radial.dot(frame_n.x);
  last.theta_offset_rad = signed_angle(frame.x, frame_n.x, frame.z);
  // A flange whose x lies along the last joint's axis is ROS-Industrial's (x out of the flange, as ROS's
  // ur_description writes it): its z is not frame n's, which stays on the joint's axis.
  const bool ros_industrial_flange = std::fabs(flange_pose.rotation.col(0).dot(frame.z)) > 1.0 - 1e-9;
  const Vec3 flange_z = flange_pose.rotation.col(2);
  last.alpha_rad = !ros_industrial_flange && std::fabs(flange_z.dot(frame_n.x)) < 1e-9
                       ? signed_angle(frame.z, flange_z, frame_n.x)
                       : 0.0;
  frame_n.origin = frame.origin + last.d_m * frame.z + last.a_m * frame_n.x;
  frame_n.z = Eigen::AngleAxisd(last.alpha_rad, frame_n.x).toRotationMatrix() * frame.z;
  Mat3 rotation_n;
  rotation_n.col(0) = frame_n.x;
  rotation_n.col(2) = frame_n.z;
  rotation_n.col(1) = frame_n.z.cross(frame_n.x);
  for (std::size_t k = 0; k < tools.size(); ++k) {
    target_tool(&model, static_cast<int>(k)) =
        rotation_n.transpose() * (end_at_zero.then_after(tools[k].pose).translation_m - frame_n.origin);
  }
  // A UR arm whose root is REP-103's base_link (x forward; ROS's ur_description turns UR's base,
  // x backward, by pi about z) comes out as UR's table with every a and alpha negated: it is read
  // in UR's own base instead, so that UR's deltas, calibration.conf and kinematics YAML apply.
  RigidTransform root_to_base = base.transform();
  const bool ur_base = !(base.alpha0_rad != 0.0 || base.a0_m != 0.0) && is_ur_table_turned(model);
  if (ur_base) {
    model = turned_by_pi(model);
    root_to_base = RigidTransform{Vec3(-1.0, -1.0, 1.0).asDiagonal(), Vec3::Zero()};  // Rz(pi), exactly
  }
  RobotDescription out;
  out.robot = std::string(tree.robot_name);
  out.model = model;
  out.base_turned_by_pi = ur_base;
  out.target_count = static_cast<int>(tools.size());
  const bool offset_base = base.alpha0_rad != 0.0 || base.a0_m != 0.0;
  out.convention = offset_base ? DhConvention::modified : DhConvention::standard;
  out.modified_base = base;
  for (std::size_t k = 0; k < chain.size(); ++k) {  // a continuous joint (or one without <limit>) keeps +-2 pi
    if (!chain[k].joint->has_limit) continue;
    out.has_joint_limits = true;
    out.lower_rad(static_cast<Eigen::Index>(k)) = chain[k].joint->lower;
    out.upper_rad(static_cast<Eigen::Index>(k)) = chain[k].joint->upper;
  }
  const port::Error bounded = check_model_bounds(out, source_name);  // the JSON description's bounds
  if (!bounded.ok()) return bounded;
  // Exact or refused: the model's FK against the URDF's own on random poses.
  Random random(1);
  double worst_m = 0.0;
  for (int pose = 0; pose < 100; ++pose) {
    JointVector q;
    for (int j = 0; j < model.joint_count; ++j) q(j) = random.uniform(-3.0, 3.0);  // [rad], a slide's [m]
    const RigidTransform chain_end = chain_end_at(chain, q);
    for (std::size_t k = 0; k < tools.size(); ++k) {
      const Vec3 urdf_point = chain_end.then_after(tools[k].pose).translation_m;
      const Vec3 dh_point = root_to_base.apply(fk_target_point(model, q, static_cast<int>(k)));
      worst_m = std::fmax(worst_m, (urdf_point - dh_point).norm());
    }
  }
  if (!(worst_m <= 1e-9)) {
    char text_m[64];
    std::snprintf(text_m, sizeof text_m, "%.3g m", worst_m);
    return refuse_whole(
        "its chain cannot be written as DH exactly: the DH model's tool points differ from the URDF's by " +
        std::string(text_m));
  }
  *description = out;
  return port::Error{};
}

}  // namespace hivecal::textio
