// Progress reporting for long jobs: a redrawn bar with rate and ETA on a terminal,
// plain lines every 10% otherwise (logs, CI). And Ctrl-C handling: the first Ctrl-C
// asks the job to stop cleanly (keeping what it wrote), a second one kills it.
#pragma once

#include <chrono>
#include <string>

namespace dynahand::cli {

class Progress {
 public:
  // total <= 0: unknown length (no bar, no ETA).
  Progress(std::string label, int total, std::string unit = "frames");
  void update(int done, const std::string& extra = {});
  void finish(const std::string& extra = {});

 private:
  std::string label_, unit_;
  int total_;
  bool tty_;
  int lastDecile_ = -1;
  std::chrono::steady_clock::time_point start_, lastDraw_;
};

// Installs the SIGINT handler (idempotent).
void installInterruptHandler();
// True once Ctrl-C was pressed.
bool interrupted();

}  // namespace dynahand::cli
