/// @file
/// Interop with the original authors' open-source release (IntelRealSense/hand_tracking_samples,
/// Apache-2.0): their hand model (model_hand.json) and pose files (.pose). Formats are
/// described in docs/formats/model.md ("Importing the original authors' model") and
/// docs/formats/pose.md.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "dynahand/model_pose.h"

namespace dynahand::model {

/// How importIntelModel builds the bodies.
struct IntelImportOptions {
  /// Catmull-Clark subdivision levels applied to each control cage before taking the hull;
  /// their tracker used 2. The centres of mass (and so .pose conversion) depend on it.
  int subdivisions = 2;
};

/// The original authors' hand model, imported.
struct IntelModel {
  ArticulatedModel model;  ///< 17 bodies named like makeDefaultHand's, same order
  ModelPose restPose;      ///< the file's "pose", body frames
};

/// Reads their model_hand.json: the model (body pairs that overlap in the rest pose never
/// collide) and its rest pose. Errors name the file.
Result<IntelModel> importIntelModel(const std::filesystem::path& path,
                                    const IntelImportOptions& options = {});

/// .pose: one frame per line, per body px py pz qx qy qz qw of the body's centre-of-mass
/// frame (m, camera frame). Converted to and from body frames with the model's hull centroids.
Result<std::vector<ModelPose>> loadIntelPoses(const std::filesystem::path& path,
                                              const ArticulatedModel& model);
/// Writes poses of `model` as a .pose file, one line per pose (intelPoseLine).
Status saveIntelPoses(const std::filesystem::path& path, const ArticulatedModel& model,
                      std::span<const ModelPose> poses);

/// One .pose line's numbers (7 per body) <-> body-frame poses.
Result<ModelPose> intelPoseFromNumbers(std::span<const float> numbers,
                                       const ArticulatedModel& model);
/// The inverse of intelPoseFromNumbers: 7 numbers per body.
std::vector<float> intelPoseToNumbers(const ModelPose& pose, const ArticulatedModel& model);
/// One .pose line (no newline), as saveIntelPoses writes it; for writers that stream frames.
std::string intelPoseLine(const ModelPose& pose, const ArticulatedModel& model);

/// A polygon mesh: vertices and faces as lists of vertex indices.
struct PolygonMesh {
  std::vector<Vec3> vertices;           ///< vertex positions
  std::vector<std::vector<int>> faces;  ///< vertex indices of each face, in order
};
/// Catmull-Clark subdivision of a closed polygon mesh (used on the control cages); returns the
/// subdivided vertices and quad faces.
PolygonMesh catmullClark(const PolygonMesh& mesh);

}  // namespace dynahand::model
