#include "dynahand/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

namespace dynahand {

namespace fs = std::filesystem;

fs::path partPath(const fs::path& path, bool keepExtension) {
  if (keepExtension && path.has_extension()) {
    fs::path part = path;
    part.replace_extension(".part" + path.extension().string());
    return part;
  }
  fs::path part = path;
  part += ".part";
  return part;
}

Status commitPart(const fs::path& part, const fs::path& path) {
  std::error_code ec;
  fs::rename(part, path, ec);
  if (ec) return Error{part.string() + ": cannot rename to " + path.string() + ": " + ec.message()};
  return Ok{};
}

namespace {
void createParent(const fs::path& path) {
  if (!path.has_parent_path()) return;
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);  // a failure shows when opening the file
}
}  // namespace

Status writeFileAtomically(const fs::path& path, std::string_view contents) {
  createParent(path);
  const fs::path part = partPath(path);
  std::FILE* f = std::fopen(part.c_str(), "wb");
  if (f == nullptr) return Error{path.string() + ": cannot write (" + std::strerror(errno) + ")"};
  bool written = std::fwrite(contents.data(), 1, contents.size(), f) == contents.size();
  int err = written ? 0 : errno;
  if (std::fflush(f) != 0 && written) {
    written = false;
    err = errno;
  }
  if (std::fclose(f) != 0 && written) {
    written = false;
    err = errno;
  }
  std::error_code ec;
  if (!written) {
    fs::remove(part, ec);
    return Error{path.string() + ": write failed (" +
                 (err != 0 ? std::string(std::strerror(err)) : std::string("disk full?")) + ")"};
  }
  fs::rename(part, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(part, ignored);
    return Error{path.string() + ": cannot write (rename from " + part.filename().string() + ": " +
                 ec.message() + ")"};
  }
  return Ok{};
}

Status AtomicFileWriter::open(const fs::path& path) {
  path_ = path;
  part_ = partPath(path);
  createParent(path);
  out_.open(part_, std::ios::out | std::ios::trunc | std::ios::binary);
  if (!out_) return Error{part_.string() + ": cannot write"};
  return Ok{};
}

Status AtomicFileWriter::flush() {
  if (!out_.is_open()) return Ok{};
  out_.flush();
  if (!out_) return Error{part_.string() + ": write failed (disk full?)"};
  return Ok{};
}

Status AtomicFileWriter::commit() {
  if (!out_.is_open()) return Ok{};  // committed already
  out_.flush();
  const bool flushed = static_cast<bool>(out_);
  out_.close();
  if (!flushed || out_.fail())
    return Error{part_.string() + ": could not be written in full (disk full?)"};
  return commitPart(part_, path_);
}

}  // namespace dynahand
