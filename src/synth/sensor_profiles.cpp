// The built-in sensor profiles (docs/synth.md explains each number) and the statistics
// they promise.
#include <cmath>
#include <string>

#include "dynahand/synth_sensor.h"

namespace dynahand::synth {
namespace {

Intrinsics centred(int width, int height, float focal) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = focal;
  k.fy = focal;
  k.cx = 0.5f * static_cast<float>(width - 1);
  k.cy = 0.5f * static_cast<float>(height - 1);
  return k;
}

std::vector<SensorProfile> makeProfiles() {
  std::vector<SensorProfile> profiles;

  SensorProfile ideal;
  ideal.name = "ideal";
  ideal.device = "none: exact depth, only 0.1 mm storage quantisation (the tof camera's geometry)";
  ideal.kind = SensorKind::Ideal;
  ideal.intrinsics = centred(320, 240, 224.0f);
  ideal.depthScale = 0.0001f;
  ideal.minRange = 0.05f;
  ideal.maxRange = 6.0f;
  profiles.push_back(ideal);

  // Creative Interactive Gesture Camera / SoftKinetic DS325 (the paper's camera): 320x240
  // depth, ~72 deg horizontal field of view, 0.15-1 m working range.
  SensorProfile tof;
  tof.name = "tof";
  tof.device =
      "Creative Interactive Gesture Camera (SoftKinetic DS325), close-range time of flight";
  tof.kind = SensorKind::TimeOfFlight;
  tof.intrinsics = centred(320, 240, 224.0f);
  tof.depthScale = 0.001f;
  tof.minRange = 0.20f;
  tof.maxRange = 1.00f;
  tof.noiseAtHalfMetre = 0.0030f;
  tof.dropoutFraction = 0.005f;
  tof.edgeJump = 0.03f;
  tof.flyingPixelProbability = 0.6f;
  profiles.push_back(tof);

  // Kinect v1 / PrimeSense Carmine / Asus Xtion: 640x480, 58 deg horizontal field of view,
  // 7.5 cm projector baseline, disparity in 1/8 px steps.
  SensorProfile sl;
  sl.name = "structured-light";
  sl.device = "Microsoft Kinect v1 / PrimeSense Carmine / Asus Xtion, structured light";
  sl.kind = SensorKind::StructuredLight;
  sl.intrinsics = centred(640, 480, 570.0f);
  sl.depthScale = 0.001f;
  sl.minRange = 0.50f;
  sl.maxRange = 4.00f;
  sl.noiseAtHalfMetre = 0.0010f;
  sl.dropoutFraction = 0.010f;
  sl.edgeJump = 0.02f;
  sl.baseline = 0.075f;
  sl.disparityStep = 0.125f;
  sl.thinRadiusPx = 4;
  sl.thinDropProbability = 0.9f;
  sl.projectorShadows = true;
  profiles.push_back(sl);

  // Intel RealSense D435 in 640x480 depth mode: ~87 deg horizontal field of view, 50 mm
  // stereo baseline, ~0.08 px subpixel RMS, 1/32 px disparity steps.
  SensorProfile stereo;
  stereo.name = "active-stereo";
  stereo.device = "Intel RealSense D435 (D400 family) at 640x480, active infrared stereo";
  stereo.kind = SensorKind::ActiveStereo;
  stereo.intrinsics = centred(640, 480, 385.0f);
  stereo.depthScale = 0.001f;
  stereo.minRange = 0.175f;
  stereo.maxRange = 3.00f;
  stereo.noiseAtHalfMetre = 0.0010f;
  stereo.dropoutFraction = 0.005f;
  stereo.edgeJump = 0.02f;
  stereo.baseline = 0.050f;
  stereo.disparityStep = 1.0f / 32.0f;
  stereo.holeFraction = 0.02f;
  stereo.holeRadiusPx = 2.5f;
  stereo.speckleFraction = 0.002f;
  stereo.edgeFatteningPx = 2;
  stereo.leftInvalidBand = true;
  profiles.push_back(stereo);
  return profiles;
}

}  // namespace

float SensorProfile::expectedNoiseStd(float z) const {
  const float ratio = z / 0.5f;
  const float sigma = noiseAtHalfMetre * ratio * ratio;
  float variance = sigma * sigma + depthScale * depthScale / 12.0f;
  if (baseline > 0.0f && disparityStep > 0.0f) {
    const float step = z * z * disparityStep / (intrinsics.fx * baseline);
    variance += step * step / 12.0f;
  }
  return std::sqrt(variance);
}

float SensorProfile::expectedWallDropout() const {
  return 1.0f - (1.0f - dropoutFraction) * (1.0f - holeFraction);
}

const std::vector<SensorProfile>& sensorProfiles() {
  static const std::vector<SensorProfile> kProfiles = makeProfiles();
  return kProfiles;
}

Result<SensorProfile> findSensorProfile(std::string_view name) {
  std::string names;
  for (const SensorProfile& p : sensorProfiles()) {
    if (p.name == name) return p;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  return Error{"unknown sensor profile '" + std::string(name) + "' (known: " + names + ")"};
}

}  // namespace dynahand::synth
