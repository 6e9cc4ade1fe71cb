#include "dynahand/atomic_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace dynahand {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

fs::path freshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynahand_atomic_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(AtomicFile, PartPathKeepsTheExtensionWhenAsked) {
  EXPECT_EQ(partPath("a/b.md"), fs::path("a/b.md.part"));
  EXPECT_EQ(partPath("a/v.mp4", true), fs::path("a/v.part.mp4"));
  EXPECT_EQ(partPath("a/noext", true), fs::path("a/noext.part"));
}

TEST(AtomicFile, WritesWholeFileAndCreatesTheFolder) {
  const fs::path dir = freshDir("whole");
  const fs::path file = dir / "sub" / "x.md";
  ASSERT_TRUE(writeFileAtomically(file, "hello\n").ok());
  EXPECT_EQ(slurp(file), "hello\n");
  EXPECT_FALSE(fs::exists(partPath(file)));
  ASSERT_TRUE(writeFileAtomically(file, "again\n").ok());  // replaces
  EXPECT_EQ(slurp(file), "again\n");
  fs::remove_all(dir);
}

TEST(AtomicFile, FailureLeavesTheOldFileAndNamesThePath) {
  const fs::path dir = freshDir("fail");
  std::ofstream(dir / "afile") << "x";
  const fs::path below = dir / "afile" / "x.md";  // below a regular file: cannot be created
  const Status s = writeFileAtomically(below, "data");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(below.string()), std::string::npos) << s.message();

  // The final name is a folder: the rename fails, the folder stays, no .part is left.
  fs::create_directories(dir / "d.md");
  const Status r = writeFileAtomically(dir / "d.md", "data");
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(fs::is_directory(dir / "d.md"));
  EXPECT_FALSE(fs::exists(partPath(dir / "d.md")));
  fs::remove_all(dir);
}

TEST(AtomicFile, FullDiskIsAnErrorAndLeavesNoFinalFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  // The temporary name is a link to /dev/full: every write fails as on a full disk.
  const fs::path dir = freshDir("full");
  const fs::path file = dir / "x.md";
  fs::create_symlink("/dev/full", partPath(file));
  const Status s = writeFileAtomically(file, std::string(100000, 'x'));
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(file.string()), std::string::npos) << s.message();
  EXPECT_FALSE(fs::exists(file));

  fs::create_symlink("/dev/full", partPath(dir / "y.jsonl"));
  AtomicFileWriter w;
  ASSERT_TRUE(w.open(dir / "y.jsonl").ok());
  w.stream() << std::string(100000, 'y');
  EXPECT_FALSE(w.commit().ok());
  EXPECT_FALSE(fs::exists(dir / "y.jsonl"));
  fs::remove_all(dir);
}

TEST(AtomicFile, StreamingWriterRenamesOnlyOnCommit) {
  const fs::path dir = freshDir("stream");
  const fs::path file = dir / "out.jsonl";
  AtomicFileWriter w;
  ASSERT_TRUE(w.open(file).ok());
  w.stream() << "1\n";
  ASSERT_TRUE(w.flush().ok());
  EXPECT_FALSE(fs::exists(file));
  EXPECT_EQ(slurp(partPath(file)), "1\n");
  ASSERT_TRUE(w.commit().ok());
  EXPECT_EQ(slurp(file), "1\n");
  EXPECT_FALSE(fs::exists(partPath(file)));
  EXPECT_TRUE(w.commit().ok());  // once

  AtomicFileWriter bad;  // below a regular file
  EXPECT_FALSE(bad.open(file / "below").ok());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dynahand
