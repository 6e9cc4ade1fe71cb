#include "sensor/png_depth.h"

#include <cstdio>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <cassert>
#include <cstring>
#include <fstream>
#include <system_error>

#include "sensor/reader_error.h"

namespace dynahand::sensor {
namespace {

constexpr std::array<std::uint8_t, 8> kPngSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
// Depth cameras top out around 1-2 megapixels; the cap keeps a corrupt header from
// asking for gigabytes.
constexpr std::int64_t kMaxPixels = 4096 * 4096;

std::uint32_t readBigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         p[3];
}

using detail::fail;

// Decodes with OpenCV after the header was checked; returns the raw Mat.
Result<cv::Mat> decode(std::span<const std::uint8_t> bytes, const std::string& name) {
  cv::Mat image;
  try {
    // cv::Mat over const data: imdecode only reads it.
    const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8UC1,
                         const_cast<std::uint8_t*>(bytes.data()));  // NOLINT
    image = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return fail(name, std::string("PNG could not be decoded (") + e.what() + ")");
  }
  if (image.empty())
    return fail(name, "PNG data is truncated or corrupt (the image could not be decoded)");
  return image;
}

Status checkSize(const PngHeader& header, const std::string& name, int expectWidth,
                 int expectHeight) {
  if (expectWidth > 0 && expectHeight > 0 &&
      (header.width != expectWidth || header.height != expectHeight)) {
    return fail(name, "image is " + std::to_string(header.width) + " x " +
                          std::to_string(header.height) + " but the camera description says " +
                          std::to_string(expectWidth) + " x " + std::to_string(expectHeight));
  }
  return Ok{};
}

}  // namespace

int PngHeader::channels() const {
  switch (colorType) {
    case 0:
      return 1;
    case 2:
      return 3;
    case 3:
      return 1;
    case 4:
      return 2;
    case 6:
      return 4;
    default:
      return 0;
  }
}

std::string PngHeader::describe() const {
  const char* kind = "unknown colour type";
  switch (colorType) {
    case 0:
      kind = "grey";
      break;
    case 2:
      kind = "RGB";
      break;
    case 3:
      kind = "palette";
      break;
    case 4:
      kind = "grey+alpha";
      break;
    case 6:
      kind = "RGBA";
      break;
    default:
      break;
  }
  return std::to_string(bitDepth) + "-bit " + kind;
}

Result<PngHeader> inspectPng(std::span<const std::uint8_t> bytes, const std::string& name) {
  if (bytes.empty()) return fail(name, "file is empty (expected a PNG image)");
  if (bytes.size() < kPngSignature.size() ||
      std::memcmp(bytes.data(), kPngSignature.data(), kPngSignature.size()) != 0) {
    return fail(name, "not a PNG file (bad signature)");
  }
  // Signature, then the IHDR chunk: length(4) "IHDR"(4) width(4) height(4) depth colour ...
  constexpr std::size_t kIhdrEnd = 8 + 8 + 13;
  if (bytes.size() < kIhdrEnd) return fail(name, "PNG is truncated (header incomplete)");
  const std::uint8_t* ihdr = bytes.data() + 8;
  if (readBigEndian32(ihdr) != 13 || std::memcmp(ihdr + 4, "IHDR", 4) != 0) {
    return fail(name, "PNG is corrupt (first chunk is not a valid IHDR)");
  }
  const std::uint32_t width = readBigEndian32(ihdr + 8);
  const std::uint32_t height = readBigEndian32(ihdr + 12);
  PngHeader header;
  header.bitDepth = ihdr[16];
  header.colorType = ihdr[17];
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu) {
    return fail(name, "PNG header has an invalid size " + std::to_string(width) + " x " +
                          std::to_string(height));
  }
  if (static_cast<std::int64_t>(width) * height > kMaxPixels) {
    return fail(name, "PNG is " + std::to_string(width) + " x " + std::to_string(height) +
                          ", larger than the 4096 x 4096 pixels a depth image may have");
  }
  header.width = static_cast<int>(width);
  header.height = static_cast<int>(height);
  if (header.channels() == 0) {
    return fail(name, "PNG header has an invalid colour type " + std::to_string(header.colorType));
  }
  return header;
}

Result<DepthFrame> decodeDepthPng16(std::span<const std::uint8_t> bytes, const std::string& name,
                                    int expectWidth, int expectHeight) {
  auto header = inspectPng(bytes, name);
  if (!header) return header.error();
  if (header->bitDepth != 16 || header->colorType != 0) {
    return fail(name, "PNG is " + header->describe() +
                          "; a depth image must be 16-bit grey (single channel)");
  }
  if (auto size = checkSize(*header, name, expectWidth, expectHeight); !size) return size.error();
  auto image = decode(bytes, name);
  if (!image) return image.error();
  if (image->type() != CV_16UC1 || image->cols != header->width || image->rows != header->height) {
    return fail(name, "PNG decoded to an unexpected layout (expected 16-bit single channel)");
  }
  DepthFrame frame(header->width, header->height, 0.001f);
  for (int v = 0; v < frame.height; ++v) {
    std::memcpy(&frame.at(0, v), image->ptr<std::uint16_t>(v), sizeof(std::uint16_t) * frame.width);
  }
  return frame;
}

Result<DepthFrame> decodeNyuPng(std::span<const std::uint8_t> bytes, const std::string& name,
                                int expectWidth, int expectHeight) {
  auto header = inspectPng(bytes, name);
  if (!header) return header.error();
  if (header->bitDepth != 8 || (header->colorType != 2 && header->colorType != 6)) {
    return fail(name,
                "PNG is " + header->describe() + "; an NYU packed depth image must be 8-bit RGB");
  }
  if (auto size = checkSize(*header, name, expectWidth, expectHeight); !size) return size.error();
  auto image = decode(bytes, name);
  if (!image) return image.error();
  const int channels = image->channels();
  if (image->depth() != CV_8U || (channels != 3 && channels != 4) || image->cols != header->width ||
      image->rows != header->height) {
    return fail(name, "PNG decoded to an unexpected layout (expected 8-bit RGB)");
  }
  DepthFrame frame(header->width, header->height, 0.001f);
  for (int v = 0; v < frame.height; ++v) {
    const std::uint8_t* row = image->ptr<std::uint8_t>(v);
    for (int u = 0; u < frame.width; ++u) {
      // OpenCV stores B, G, R: depth mm = G * 256 + B.
      const std::uint8_t* px = row + static_cast<std::ptrdiff_t>(u) * channels;
      frame.at(u, v) = static_cast<std::uint16_t>(px[1] * 256 + px[0]);
    }
  }
  return frame;
}

Result<std::vector<std::uint8_t>> encodeDepthPng16(const DepthFrame& frame) {
  assert(frame.consistent() && "encodeDepthPng16: frame buffer does not match its size");
  if (frame.width <= 0 || frame.height <= 0)
    return Error{"cannot encode an empty depth frame as PNG"};
  const cv::Mat image(
      frame.height, frame.width, CV_16UC1,
      const_cast<std::uint16_t*>(frame.depth.data()));  // NOLINT: imencode only reads
  std::vector<std::uint8_t> bytes;
  try {
    // Fast zlib level: depth recordings are written live.
    if (!cv::imencode(".png", image, bytes, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
      return Error{"PNG encoder failed"};
    }
  } catch (const cv::Exception& e) {
    return Error{std::string("PNG encoder failed: ") + e.what()};
  }
  return bytes;
}

Result<std::vector<std::uint8_t>> readFileBytes(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return fail(file.string(), "file not found");
  if (std::filesystem::is_directory(file, ec))
    return fail(file.string(), "is a directory, expected a file");
  std::ifstream in(file, std::ios::binary);
  if (!in) return fail(file.string(), "cannot open for reading");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) return fail(file.string(), "cannot determine the file size");
  in.seekg(0, std::ios::beg);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size)) {  // NOLINT
    return fail(file.string(), "read error");
  }
  return bytes;
}

Status writeFileBytes(const std::filesystem::path& file, std::span<const std::uint8_t> bytes) {
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return fail(file.string(), "cannot open for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));  // NOLINT
    out.flush();
    if (!out) return fail(file.string(), "write error (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) return fail(file.string(), "cannot rename the temporary file: " + ec.message());
  return Ok{};
}

std::string framePngName(int index) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", index);
  return name;
}

}  // namespace dynahand::sensor
