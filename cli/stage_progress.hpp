// Progress of a command that runs in a few long stages, on stderr: the
// current stage and the time so far, refreshed twice a second, on a terminal
// only and once the command has taken a second (`truecut part: writing the
// files (3 s)`; $TRUECUT_PROGRESS_AFTER_S sets that second). Ends its line
// when destroyed.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace truecut::cli {

class StageProgress {
 public:
  // `enabled` false: shows nothing (not a terminal, or --quiet).
  StageProgress(std::string command, bool enabled);
  ~StageProgress();
  StageProgress(const StageProgress&) = delete;
  StageProgress& operator=(const StageProgress&) = delete;

  void stage(std::string what);
  // Writes `line` (ending in a newline) to stderr below the progress line,
  // which is drawn again on the next line.
  void message(const std::string& line);

 private:
  void run();
  void draw_if_due();  // with mutex_ held
  std::string command_;
  std::chrono::steady_clock::time_point start_;
  double after_s_;
  bool enabled_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::string stage_;
  bool stop_ = false;
  bool shown_ = false;
  std::thread thread_;
};

}  // namespace truecut::cli
