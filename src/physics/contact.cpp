// Convex contacts. Narrow phase: libccd's MPR on both hulls inflated by margin/2 finds whether
// the pair is within the margin and a separating-direction estimate n (A to B). The manifold is
// then built from the hull faces: the face (of A or B) best aligned with n is the reference,
// the most anti-aligned face of the other hull is clipped against the reference face's side
// planes (Sutherland-Hodgman), and each clipped point within the margin becomes a contact with
// the exact separation along the reference normal. A face manifold keeps resting stacks
// stable; edge-edge contacts that clip to nothing fall back to MPR's single point.
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <span>

#include "physics/rows.h"

extern "C" {
#include <ccd/ccd.h>
}

namespace dynahand::physics {
namespace {

constexpr int kMaxClip = 256;         // polygon vertices during clipping
constexpr float kMatchDist2 = 4e-6f;  // (2 mm)^2: a contact within this of last step's is the same

struct CcdObject {
  const ConvexShape* shape;
  Pose pose;      // body frame in world
  Vec3 centre;    // a point inside (world centroid)
  float inflate;  // m added along every support direction
};

void ccdSupport(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto* o = static_cast<const CcdObject*>(obj);
  const Vec3 d(static_cast<float>(dir->v[0]), static_cast<float>(dir->v[1]),
               static_cast<float>(dir->v[2]));
  const float len = d.norm();
  Vec3 p = o->pose.transform(o->shape->support(inverseRotateVector(o->pose.q, d)));
  if (len > 0.0f) p += (o->inflate / len) * d;
  for (int k = 0; k < 3; ++k) out->v[k] = static_cast<ccd_real_t>(p[k]);
}

void ccdCentre(const void* obj, ccd_vec3_t* out) {
  const auto* o = static_cast<const CcdObject*>(obj);
  for (int k = 0; k < 3; ++k) out->v[k] = static_cast<ccd_real_t>(o->centre[k]);
}

// Index of the face whose world normal maximises dot(normal, dir).
int mostAlignedFace(const ConvexShape& s, const Quat& q, const Vec3& dir, float* bestDot) {
  const Vec3 local = inverseRotateVector(q, dir);
  int best = 0;
  float bestD = -std::numeric_limits<float>::infinity();
  for (std::size_t f = 0; f < s.faces().size(); ++f) {
    const float d = s.faces()[f].normal.dot(local);
    if (d > bestD) {
      bestD = d;
      best = static_cast<int>(f);
    }
  }
  *bestDot = bestD;
  return best;
}

// Separation of the two hulls along the unit world axis (A towards B): > 0 apart, < 0 overlap.
float separationAlong(const ConvexShape& a, const Pose& poseA, const ConvexShape& b,
                      const Pose& poseB, const Vec3& axis) {
  const Vec3 onA = poseA.transform(a.support(inverseRotateVector(poseA.q, axis)));
  const Vec3 onB = poseB.transform(b.support(inverseRotateVector(poseB.q, -axis)));
  return axis.dot(onB - onA);
}

// True when some axis shows the hulls more than `margin` apart, so MPR (~20 support calls
// on the inflated hulls) would find no contact. Exact, not a heuristic: a separating axis
// with a gap > margin proves the distance is > margin. Tried in order: the axis that
// separated this pair last step (*cachedAxis, in A's frame, zero when none), the line
// between the centres, then A's and B's own axes (side-by-side finger bones are apart along
// their width, not along the diagonal between their centres). The axis that worked is kept.
bool separatedBeyond(const ConvexShape& a, const Pose& poseA, const ConvexShape& b,
                     const Pose& poseB, const Vec3& centreLine, float margin, Vec3* cachedAxis) {
  auto separates = [&](Vec3 axis) {
    const float len = axis.norm();
    if (!(len > 1e-6f)) return false;
    axis /= len;
    if (axis.dot(centreLine) < 0.0f) axis = -axis;  // B lies on the positive side
    if (separationAlong(a, poseA, b, poseB, axis) <= margin) return false;
    if (cachedAxis) *cachedAxis = inverseRotateVector(poseA.q, axis);
    return true;
  };
  if (cachedAxis && separates(rotateVector(poseA.q, *cachedAxis))) return true;
  if (separates(centreLine)) return true;
  for (int k = 0; k < 3; ++k)
    if (separates(rotateVector(poseA.q, Vec3::Unit(k))) ||
        separates(rotateVector(poseB.q, Vec3::Unit(k))))
      return true;
  if (cachedAxis) *cachedAxis = Vec3::Zero();
  return false;
}

// MPR's direction follows the line between the two centres, so a small body against a large
// box (a fingertip low on a wall, a block near the table's edge) can get the normal of the
// wrong face and be pushed through. For a hull with few faces (boxes, walls, tables) its face
// axes are tested as separating axes, and the one of least penetration replaces MPR's
// direction when it separates better. Hulls with many faces (the hand's) add no axes.
constexpr std::size_t kFewFaces = 12;
Vec3 leastPenetrationAxis(const ConvexShape& a, const Pose& poseA, const ConvexShape& b,
                          const Pose& poseB, const Vec3& mprAxis) {
  Vec3 best = mprAxis;
  float bestSep = separationAlong(a, poseA, b, poseB, mprAxis);
  auto tryFaces = [&](const ConvexShape& s, const Quat& q, float sign) {
    if (s.faces().size() > kFewFaces) return;
    for (const Face& f : s.faces()) {
      const Vec3 axis = sign * rotateVector(q, f.normal);
      const float sep = separationAlong(a, poseA, b, poseB, axis);
      if (sep > bestSep + 1e-6f) {
        bestSep = sep;
        best = axis;
      }
    }
  };
  tryFaces(a, poseA.q, 1.0f);
  tryFaces(b, poseB.q, -1.0f);
  return best;
}

// Four of more than four clipped points that keep the manifold's area: the deepest, the
// farthest from it, and the two spanning the largest areas on either side of that diagonal.
void keepFour(std::span<const ManifoldPoint> candidates, const Vec3& refNormal,
              ManifoldPoint* points) {
  auto pick = [&](auto score) {
    std::size_t best = 0;
    float bestScore = -std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const float sc = score(candidates[i].position);
      if (sc > bestScore) {
        bestScore = sc;
        best = i;
      }
    }
    return candidates[best];
  };
  std::size_t deepest = 0;
  for (std::size_t i = 1; i < candidates.size(); ++i) {
    if (candidates[i].separation < candidates[deepest].separation) deepest = i;
  }
  const ManifoldPoint p0 = candidates[deepest];
  const ManifoldPoint p1 = pick([&](const Vec3& p) { return (p - p0.position).squaredNorm(); });
  const Vec3 diag = p1.position - p0.position;
  const ManifoldPoint p2 =
      pick([&](const Vec3& p) { return refNormal.dot(diag.cross(p - p0.position)); });
  const ManifoldPoint p3 =
      pick([&](const Vec3& p) { return -refNormal.dot(diag.cross(p - p0.position)); });
  points[0] = p0;
  points[1] = p1;
  points[2] = p2;
  points[3] = p3;
}

}  // namespace

int collideConvex(const ConvexShape& a, const Pose& poseA, const ConvexShape& b, const Pose& poseB,
                  float margin, ManifoldPoint* points, Vec3* normal, bool faceAxes,
                  Vec3* cachedAxis) {
  const CcdObject objA{&a, poseA, poseA.transform(a.centroid()), 0.5f * margin};
  const CcdObject objB{&b, poseB, poseB.transform(b.centroid()), 0.5f * margin};
  if (separatedBeyond(a, poseA, b, poseB, objB.centre - objA.centre, margin, cachedAxis)) return 0;
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccdSupport;
  ccd.support2 = ccdSupport;
  ccd.center1 = ccdCentre;
  ccd.center2 = ccdCentre;
  ccd.max_iterations = 100;
  ccd.mpr_tolerance = 1e-7;
  ccd_real_t depth = 0;
  ccd_vec3_t dir, pos;
  if (ccdMPRPenetration(&objA, &objB, &ccd, &depth, &dir, &pos) != 0) return 0;
  Vec3 n(static_cast<float>(dir.v[0]), static_cast<float>(dir.v[1]), static_cast<float>(dir.v[2]));
  if (!(n.squaredNorm() > 0.0f) || !n.allFinite()) return 0;
  n.normalize();
  if (faceAxes) n = leastPenetrationAxis(a, poseA, b, poseB, n);

  // Reference face: A's face along n or B's face along -n, whichever is better aligned
  // (ties go to A so the choice is stable).
  float dotA = 0.0f, dotB = 0.0f;
  const int faceA = mostAlignedFace(a, poseA.q, n, &dotA);
  const int faceB = mostAlignedFace(b, poseB.q, -n, &dotB);
  const bool refIsA = dotA >= dotB - 1e-3f;
  const ConvexShape& ref = refIsA ? a : b;
  const ConvexShape& inc = refIsA ? b : a;
  const Pose& refPose = refIsA ? poseA : poseB;
  const Pose& incPose = refIsA ? poseB : poseA;
  const Face& refFace = ref.faces()[static_cast<std::size_t>(refIsA ? faceA : faceB)];
  const Vec3 refNormal = refPose.rotate(refFace.normal);
  float incDot = 0.0f;
  const Face& incFace =
      inc.faces()[static_cast<std::size_t>(mostAlignedFace(inc, incPose.q, -refNormal, &incDot))];

  std::array<Vec3, kMaxClip> polyA, polyB;
  int count = 0;
  bool overflow = incFace.vertices.size() + refFace.vertices.size() > kMaxClip;
  if (!overflow) {
    for (int v : incFace.vertices)
      polyA[static_cast<std::size_t>(count++)] =
          incPose.transform(inc.vertices()[static_cast<std::size_t>(v)]);
    const std::size_t refCount = refFace.vertices.size();
    for (std::size_t e = 0; e < refCount && count > 0; ++e) {
      const Vec3 p0 =
          refPose.transform(ref.vertices()[static_cast<std::size_t>(refFace.vertices[e])]);
      const Vec3 p1 = refPose.transform(
          ref.vertices()[static_cast<std::size_t>(refFace.vertices[(e + 1) % refCount])]);
      const Vec3 outward = (p1 - p0).cross(refNormal);
      int outCount = 0;
      for (int i = 0; i < count; ++i) {
        const Vec3& s = polyA[static_cast<std::size_t>(i)];
        const Vec3& t = polyA[static_cast<std::size_t>((i + 1) % count)];
        const float ds = outward.dot(s - p0), dt = outward.dot(t - p0);
        if (ds <= 0.0f) polyB[static_cast<std::size_t>(outCount++)] = s;
        if ((ds < 0.0f) != (dt < 0.0f) && ds != dt) {
          polyB[static_cast<std::size_t>(outCount++)] = s + (ds / (ds - dt)) * (t - s);
        }
      }
      count = outCount;
      std::swap(polyA, polyB);
    }
  }
  const float refOffset = refNormal.dot(
      refPose.transform(ref.vertices()[static_cast<std::size_t>(refFace.vertices[0])]));
  std::array<ManifoldPoint, kMaxClip> candidates;
  int candidateCount = 0;
  for (int i = 0; i < (overflow ? 0 : count); ++i) {
    const Vec3& p = polyA[static_cast<std::size_t>(i)];
    const float sep = refNormal.dot(p) - refOffset;
    if (sep <= margin) candidates[static_cast<std::size_t>(candidateCount++)] = {p, sep};
  }
  *normal = refIsA ? refNormal : Vec3(-refNormal);
  if (candidateCount == 0) {
    // Edge-edge (or clipping lost everything): MPR's point and depth along its own normal.
    *normal = n;
    const Vec3 p(static_cast<float>(pos.v[0]), static_cast<float>(pos.v[1]),
                 static_cast<float>(pos.v[2]));
    points[0] = {p, margin - static_cast<float>(depth)};
    return 1;
  }
  if (candidateCount <= 4) {
    for (int i = 0; i < candidateCount; ++i) points[i] = candidates[static_cast<std::size_t>(i)];
    return candidateCount;
  }
  keepFour(std::span(candidates.data(), static_cast<std::size_t>(candidateCount)), refNormal,
           points);
  return 4;
}

void World::buildContacts(float h) {
  Impl& m = *impl_;
  WorldState& s = state_;
  m.newContacts.clear();
  m.contactView.clear();
  if (!settings_.enableContacts) {
    s.contacts.clear();
    return;
  }
  const std::size_t n = m.bodies.size();
  const float margin = settings_.contactMargin;
  std::size_t cursor = 0;  // into last step's contacts, which are sorted by pair key
  std::array<ManifoldPoint, 4> manifold;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      if (!m.collide[i * n + j]) continue;
      const int sa = m.slotOf(s, static_cast<BodyId>(i)), sb = m.slotOf(s, static_cast<BodyId>(j));
      if (sa == sb) continue;
      if (m.solverBodies[static_cast<std::size_t>(sa)].invMass == 0.0f &&
          m.solverBodies[static_cast<std::size_t>(sb)].invMass == 0.0f)
        continue;
      const float reach = m.bodies[i].boundingRadius + m.bodies[j].boundingRadius + margin;
      if ((s.position[i] - s.position[j]).squaredNorm() > reach * reach) continue;
      Vec3 nrm;
      const bool againstStatic =
          m.bodies[i].type == BodyType::Static || m.bodies[j].type == BodyType::Static;
      const int count = collideConvex(
          shapes_[static_cast<std::size_t>(m.bodies[i].shape)], pose(static_cast<BodyId>(i)),
          shapes_[static_cast<std::size_t>(m.bodies[j].shape)], pose(static_cast<BodyId>(j)),
          margin, manifold.data(), &nrm, againstStatic, &m.separatingAxis[i * n + j]);
      const auto key = static_cast<std::uint32_t>(i * n + j);
      while (cursor < s.contacts.size() && s.contacts[cursor].pair < key) ++cursor;
      for (int k = 0; k < count; ++k) {
        const ManifoldPoint& mp = manifold[static_cast<std::size_t>(k)];
        WorldState::CachedContact cc{
            key, s.orientation[i].conjugate() * (mp.position - s.position[i]), 0.0f, 0.0f, 0.0f};
        float bestD2 = kMatchDist2;
        for (std::size_t o = cursor; o < s.contacts.size() && s.contacts[o].pair == key; ++o) {
          const float d2 = (s.contacts[o].localA - cc.localA).squaredNorm();
          if (d2 < bestD2) {
            bestD2 = d2;
            cc.normalImpulse = s.contacts[o].normalImpulse;
            cc.tangentImpulse1 = s.contacts[o].tangentImpulse1;
            cc.tangentImpulse2 = s.contacts[o].tangentImpulse2;
          }
        }
        m.newContacts.push_back(cc);
        m.contactView.push_back({static_cast<BodyId>(i), static_cast<BodyId>(j), mp.position, nrm,
                                 mp.separation, 0.0f});
      }
    }
  }
  // Rows, now that the contact list (which the rows point into) is complete.
  RowBuilder rb{m};
  const float invH = 1.0f / h;
  const float mu = settings_.friction;
  // Contact spring: at most a quarter of the step rate (stable), as Box2D v3.
  const Softness contactSoft = makeSoft(settings_.contactHertz, settings_.contactDampingRatio, h);
  const std::size_t firstContactRow = m.rows.size();
  for (std::size_t k = 0; k < m.contactView.size(); ++k) {
    const ContactPoint& c = m.contactView[k];
    WorldState::CachedContact& cc = m.newContacts[k];
    const int sa = m.slotOf(s, c.a), sb = m.slotOf(s, c.b);
    const Vec3 rA = c.position - m.slotPosition[static_cast<std::size_t>(sa)];
    const Vec3 rB = c.position - m.slotPosition[static_cast<std::size_t>(sb)];
    const Vec3& nrm = c.normal;
    // Separated: speculative (may close the gap, not cross it). Penetrating beyond the slop:
    // a soft spring pushes out (Box2D v3 soft step), capped at maxCorrectionSpeed.
    Bias bias{0.0f, 0.0f};
    bool soft = false;
    if (c.separation > 0.0f) {
      bias = {c.separation * invH, c.separation * invH};
    } else {
      const float err = std::min(0.0f, c.separation + settings_.linearSlop);
      const float rate =
          settings_.contactHertz > 0.0f ? contactSoft.biasRate : settings_.contactErp * invH;
      bias = {std::max(rate * err, -settings_.maxCorrectionSpeed), 0.0f};
      soft = settings_.contactHertz > 0.0f;
    }
    const int normalRow = static_cast<int>(m.rows.size());
    rb.add(sa, sb, nrm, -rA.cross(nrm), rB.cross(nrm), bias, 0.0f, kInf, cc.normalImpulse, true);
    if (soft) {
      m.rows.back().massScale = contactSoft.massScale;
      m.rows.back().impulseScale = contactSoft.impulseScale;
    }
    m.rows.back().store = &cc.normalImpulse;
    if (mu <= 0.0f) continue;
    const Vec3 t1 = nrm.unitOrthogonal();
    const Vec3 t2 = nrm.cross(t1);
    rb.add(sa, sb, t1, -rA.cross(t1), rB.cross(t1), {0.0f, 0.0f}, -kInf, kInf, cc.tangentImpulse1,
           true, normalRow, mu);
    m.rows.back().store = &cc.tangentImpulse1;
    rb.add(sa, sb, t2, -rA.cross(t2), rB.cross(t2), {0.0f, 0.0f}, -kInf, kInf, cc.tangentImpulse2,
           true, normalRow, mu);
    m.rows.back().store = &cc.tangentImpulse2;
  }
  // Rows of one manifold (same two solver slots) form a block the sweeps iterate locally, so
  // the load spreads over its points before the next manifold is visited.
  const int inner = std::max(1, settings_.contactInnerIterations);
  for (std::size_t i = firstContactRow; i < m.rows.size();) {
    std::size_t j = i + 1;
    while (j < m.rows.size() && m.rows[j].slotA == m.rows[i].slotA &&
           m.rows[j].slotB == m.rows[i].slotB)
      ++j;
    m.rows[i].blockSize = static_cast<int>(j - i);
    m.rows[i].blockPasses = inner;
    i = j;
  }
}

void World::storeContactImpulses() {
  Impl& m = *impl_;
  for (std::size_t k = 0; k < m.contactView.size(); ++k) {
    m.contactView[k].impulse = m.newContacts[k].normalImpulse;
  }
  state_.contacts.swap(m.newContacts);
}

}  // namespace dynahand::physics
