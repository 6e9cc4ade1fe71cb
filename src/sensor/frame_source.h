// The per-format back end of SequenceReader: each format opens into a FrameSource
// that knows its SequenceInfo and decodes frame i on demand.
#pragma once

#include <filesystem>
#include <memory>

#include "dynahand/sequence.h"

namespace dynahand::sensor {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // Frame `index` (already range-checked) with depthScale and timestamp set.
  virtual Result<DepthFrame> read(int index) const = 0;
};

struct OpenedSource {
  SequenceInfo info;
  std::unique_ptr<FrameSource> source;
  std::vector<std::optional<Keypoints21>> groundTruth;  // empty, or (info.frameCount)
};

// One opener per format; each returns an Error naming the file and the problem.
Result<OpenedSource> openCanonical(const std::filesystem::path& dir);
Result<OpenedSource> openIntelRaw(const std::filesystem::path& rsFile,
                                  const std::filesystem::path& jsonFile);
Result<OpenedSource> openPngFolder(const std::filesystem::path& dir,
                                   const SequenceOpenOptions& options);
bool oniSupported();
Result<OpenedSource> openOni(const std::filesystem::path& file);

// Reads groundtruth.jsonl into one entry per frame (missing lines = nullopt).
Result<std::vector<std::optional<Keypoints21>>> readGroundTruthFile(
    const std::filesystem::path& file, int frameCount);

// Frame size in bytes of a raw .rs recording and the error for a bad file size.
Status checkRawSize(std::uintmax_t fileBytes, const Intrinsics& intrinsics,
                    const std::string& name);

}  // namespace dynahand::sensor
