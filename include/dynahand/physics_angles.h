/// @file
/// Joint angle convention shared by the physics limits/drives and the hand model.
///
/// A joint has a frame fixed in the parent body and one fixed in the child body; at zero angles
/// they coincide. The relative rotation R = frameParentWorld^-1 * frameChildWorld is split as
/// R = swing * twist: twist is a rotation about the joint frame's X axis (along the child bone),
/// swing the shortest rotation taking X to d = R * X. From d = (dx, dy, dz):
///   flexion   = atan2(dy, dx)           rotation of the bone about the joint Z axis, rad
///   abduction = asin(-dz)               rotation of the bone about the joint Y axis, rad
///   twist     = angle of twist about X, in (-pi, pi], rad
/// composeJointRotation() is the exact inverse for |abduction| < pi/2.
#pragma once

#include "dynahand/core.h"

namespace dynahand::physics {

/// Indices of the three angles in a (flexion, abduction, twist) vector.
struct JointAxes {
  static constexpr int kFlexion = 0;    ///< about the joint Z axis
  static constexpr int kAbduction = 1;  ///< about the joint Y axis
  static constexpr int kTwist = 2;      ///< about the joint X axis (along the child bone)
};

/// (flexion, abduction, twist) of a relative joint rotation, rad.
Vec3 decomposeJointRotation(const Quat& relative);
/// The relative joint rotation with these (flexion, abduction, twist) angles, rad.
Quat composeJointRotation(const Vec3& angles);

}  // namespace dynahand::physics
