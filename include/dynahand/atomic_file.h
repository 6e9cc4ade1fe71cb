/// @file
/// Writing output files whole or not at all (docs/reliability.md, "How outputs are written"):
/// the bytes go to a temporary name in the same folder (PATH.part), which is renamed to PATH
/// only once everything was written and the file closed without error. A run that fails or dies
/// part-way never leaves a partial file under the final name.
#pragma once

#include <filesystem>
#include <fstream>
#include <string_view>

#include "dynahand/core.h"

namespace dynahand {

/// PATH.part, or with keepExtension NAME.part.EXT (for writers that pick the format from the
/// extension, such as a video writer).
std::filesystem::path partPath(const std::filesystem::path& path, bool keepExtension = false);

/// Renames a finished `part` to `path` (replacing it); an Error naming both on failure.
Status commitPart(const std::filesystem::path& part, const std::filesystem::path& path);

/// Writes `contents` as PATH, atomically: PATH.part, checked on close, renamed. The folder is
/// created if missing. On failure PATH is untouched, PATH.part removed, and the Error names PATH.
Status writeFileAtomically(const std::filesystem::path& path, std::string_view contents);

/// Streams an output to PATH.part; commit() closes it, checks that every byte was written and
/// renames it to PATH. Not committed (an error, an interrupted run): PATH.part keeps what was
/// written so far and PATH is untouched.
class AtomicFileWriter {
 public:
  /// Creates the folder if missing and opens PATH.part; an Error naming PATH.part if it cannot.
  Status open(const std::filesystem::path& path);
  std::ostream& stream() { return out_; }  ///< the stream writing PATH.part
  /// Flushes; an Error naming PATH.part if a write failed (e.g. the disk is full).
  Status flush();
  Status commit();                                             ///< once; later calls: Ok
  const std::filesystem::path& path() const { return path_; }  ///< PATH
  const std::filesystem::path& part() const { return part_; }  ///< PATH.part

 private:
  std::filesystem::path path_;
  std::filesystem::path part_;
  std::ofstream out_;
};

}  // namespace dynahand
