// PNG depth images: header inspection (for precise errors before decoding),
// decoding of 16-bit and NYU packed images, encoding of 16-bit images.
// All functions take the bytes plus a name used in error messages (the file).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"

namespace dynahand::sensor {

// What the IHDR chunk says about a PNG.
struct PngHeader {
  int width = 0;      // pixels
  int height = 0;     // pixels
  int bitDepth = 0;   // bits per channel: 1, 2, 4, 8 or 16
  int colorType = 0;  // PNG colour type: 0 grey, 2 RGB, 3 palette, 4 grey+alpha, 6 RGBA
  int channels() const;
  std::string describe() const;  // "8-bit RGB", "16-bit grey", ...
};

// Reads the signature and IHDR; Error when the data is not a PNG or the header is bad.
Result<PngHeader> inspectPng(std::span<const std::uint8_t> bytes, const std::string& name);

// A 16-bit single-channel PNG as a frame (depthScale set by the caller). When
// expectWidth/expectHeight are positive, a different size is an Error.
Result<DepthFrame> decodeDepthPng16(std::span<const std::uint8_t> bytes, const std::string& name,
                                    int expectWidth = 0, int expectHeight = 0);

// NYU's packed depth: 8-bit RGB PNG with depth (mm) = G * 256 + B.
Result<DepthFrame> decodeNyuPng(std::span<const std::uint8_t> bytes, const std::string& name,
                                int expectWidth = 0, int expectHeight = 0);

// 16-bit single-channel PNG bytes of the frame's raw values.
Result<std::vector<std::uint8_t>> encodeDepthPng16(const DepthFrame& frame);

// Whole-file read with errors naming the file ("cannot open", "empty").
Result<std::vector<std::uint8_t>> readFileBytes(const std::filesystem::path& file);
// Writes to file.tmp then renames, so a crash never leaves a half-written file.
Status writeFileBytes(const std::filesystem::path& file, std::span<const std::uint8_t> bytes);

// File name of frame `index` in a canonical sequence's depth/ folder: "000042.png".
std::string framePngName(int index);

}  // namespace dynahand::sensor
