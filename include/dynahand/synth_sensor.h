/// @file
/// Synthetic depth-sensor profiles: turn a rendered (exact) depth image into what a real
/// camera of that kind would report. Each profile imitates a real device; its parameters
/// are documented in docs/synth.md. Seeded and reproducible: the same (seed, frame index,
/// input) always gives the same bytes, and frames can be produced in any order.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/synth_render.h"

namespace dynahand::synth {

/// The depth-sensing principle a profile imitates (which artefacts apply).
enum class SensorKind { Ideal, TimeOfFlight, StructuredLight, ActiveStereo };

/// All parameters of a profile. Fields a kind does not use are zero.
struct SensorProfile {
  std::string name;                     ///< "ideal", "tof", "structured-light", "active-stereo"
  std::string device;                   ///< the real device this profile imitates
  SensorKind kind = SensorKind::Ideal;  ///< sensing principle
  Intrinsics intrinsics;                ///< image size and pinhole parameters, pixels
  float depthScale = 0.001f;            ///< m per stored uint16 unit
  float minRange = 0.0f;                ///< m: true depth below this reads 0 (no data)
  float maxRange = 0.0f;                ///< m: true depth above this reads 0
  /// Random depth noise, Gaussian, std sigma(z) = noiseAtHalfMetre * (z / 0.5 m)^2 (ToF:
  /// amplitude falls as 1/z^2; triangulation: dz = z^2 dd / (f b)). Triangulating kinds
  /// apply it as the equivalent disparity noise.
  float noiseAtHalfMetre = 0.0f;  ///< m
  float dropoutFraction = 0.0f;   ///< independent random loss of valid pixels, fraction
  /// Time of flight: pixels at depth jumps larger than edgeJump read, with
  /// flyingPixelProbability, a depth between the two surfaces ("flying pixels").
  float edgeJump = 0.0f;                ///< m
  float flyingPixelProbability = 0.0f;  ///< fraction of edge pixels
  /// Triangulation (structured light, active stereo): depth = fx * baseline / disparity.
  float baseline = 0.0f;       ///< m, camera to projector (SL) or left to right imager (stereo)
  float disparityStep = 0.0f;  ///< px: disparities are quantised to this step
  /// Structured light: near features narrower than (2 thinRadiusPx + 1) px that stand more
  /// than edgeJump in front of their surroundings drop out with thinDropProbability;
  /// background the projector cannot see (its shadow, left of near objects) reads 0.
  int thinRadiusPx = 0;
  float thinDropProbability = 0.0f;  ///< chance that a thin near feature's pixel drops out
  bool projectorShadows = false;     ///< whether projector-shadowed background reads 0
  /// Active stereo: disc-shaped holes covering holeFraction of the image, isolated speckle
  /// outliers (speckleFraction of valid pixels, offset 2-8 cm), foreground fattened by
  /// edgeFatteningPx onto background along rows, and the left invalid band (pixels the
  /// right imager cannot see: u < fx * baseline / z).
  float holeFraction = 0.0f;
  float holeRadiusPx = 0.0f;     ///< radius of each hole, px
  float speckleFraction = 0.0f;  ///< fraction of valid pixels turned into outliers
  int edgeFatteningPx = 0;       ///< px that foreground grows onto background along rows
  bool leftInvalidBand = false;  ///< whether the left invalid band reads 0

  /// Documented statistics the tests check the simulation against:
  /// std of reported minus true depth on a flat surface at depth z (noise plus disparity
  /// and depth-unit quantisation), m.
  float expectedNoiseStd(float z) const;
  /// Fraction of a flat, frontal wall inside the range (left band excluded) reading 0.
  float expectedWallDropout() const;
};

/// The built-in profiles, in a stable order.
const std::vector<SensorProfile>& sensorProfiles();
/// Looks a profile up by name; the error lists the valid names.
Result<SensorProfile> findSensorProfile(std::string_view name);

/// Applies a profile to rendered frames. Holds its scratch buffers (no allocation per frame).
class SensorSimulator {
 public:
  /// A simulator of `profile` with noise seed `seed`.
  SensorSimulator(SensorProfile profile, std::uint64_t seed);

  const SensorProfile& profile() const { return profile_; }  ///< the simulated profile

  /// trueDepth, labels: (height x width) as DepthRenderer produces for the profile's
  /// intrinsics (0 = no surface). Writes `out` (resized on first use).
  void apply(std::span<const float> trueDepth, std::span<const PixelLabel> labels, int frameIndex,
             double timestamp, DepthFrame& out);

 private:
  void flyingPixels(std::span<const float> depth, std::uint64_t frameKey);
  void thinFeatures(std::uint64_t frameKey);
  void shadows();
  void holes(std::uint64_t frameKey);
  void fattenEdges();

  SensorProfile profile_;
  std::uint64_t seed_;
  std::vector<float> work_;      ///< (height x width) depth being degraded, m
  std::vector<float> scratch_;   ///< (height x width) filter scratch, m
  std::vector<float> scratch2_;  ///< (height x width)
};

}  // namespace dynahand::synth
