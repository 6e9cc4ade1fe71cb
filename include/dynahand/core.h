/// @file
/// dynahand core vocabulary: Eigen aliases, rigid poses, Result<T> and hashing.
/// Units: metres, seconds, radians everywhere inside dynahand. Camera frame as
/// OpenCV: x right, y down, z forward.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>

namespace dynahand {

using Vec2 = Eigen::Vector2f;        ///< 2D float vector
using Vec3 = Eigen::Vector3f;        ///< 3D float vector (points, directions)
using Vec4 = Eigen::Vector4f;        ///< 4D float vector
using Mat3 = Eigen::Matrix3f;        ///< 3x3 float matrix
using Quat = Eigen::Quaternionf;     ///< float quaternion (rotations, unit length)
using Isometry = Eigen::Isometry3f;  ///< float rigid transform as a 4x4 matrix

/// q * v: Eigen's QuaternionBase::_transformVector written out, the same operations in the
/// same order (so the same bits), because GCC keeps Eigen's out of line, a call per rotation
/// in the solver's and the tracker's hot loops.
inline Vec3 rotateVector(const Quat& q, const Vec3& v) {
  const float qx = q.x(), qy = q.y(), qz = q.z(), qw = q.w();
  float ux = qy * v.z() - qz * v.y();  // uv = q.vec() x v
  float uy = qz * v.x() - qx * v.z();
  float uz = qx * v.y() - qy * v.x();
  ux += ux;
  uy += uy;
  uz += uz;
  return Vec3(v.x() + qw * ux + (qy * uz - qz * uy), v.y() + qw * uy + (qz * ux - qx * uz),
              v.z() + qw * uz + (qx * uy - qy * ux));
}
/// q.conjugate() * v, likewise.
inline Vec3 inverseRotateVector(const Quat& q, const Vec3& v) {
  return rotateVector(q.conjugate(), v);
}

/// A rigid transform: x_world = q * x_local + p. Plain data; q is kept unit length.
struct Pose {
  Vec3 p = Vec3::Zero();      ///< position, m
  Quat q = Quat::Identity();  ///< orientation, unit quaternion

  static Pose identity() { return {}; }  ///< no rotation, no translation
  /// A local point in world coordinates: q * local + p.
  Vec3 transform(const Vec3& local) const { return rotateVector(q, local) + p; }
  /// A local direction in world coordinates: q * local.
  Vec3 rotate(const Vec3& local) const { return rotateVector(q, local); }
  /// A world point in local coordinates (inverse of transform).
  Vec3 inverseTransform(const Vec3& world) const { return inverseRotateVector(q, world - p); }
  /// The inverse transform (world to local).
  Pose inverse() const {
    const Quat qi = q.conjugate();
    return {qi * (-p), qi};
  }
  /// (a * b).transform(x) == a.transform(b.transform(x))
  Pose operator*(const Pose& b) const { return {q * b.p + p, (q * b.q).normalized()}; }
  /// The same transform as an Eigen isometry.
  Isometry toIsometry() const {
    Isometry t = Isometry::Identity();
    t.linear() = q.toRotationMatrix();
    t.translation() = p;
    return t;
  }
};

/// Interpolates positions linearly and orientations by slerp; t in [0, 1].
Pose interpolate(const Pose& a, const Pose& b, float t);

/// Eigen's Quat::FromTwoVectors (out of line): the case of shortestRotation for nearly
/// opposite directions.
Quat shortestRotationOpposite(const Vec3& from, const Vec3& to);
/// The shortest rotation taking direction `from` to direction `to`: Eigen's
/// Quat::FromTwoVectors, bit for bit. Use this instead of FromTwoVectors: Eigen's version
/// instantiates JacobiSVD for nearly opposite directions, about 6 s of compile time in every
/// file that calls it; here that case is compiled once (shortestRotationOpposite, core).
inline Quat shortestRotation(const Vec3& from, const Vec3& to) {
  const Vec3 v0 = from.normalized();
  const Vec3 v1 = to.normalized();
  const float c = v1.dot(v0);
  if (c < -1.0f + Eigen::NumTraits<float>::dummy_precision())
    return shortestRotationOpposite(from, to);
  const float s = std::sqrt((1.0f + c) * 2.0f);
  const float invs = 1.0f / s;
  Quat q;
  q.vec() = v0.cross(v1) * invs;
  q.w() = s * 0.5f;
  return q;
}

/// A recoverable failure with a human-readable reason (files, cameras, user input).
/// Programmer errors are asserts, not Errors.
struct Error {
  std::string message;  ///< what failed and why
};

/// Either a value or an Error. A small stand-in for C++23 std::expected.
template <class T>
class [[nodiscard]] Result {
 public:
  /// Holds a value.
  Result(T value) : data_(std::move(value)) {}  // NOLINT(google-explicit-constructor)
  /// Holds an error.
  Result(Error error) : data_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return data_.index() == 0; }             ///< True when it holds a value.
  explicit operator bool() const { return ok(); }            ///< True when it holds a value.
  T& value() & { return std::get<0>(data_); }                ///< The value; only when ok().
  const T& value() const& { return std::get<0>(data_); }     ///< The value; only when ok().
  T&& value() && { return std::get<0>(std::move(data_)); }   ///< Moves the value out; ok() only.
  T& operator*() & { return value(); }                       ///< The value; only when ok().
  const T& operator*() const& { return value(); }            ///< The value; only when ok().
  T* operator->() { return &value(); }                       ///< The value; only when ok().
  const T* operator->() const { return &value(); }           ///< The value; only when ok().
  const Error& error() const { return std::get<1>(data_); }  ///< The error; only when !ok().
  const std::string& message() const { return error().message; }  ///< error().message

 private:
  std::variant<T, Error> data_;
};

/// The empty value of a successful Status.
struct Ok {};
/// Result for operations that produce nothing but can fail.
using Status = Result<Ok>;

/// 64-bit FNV-1a, used for determinism hashes of float state (bit patterns).
class Fnv1a {
 public:
  void add(const void* data, std::size_t bytes);                 ///< Hashes `bytes` bytes at data.
  void add(float v) { add(&v, sizeof v); }                       ///< Hashes the float's bits.
  void add(const Vec3& v) { add(v.data(), sizeof(float) * 3); }  ///< Hashes x, y, z bits.
  /// Hashes the coefficient bits in Eigen's order (x, y, z, w).
  void add(const Quat& q) { add(q.coeffs().data(), sizeof(float) * 4); }
  /// Hashes the position, then the orientation.
  void add(const Pose& pose) {
    add(pose.p);
    add(pose.q);
  }
  std::uint64_t value() const { return h_; }  ///< The hash of everything added so far.

 private:
  std::uint64_t h_ = 14695981039346656037ull;
};

/// Logging verbosity for the whole library (spdlog underneath): 0 errors only,
/// 1 warnings, 2 info (default), 3 debug.
void setLogLevel(int level);

}  // namespace dynahand
