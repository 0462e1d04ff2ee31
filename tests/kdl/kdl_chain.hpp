// A URDF read by ROS's own libraries (kdl_parser, orocos KDL) for the tests that check what
// hivecal exports against them: the document's chain between two links as KDL builds it, and
// its forward kinematics for joint vectors of any length (revolute joints in rad, prismatic in m,
// in chain order). Header-only; the KDL test suite links kdl_parser and orocos-kdl.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include <string>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal::test {

/// The model's joints as KDL takes them (chain order, rad or m): its joint_count of q's entries.
inline std::vector<double> joint_values(const RobotModel& model, const JointVector& q) {
  return std::vector<double>(q.data(), q.data() + model.joint_count);
}

/// The chain of a URDF from one link to another, read by kdl_parser.
class KdlChain {
 public:
  /// Parses `urdf` (the document's text) and takes its chain from link `root` to link `tip`;
  /// false, with *error saying why, when the document does not parse or has no such chain.
  bool load(const std::string& urdf, const std::string& root, const std::string& tip, std::string* error) {
    KDL::Tree tree;
    if (!kdl_parser::treeFromString(urdf, tree)) {
      *error = "kdl_parser cannot read the document";
      return false;
    }
    if (!tree.getChain(root, tip, chain_)) {
      *error = "no chain from '" + root + "' to '" + tip + "'";
      return false;
    }
    return true;
  }

  /// Movable joints of the chain (revolute, continuous, prismatic) [-].
  unsigned joints() const { return chain_.getNrOfJoints(); }

  /// Pose of the tip in the root's frame at the movable joints' values `q` (rad, m), as KDL's
  /// recursive solver gives it; the identity when `q` has the wrong length.
  RigidTransform fk(const std::vector<double>& q) const {
    RigidTransform pose;
    if (q.size() != chain_.getNrOfJoints()) return pose;
    KDL::JntArray values(chain_.getNrOfJoints());
    for (unsigned i = 0; i < values.rows(); ++i) values(i) = q[i];
    KDL::ChainFkSolverPos_recursive solver(chain_);
    KDL::Frame frame;
    if (solver.JntToCart(values, frame) < 0) return pose;
    for (int r = 0; r < 3; ++r) {
      pose.translation_m(r) = frame.p(r);
      for (int c = 0; c < 3; ++c) pose.rotation(r, c) = frame.M(r, c);
    }
    return pose;
  }

 private:
  KDL::Chain chain_;
};

}  // namespace hivecal::test
