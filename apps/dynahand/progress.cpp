#include "dynahand/progress.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>

namespace dynahand::cli {

namespace {
std::atomic<bool> gInterrupted{false};

void onInterrupt(int) {
  if (gInterrupted.exchange(true)) std::_Exit(130);  // second Ctrl-C: stop now
}

std::string clock(double seconds) {
  const int s = static_cast<int>(seconds + 0.5);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d:%02d", s / 60, s % 60);
  return buf;
}
}  // namespace

void installInterruptHandler() {
  static bool installed = false;
  if (installed) return;
  installed = true;
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
}

bool interrupted() {
  return gInterrupted.load();
}

Progress::Progress(std::string label, int total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      tty_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      lastDraw_(start_) {}

void Progress::update(int done, const std::string& extra) {
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  if (tty_) {
    if (now - lastDraw_ < std::chrono::milliseconds(100) && done != total_) return;
    lastDraw_ = now;
    std::string bar;
    if (total_ > 0) {
      const int width = 30;
      const int filled = static_cast<int>(static_cast<double>(width) * done / total_);
      bar = "[" + std::string(static_cast<std::size_t>(filled), '#') +
            std::string(static_cast<std::size_t>(width - filled), ' ') + "] ";
    }
    const std::string eta = (total_ > 0 && rate > 0) ? " ETA " + clock((total_ - done) / rate) : "";
    std::fprintf(stderr, "\r\033[K%s %s%d/%d %s  %.1f %s/s%s %s", label_.c_str(), bar.c_str(), done,
                 total_ > 0 ? total_ : done, unit_.c_str(), rate, unit_.c_str(), eta.c_str(),
                 extra.c_str());
    std::fflush(stderr);
  } else if (total_ > 0) {
    const int decile = static_cast<int>(10.0 * done / total_);
    if (decile != lastDecile_) {
      lastDecile_ = decile;
      std::fprintf(stderr, "%s %d/%d %s (%d%%) %.1f %s/s %s\n", label_.c_str(), done, total_,
                   unit_.c_str(), 10 * decile, rate, unit_.c_str(), extra.c_str());
    }
  }
}

void Progress::finish(const std::string& extra) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (tty_) std::fprintf(stderr, "\r\033[K");
  std::fprintf(stderr, "%s done in %s %s\n", label_.c_str(), clock(elapsed).c_str(), extra.c_str());
}

}  // namespace dynahand::cli
