/// @file
/// Reading 21-keypoint sequences from JSON lines for evaluation. Accepts both the
/// canonical ground truth (`{"frame":i,"keypoints21":[[x,y,z]x21] | null}`) and the
/// tracker's output (`{"frame":i,"hands":[{"side":"right","tracked":true,
/// "keypoints21":[...]},...]}`); see docs/formats.md.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "dynahand/metrics.h"

namespace dynahand::eval {

/// 21-keypoint frames read by readKeypointsJsonl.
struct KeypointSequence {
  /// Indexed by frame number; frames missing from the file are nullopt.
  std::vector<std::optional<Keypoints21>> frames;
};

/// side: for tracker output, which hand to take ("right" or "left"); a hand with
/// "tracked":false counts as missing. Errors name the file, line and problem.
Result<KeypointSequence> readKeypointsJsonl(const std::filesystem::path& path,
                                            const std::string& side = "right");

}  // namespace dynahand::eval
