// Row construction helpers shared by the solver and the contact stage (see solver.cpp).
#pragma once

#include <algorithm>
#include <limits>

#include "physics/world_impl.h"

namespace dynahand::physics {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Position bias for a row whose error C must go to zero (two-sided) or stay >= 0 (one-sided).
struct Bias {
  float solve, relax;
};
inline Bias twoSidedBias(float c, float erp, float invH) {
  return {erp * c * invH, 0.0f};
}
inline Bias oneSidedBias(float c, float erp, float invH, float maxSpeed = kInf) {
  if (c > 0.0f) return {c * invH, c * invH};  // speculative: may approach, not cross
  return {std::max(erp * c * invH, -maxSpeed), 0.0f};
}

// Soft constraint coefficients (as Box2D v3's b2MakeSoft): a spring of `hertz` with damping
// ratio `zeta` integrated implicitly over one step h. Used by contacts in the biased sweeps:
// increment = -effMass massScale (Jv + biasRate C) - impulseScale accumulated.
struct Softness {
  float biasRate, massScale, impulseScale;
};
inline Softness makeSoft(float hertz, float zeta, float h) {
  if (hertz <= 0.0f) return {0.0f, 1.0f, 0.0f};
  const float omega = 2.0f * 3.14159265f * hertz;
  const float a1 = 2.0f * zeta + h * omega;
  const float a2 = h * omega * a1;
  const float a3 = 1.0f / (1.0f + a2);
  return {omega / a1, a2 * a3, a3};
}

// Appends rows to m.rows, computing the inverse-inertia products and the effective mass.
struct RowBuilder {
  World::Impl& m;  // rows are appended to m.rows
  void add(int slotA, int slotB, const Vec3& axis, const Vec3& angA, const Vec3& angB, Bias bias,
           float lower, float upper, float warm, bool relax, int frictionOf = -1,
           float friction = 0.0f) {
    const SolverBody& a = m.solverBodies[static_cast<std::size_t>(slotA)];
    const SolverBody& b = m.solverBodies[static_cast<std::size_t>(slotB)];
    Row r;
    r.axis = axis;
    r.angA = angA;
    r.angB = angB;
    r.invIAngA = applyInvInertia(a, angA);
    r.invIAngB = applyInvInertia(b, angB);
    r.slotA = slotA;
    r.slotB = slotB;
    r.invMassA = a.invMass;
    r.invMassB = b.invMass;
    const float k =
        (a.invMass + b.invMass) * axis.squaredNorm() + angA.dot(r.invIAngA) + angB.dot(r.invIAngB);
    r.effMass = k > 0.0f ? 1.0f / k : 0.0f;
    r.bias = bias.solve;
    r.relaxBias = bias.relax;
    r.massScale = 1.0f;
    r.impulseScale = 0.0f;
    r.lower = lower;
    r.upper = upper;
    r.impulse = std::clamp(warm, lower, upper);
    r.frictionOf = frictionOf;
    r.friction = friction;
    r.relax = relax;
    r.angular = axis.isZero(0.0f);
    r.blockSize = 1;
    r.blockPasses = 1;
    r.store = nullptr;
    m.rows.push_back(r);
  }
};

}  // namespace dynahand::physics
