// Internal: building scene objects into a physics::World (scene_build.cpp).
#pragma once

#include <string>
#include <vector>

#include "dynahand/playground.h"

namespace dynahand::playground::detail {

// A prism with `sides` facets along the body's x axis and an ellipsoid hull, centred on the
// origin.
physics::ConvexShape cylinderShape(float radius, float length, int sides);
physics::ConvexShape ellipsoidShape(const Vec3& semiAxes);
// The hull of a simple object (box, sphere, cylinder, convex).
Result<physics::ConvexShape> objectShape(const ObjectSpec& object);

struct HingeRecord {
  std::string object;  // the lever/dial name
  physics::JointId joint = -1;
};

class SceneBuilder {
 public:
  SceneBuilder(physics::World& world, std::vector<SceneBody>& bodies);
  Status addObject(const ObjectSpec& object);
  physics::BodyId add(const std::string& name, const physics::ConvexShape& shape, const Pose& pose,
                      float mass, bool isStatic, float angularDamping = 0.0f);
  const std::vector<HingeRecord>& hinges() const { return hinges_; }

 private:
  void hinge(physics::BodyId mount, physics::BodyId child, const Vec3& hingePoint,
             const Vec3& anchorChild, const Quat& childRest, const ObjectSpec& object);

  physics::World& world_;
  std::vector<SceneBody>& bodies_;
  std::vector<HingeRecord> hinges_;
};

}  // namespace dynahand::playground::detail
