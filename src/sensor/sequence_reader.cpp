// SequenceReader: format detection and random access over a FrameSource.
#include <algorithm>
#include <cctype>

#include "dynahand/sequence.h"
#include "sensor/frame_source.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

Result<sensor::OpenedSource> openDetected(const fs::path& path,
                                          const SequenceOpenOptions& options) {
  std::error_code ec;
  const std::string ext = lowerExtension(path);
  if (!fs::exists(path, ec)) {
    fs::path rs = path;
    rs += ".rs";
    if (ext.empty() && fs::exists(rs, ec)) {
      fs::path json = path;
      json += ".json";
      return sensor::openIntelRaw(rs, json);
    }
    return Error{path.string() + ": not found"};
  }
  if (fs::is_directory(path, ec)) {
    if (fs::exists(path / "camera.json", ec)) return sensor::openCanonical(path);
    return sensor::openPngFolder(path, options);
  }
  if (ext == ".rs") return sensor::openIntelRaw(path, fs::path(path).replace_extension(".json"));
  if (ext == ".json") {
    if (path.filename() == "camera.json") return sensor::openCanonical(path.parent_path());
    const fs::path rs = fs::path(path).replace_extension(".rs");
    if (fs::exists(rs, ec)) return sensor::openIntelRaw(rs, path);
    return Error{path.string() + ": a .json camera file needs its depth recording " +
                 rs.filename().string() + " beside it"};
  }
  if (ext == ".oni") return sensor::openOni(path);
  if (ext == ".png") {
    return Error{path.string() + ": a single PNG is not a sequence; open the folder that holds it"};
  }
  return Error{
      path.string() +
      ": unrecognised recording (expected a canonical sequence folder, a PNG folder, NAME.rs + "
      "NAME.json, or an .oni file)"};
}

}  // namespace

SequenceReader::SequenceReader(SequenceReader&&) noexcept = default;
SequenceReader& SequenceReader::operator=(SequenceReader&&) noexcept = default;
SequenceReader::~SequenceReader() = default;

Result<SequenceReader> SequenceReader::open(const fs::path& path) {
  return open(path, SequenceOpenOptions{});
}

Result<SequenceReader> SequenceReader::open(const fs::path& path,
                                            const SequenceOpenOptions& options) {
  auto opened = openDetected(path, options);
  if (!opened) return opened.error();
  SequenceReader reader;
  reader.info_ = std::move(opened->info);
  reader.source_ = std::move(opened->source);
  reader.groundTruth_ = std::move(opened->groundTruth);
  return reader;
}

Result<DepthFrame> SequenceReader::frame(int index) const {
  if (index < 0 || index >= info_.frameCount) {
    return Error{info_.path.string() + ": frame " + std::to_string(index) + " is out of range (" +
                 std::to_string(info_.frameCount) + " frames)"};
  }
  return source_->read(index);
}

std::optional<Keypoints21> SequenceReader::groundTruth(int index) const {
  if (index < 0 || static_cast<std::size_t>(index) >= groundTruth_.size()) return std::nullopt;
  return groundTruth_[static_cast<std::size_t>(index)];
}

std::vector<std::string> sequenceFormats() {
  std::vector<std::string> formats{"canonical", "intel-rs", "nyu-png", "png16"};
  if (sensor::oniSupported()) formats.emplace_back("oni");
  return formats;
}

}  // namespace dynahand
