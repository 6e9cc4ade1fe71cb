// Recordings dynahand reads but does not write: PNG folders (plain 16-bit and
// NYU packed) and the original authors' raw NAME.rs + NAME.json layout.
#include <algorithm>
#include <bit>
#include <cctype>
#include <fstream>
#include <limits>

#include "sensor/camera_json.h"
#include "sensor/frame_source.h"
#include "sensor/png_depth.h"

namespace dynahand::sensor {
namespace {

namespace fs = std::filesystem;

// NYU hand pose dataset (Kinect v1 depth camera, 640 x 480).
constexpr Intrinsics kNyuIntrinsics{640, 480, 588.036865f, 587.075073f, 320.0f, 240.0f};

// "frame2.png" < "frame10.png": digit runs compare by value, then by text.
bool naturalLess(const std::string& a, const std::string& b) {
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool db = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (da && db) {
      std::size_t ie = i;
      std::size_t je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string_view na(a.data() + i, ie - i);
      std::string_view nb(b.data() + j, je - j);
      while (na.size() > 1 && na.front() == '0') na.remove_prefix(1);
      while (nb.size() > 1 && nb.front() == '0') nb.remove_prefix(1);
      if (na.size() != nb.size()) return na.size() < nb.size();
      if (na != nb) return na < nb;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if ((a.size() - i) != (b.size() - j)) return (a.size() - i) < (b.size() - j);
  return a < b;  // equal by value ("01" vs "1"): fall back to the text
}

class PngFolderSource final : public FrameSource {
 public:
  PngFolderSource(std::vector<fs::path> files, const SequenceInfo& info, bool nyu)
      : files_(std::move(files)), info_(info), nyu_(nyu) {}

  Result<DepthFrame> read(int index) const override {
    const fs::path& file = files_[static_cast<std::size_t>(index)];
    auto bytes = readFileBytes(file);
    if (!bytes) return bytes.error();
    const int w = info_.intrinsics.width;
    const int h = info_.intrinsics.height;
    auto frame = nyu_ ? decodeNyuPng(*bytes, file.string(), w, h)
                      : decodeDepthPng16(*bytes, file.string(), w, h);
    if (!frame) return frame.error();
    frame->depthScale = info_.depthScale;
    frame->timestamp = index / static_cast<double>(info_.framesPerSecond);
    return frame;
  }

 private:
  std::vector<fs::path> files_;
  SequenceInfo info_;
  bool nyu_;
};

class IntelRawSource final : public FrameSource {
 public:
  IntelRawSource(fs::path file, const SequenceInfo& info) : file_(std::move(file)), info_(info) {}

  Result<DepthFrame> read(int index) const override {
    DepthFrame frame(info_.intrinsics.width, info_.intrinsics.height, info_.depthScale);
    const std::streamsize bytes =
        static_cast<std::streamsize>(frame.depth.size() * sizeof(std::uint16_t));
    std::ifstream in(file_, std::ios::binary);
    if (!in) return Error{file_.string() + ": cannot open for reading"};
    in.seekg(static_cast<std::streamoff>(index) * bytes);
    if (!in.read(reinterpret_cast<char*>(frame.depth.data()), bytes)) {  // NOLINT
      return Error{file_.string() + ": frame " + std::to_string(index) +
                   " could not be read (file shrank?)"};
    }
    if constexpr (std::endian::native == std::endian::big) {
      for (std::uint16_t& d : frame.depth) d = static_cast<std::uint16_t>((d >> 8) | (d << 8));
    }
    frame.timestamp = index / static_cast<double>(info_.framesPerSecond);
    return frame;
  }

 private:
  fs::path file_;
  SequenceInfo info_;
};

}  // namespace

Status checkRawSize(std::uintmax_t fileBytes, const Intrinsics& intrinsics,
                    const std::string& name) {
  const std::uintmax_t frameBytes =
      static_cast<std::uintmax_t>(intrinsics.width) * intrinsics.height * 2;
  if (frameBytes == 0 || fileBytes % frameBytes != 0) {
    return Error{name + ": size " + std::to_string(fileBytes) +
                 " bytes is not a multiple of the frame size " + std::to_string(intrinsics.width) +
                 " x " + std::to_string(intrinsics.height) +
                 " x 2 = " + std::to_string(frameBytes) +
                 " bytes (truncated recording or wrong camera description?)"};
  }
  return Ok{};
}

Result<OpenedSource> openPngFolder(const fs::path& dir, const SequenceOpenOptions& options) {
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (ext == ".png" && entry.is_regular_file(ec))
      names.push_back(entry.path().filename().string());
  }
  if (ec) return Error{dir.string() + ": cannot list the folder: " + ec.message()};
  if (names.empty()) {
    return Error{dir.string() + ": no camera.json and no PNG files (not a sequence folder)"};
  }
  std::sort(names.begin(), names.end(), naturalLess);
  std::vector<fs::path> files;
  files.reserve(names.size());
  for (const std::string& name : names) files.push_back(dir / name);

  auto bytes = readFileBytes(files.front());
  if (!bytes) return bytes.error();
  auto header = inspectPng(*bytes, files.front().string());
  if (!header) return header.error();

  OpenedSource opened;
  opened.info.frameCount = static_cast<int>(files.size());
  opened.info.path = dir;
  bool nyu = false;
  if (header->bitDepth == 16 && header->colorType == 0) {
    if (!options.intrinsics) {
      return Error{dir.string() +
                   ": a folder of 16-bit PNGs without camera.json needs the camera intrinsics "
                   "(write a camera.json beside them, docs/formats.md; from code: "
                   "SequenceOpenOptions::intrinsics)"};
    }
    opened.info.format = "png16";
    opened.info.intrinsics = *options.intrinsics;
    opened.info.depthScale = options.depthScale.value_or(0.001f);
  } else if (header->bitDepth == 8 && (header->colorType == 2 || header->colorType == 6)) {
    nyu = true;
    opened.info.format = "nyu-png";
    opened.info.intrinsics = options.intrinsics.value_or(kNyuIntrinsics);
    opened.info.depthScale = 0.001f;  // NYU packs millimetres
  } else {
    return Error{files.front().string() + ": PNG is " + header->describe() +
                 "; a PNG folder must hold 16-bit grey depth or NYU packed 8-bit RGB images"};
  }
  if (const std::string problem = opened.info.intrinsics.problem(); !problem.empty()) {
    return Error{dir.string() + ": bad intrinsics: " + problem};
  }
  if (auto ok = checkDepthScale(static_cast<double>(opened.info.depthScale), dir.string()); !ok)
    return ok.error();
  if (header->width != opened.info.intrinsics.width ||
      header->height != opened.info.intrinsics.height) {
    return Error{files.front().string() + ": image is " + std::to_string(header->width) + " x " +
                 std::to_string(header->height) + " but the intrinsics are for " +
                 std::to_string(opened.info.intrinsics.width) + " x " +
                 std::to_string(opened.info.intrinsics.height)};
  }
  opened.source = std::make_unique<PngFolderSource>(std::move(files), opened.info, nyu);
  return opened;
}

Result<OpenedSource> openIntelRaw(const fs::path& rsFile, const fs::path& jsonFile) {
  auto text = readFileBytes(jsonFile);
  if (!text) return text.error();
  auto camera = parseIntelCameraJson(
      std::string_view(reinterpret_cast<const char*>(text->data()), text->size()),
      jsonFile.string());  // NOLINT
  if (!camera) return camera.error();
  std::error_code ec;
  if (!fs::is_regular_file(rsFile, ec)) return Error{rsFile.string() + ": not found"};
  const std::uintmax_t size = fs::file_size(rsFile, ec);
  if (ec) return Error{rsFile.string() + ": cannot read the file size: " + ec.message()};
  if (auto ok = checkRawSize(size, camera->intrinsics, rsFile.string()); !ok) return ok.error();

  const std::uintmax_t frames = size / (static_cast<std::uintmax_t>(camera->intrinsics.width) *
                                        camera->intrinsics.height * 2);
  if (frames > static_cast<std::uintmax_t>(std::numeric_limits<int>::max())) {
    return Error{rsFile.string() + ": too many frames (" + std::to_string(frames) + ")"};
  }
  OpenedSource opened;
  opened.info.intrinsics = camera->intrinsics;
  opened.info.depthScale = camera->depthScale;
  opened.info.frameCount = static_cast<int>(frames);
  opened.info.format = "intel-rs";
  opened.info.path = rsFile;
  opened.source = std::make_unique<IntelRawSource>(rsFile, opened.info);
  return opened;
}

}  // namespace dynahand::sensor
