#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "model/model_test_util.h"

namespace dynahand::model {
namespace {

TEST(DefaultHandDiagnostic, Print) {
  const ArticulatedModel hand = makeDefaultHand();
  const ModelPose rest = forwardKinematics(hand, zeroAngles(hand));
  for (int b = 0; b < hand.bodyCount(); ++b) {
    const Body& body = hand.bodies()[static_cast<size_t>(b)];
    std::printf("%2d %-18s verts %3zu mass %.4f vol %.3g inscr %.4f\n", b, body.name.c_str(),
                body.shape.vertices().size(), static_cast<double>(body.mass), static_cast<double>(body.shape.volume()),
                static_cast<double>(body.shape.inscribedRadius()));
  }
  const auto kp = keypoints21(hand, rest);
  for (size_t i = 0; i < 21; ++i) {
    std::printf("%-12s %7.4f %7.4f %7.4f\n", keypoint21Names()[i], static_cast<double>(kp[i].x()),
                static_cast<double>(kp[i].y()), static_cast<double>(kp[i].z()));
  }
  for (int a = 0; a < hand.bodyCount(); ++a) {
    for (int b = a + 1; b < hand.bodyCount(); ++b) {
      if (!hand.collides(a, b)) continue;
      if (test::overlaps(hand.bodies()[static_cast<size_t>(a)].shape, rest.bodies[static_cast<size_t>(a)],
                         hand.bodies()[static_cast<size_t>(b)].shape, rest.bodies[static_cast<size_t>(b)], 0.0f)) {
        std::printf("rest overlap %s - %s\n", hand.bodies()[static_cast<size_t>(a)].name.c_str(),
                    hand.bodies()[static_cast<size_t>(b)].name.c_str());
      }
    }
  }
}

}  // namespace
}  // namespace dynahand::model
