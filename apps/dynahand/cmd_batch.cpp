// dynahand batch: tracking and synthetic data at dataset scale on Dask (docs/python.md). The
// work is the pure-Python module dynahand_batch beside the `dynahand` Python module; this
// command runs it with Debian's /usr/bin/python3 (or $DYNAHAND_PYTHON), its folder on
// PYTHONPATH and this executable in $DYNAHAND_EXE, passing every argument through.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "dynahand/command.h"

namespace dynahand::cli {
namespace {

namespace fs = std::filesystem;

// Runs dynahand_batch.main(arguments); a missing module is a one-line error with exit 2
// (dynahand_batch itself says so, exit 2, when dynahand, dask or distributed is missing).
constexpr const char* kBatchBootstrap =
    "import sys\n"
    "try:\n"
    "    import dynahand_batch\n"
    "except ImportError as e:\n"
    "    sys.stderr.write('dynahand batch: the Python module dynahand_batch is missing (%s); '\n"
    "                     'build or install the Python module (docs/python.md)\\n' % e)\n"
    "    sys.exit(2)\n"
    "sys.exit(dynahand_batch.main(sys.argv[1:]))\n";

bool isExecutable(const std::string& path) {
  return ::access(path.c_str(), X_OK) == 0;
}

// $DYNAHAND_PYTHON, else Debian's /usr/bin/python3 (the interpreter the module is built for),
// else python3 on PATH; empty when none is found.
std::string findPython() {
  if (const char* env = std::getenv("DYNAHAND_PYTHON"); env != nullptr && *env != '\0')
    return isExecutable(env) ? std::string(env) : std::string();
  if (isExecutable("/usr/bin/python3")) return "/usr/bin/python3";
  if (const char* path = std::getenv("PATH"); path != nullptr) {
    std::string dirs(path);
    std::size_t start = 0;
    while (start <= dirs.size()) {
      const std::size_t end = std::min(dirs.find(':', start), dirs.size());
      const std::string candidate = dirs.substr(start, end - start) + "/python3";
      if (end > start && isExecutable(candidate)) return candidate;
      start = end + 1;
    }
  }
  return {};
}

// The folder holding dynahand_batch.py: $DYNAHAND_PYTHONPATH, the build tree's python/ beside
// apps/, or lib/python3.X/dist-packages under the install prefix; empty: rely on sys.path.
std::string findModuleFolder(const fs::path& exe) {
  if (const char* env = std::getenv("DYNAHAND_PYTHONPATH"); env != nullptr && *env != '\0')
    return env;
  std::error_code ec;
  const fs::path bin = exe.parent_path();
  const fs::path build = bin.parent_path() / "python";
  if (fs::exists(build / "dynahand_batch.py", ec)) return build.string();
  const fs::path lib = bin.parent_path() / "lib";
  if (fs::is_directory(lib, ec)) {
    for (const auto& entry : fs::directory_iterator(lib, ec)) {
      const fs::path candidate = entry.path() / "dist-packages";
      if (entry.path().filename().string().rfind("python3", 0) == 0 &&
          fs::exists(candidate / "dynahand_batch.py", ec))
        return candidate.string();
    }
  }
  return {};
}

int runBatch(const std::vector<std::string>& args) {
  if (args.empty())
    throw UsageError(
        "give 'track SEQUENCE... --out DIR' or 'synth --count N --out DIR' "
        "(see 'dynahand batch --help')");
  const std::string python = findPython();
  if (python.empty())
    throw UsageError(
        "Python 3 not found (/usr/bin/python3, $DYNAHAND_PYTHON or python3 on "
        "PATH); apt-get install python3 python3-dask python3-distributed");
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const std::string folder = ec ? std::string() : findModuleFolder(exe);
  if (!folder.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string value =
        old != nullptr && *old != '\0' ? folder + ":" + std::string(old) : folder;
    ::setenv("PYTHONPATH", value.c_str(), 1);
  }
  if (!ec) ::setenv("DYNAHAND_EXE", exe.c_str(), 0);  // dynahand synth for the shards

  std::vector<std::string> argvStrings{python, "-c", kBatchBootstrap};
  argvStrings.insert(argvStrings.end(), args.begin(), args.end());
  std::vector<char*> argvPointers;
  for (auto& s : argvStrings) argvPointers.push_back(s.data());
  argvPointers.push_back(nullptr);
  std::fflush(nullptr);
  ::execv(python.c_str(), argvPointers.data());
  throw UsageError("cannot run " + python + ": " + std::strerror(errno));
}

const CommandRegistration kBatchCommand{Command{
    "batch", "track sequences or write synthetic shards as Dask tasks (Python, docs/python.md)",
    [](CLI::App& sub) -> std::function<int()> {
      // Everything after `batch` goes to the Python module (its own --help per action).
      sub.prefix_command();
      sub.footer(
          "Actions (each has --help):\n"
          "  track SEQUENCE_OR_GLOB... --out DIR [--scheduler tcp://HOST:PORT] [--workers N]\n"
          "        [--init auto|gt] [--no-detector]   OUT/NAME.jsonl per sequence\n"
          "  synth --count N --out DIR [--motion M[,M...]] [--frames F] [--profile P]\n"
          "        [--seed S] [--format sequence|npz] [--scheduler ...] [--workers N]\n"
          "One Dask task per sequence or shard on a local cluster (default) or a running\n"
          "scheduler; finished outputs are skipped on a rerun; exit 1 when a task failed.\n"
          "Needs /usr/bin/python3 with the dynahand module, python3-dask and\n"
          "python3-distributed.\n\n"
          "Examples:\n"
          "  dynahand batch track 'clips/*/' --out poses/ --workers 2\n"
          "  dynahand batch synth --count 8 --frames 150 --out synth/\n"
          "  dynahand batch track 'clips/*/' --out poses/ --scheduler tcp://10.0.0.1:8786");
      return [&sub] { return runBatch(sub.remaining()); };
    }}};

}  // namespace
}  // namespace dynahand::cli
